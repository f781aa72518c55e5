//! OpenCV's one-sided Jacobi SVD (`JacobiSVDImpl_<double>`, docs/fidelity.md
//! §VO-3.5) with its seeded null-space completion, as the five-point solver,
//! `decomposeEssentialMat` and `recoverPose`'s triangulation call it. Baseline
//! code in OpenCV: plain f64 operations, no FMA.
//!
//! recoverPose needs the null vector of a 4×4 matrix for every point and
//! rotation; with AVX2 four of those SVDs run as the lanes of f64 vectors
//! (`x86`), each lane bit for bit the scalar one.

use crate::rng::CvRng;

mod sort;
#[cfg(target_arch = "x86_64")]
mod x86;

use sort::sort_descending;

/// Result of [`svd`]: `w` descending, `u` (row-major, one column per singular value) and `vt`
/// (vrows×n, row-major).
#[derive(Clone, Debug)]
pub struct Svd {
    // recoverPose reads `u` and `vt` only; the singular values and shapes
    // are kept for the tests that check the decomposition.
    #[cfg_attr(not(test), allow(dead_code))]
    pub w: Vec<f64>,
    pub u: Vec<f64>,
    pub vt: Vec<f64>,
    #[cfg_attr(not(test), allow(dead_code))]
    pub vrows: usize,
}

/// `JacobiSVDImpl_<double>` (§VO-3.5). `at` holds `n1` working vectors of length
/// `m` (only the first `n` are data; the rest are generated when `n1 > n`),
/// `vt` receives the n×n rotation accumulator. `w` gets the n singular values.
#[inline(always)]
fn jacobi_impl(at: &mut [f64], m: usize, n: usize, n1: usize, w: &mut [f64], vt: &mut [f64]) {
    // JacobiSVD(double*) passes minval = DBL_MIN and eps = 10·DBL_EPSILON.
    let minval = f64::MIN_POSITIVE;
    let eps = f64::EPSILON * 10.0;
    let max_iter = m.max(30);

    for i in 0..n {
        let mut sd = 0.0;
        for k in 0..m {
            let t = at[i * m + k];
            sd += t * t;
        }
        w[i] = sd;
        for k in 0..n {
            vt[i * n + k] = 0.0;
        }
        vt[i * n + i] = 1.0;
    }

    for _ in 0..max_iter {
        let mut changed = false;
        for i in 0..n.saturating_sub(1) {
            for j in i + 1..n {
                let (a, b) = (w[i], w[j]);
                let mut p = 0.0;
                for k in 0..m {
                    p += at[i * m + k] * at[j * m + k];
                }
                if p.abs() <= eps * (a * b).sqrt() {
                    continue;
                }
                p *= 2.0;
                let beta = a - b;
                let gamma = super::hypot(p, beta);
                let (c, s);
                if beta < 0.0 {
                    let delta = (gamma - beta) * 0.5;
                    s = (delta / gamma).sqrt();
                    c = p / (gamma * s * 2.0);
                } else {
                    c = ((gamma + beta) / (gamma * 2.0)).sqrt();
                    s = p / (gamma * c * 2.0);
                }
                let (mut na, mut nb) = (0.0, 0.0);
                for k in 0..m {
                    let ai = at[i * m + k];
                    let aj = at[j * m + k];
                    let t0 = c * ai + s * aj;
                    let t1 = -s * ai + c * aj;
                    at[i * m + k] = t0;
                    at[j * m + k] = t1;
                    na += t0 * t0;
                    nb += t1 * t1;
                }
                w[i] = na;
                w[j] = nb;
                changed = true;
                for k in 0..n {
                    let vi = vt[i * n + k];
                    let vj = vt[j * n + k];
                    vt[i * n + k] = c * vi + s * vj;
                    vt[j * n + k] = -s * vi + c * vj;
                }
            }
        }
        if !changed {
            break;
        }
    }

    for i in 0..n {
        let mut sd = 0.0;
        for k in 0..m {
            let t = at[i * m + k];
            sd += t * t;
        }
        w[i] = sd.sqrt();
    }

    sort_descending(&mut w[..n], |i, j| {
        for k in 0..m {
            at.swap(i * m + k, j * m + k);
        }
        for k in 0..n {
            vt.swap(i * n + k, j * n + k);
        }
    });

    // Normalize the data vectors and generate the missing ones from a seeded
    // random vector orthogonalized against the previous ones (this is what
    // fixes the five-point null-space basis Ea..Ed).
    let mut rng = CvRng::new(0x1234_5678);
    for i in 0..n1 {
        let mut sd = if i < n { w[i] } else { 0.0 };
        let mut ii = 0;
        while ii < 100 && sd <= minval {
            let val0 = 1.0 / m as f64;
            for k in 0..m {
                at[i * m + k] = if rng.next_u32() & 256 != 0 { val0 } else { -val0 };
            }
            for _ in 0..2 {
                for j in 0..i {
                    let mut d = 0.0;
                    for k in 0..m {
                        d += at[i * m + k] * at[j * m + k];
                    }
                    let mut asum = 0.0;
                    for k in 0..m {
                        let t = at[i * m + k] - d * at[j * m + k];
                        at[i * m + k] = t;
                        asum += t.abs();
                    }
                    let scale = if asum > eps * 100.0 { 1.0 / asum } else { 0.0 };
                    for k in 0..m {
                        at[i * m + k] *= scale;
                    }
                }
            }
            sd = 0.0;
            for k in 0..m {
                let t = at[i * m + k];
                sd += t * t;
            }
            sd = sd.sqrt();
            ii += 1;
        }
        let s = if sd > minval { 1.0 / sd } else { 0.0 };
        for k in 0..m {
            at[i * m + k] *= s;
        }
    }
}

/// `cv::SVD::compute` for a small f64 matrix `a` (m×n, row-major), as OpenCV
/// does it without LAPACK: `full` asks for the complete U (m×m) and Vᵀ (n×n).
pub fn svd(a: &[f64], m: usize, n: usize, full: bool) -> Svd {
    debug_assert_eq!(a.len(), m * n);
    let transposed = m < n;
    // Working vectors: columns of A when m >= n, rows of A otherwise.
    let (len, count) = if transposed { (n, m) } else { (m, n) };
    let n1 = if full { len } else { count };
    let mut at = vec![0.0; n1 * len];
    for i in 0..count {
        for k in 0..len {
            at[i * len + k] = if transposed { a[i * n + k] } else { a[k * n + i] };
        }
    }
    let mut w = vec![0.0; count];
    let mut v = vec![0.0; count * count];
    jacobi_impl(&mut at, len, count, n1, &mut w, &mut v);
    if transposed {
        // Vᵀ = the working vectors as rows, U = Vᵀ_workᵀ.
        Svd { w, u: transposed_rows(&v, count, count), vt: at, vrows: n1 }
    } else {
        Svd { w, u: transposed_rows(&at, n1, len), vt: v, vrows: count }
    }
}

/// The `rows`×`len` row-major matrix `a` transposed (`len`×`rows`).
fn transposed_rows(a: &[f64], rows: usize, len: usize) -> Vec<f64> {
    let mut t = vec![0.0; rows * len];
    for i in 0..rows {
        for k in 0..len {
            t[k * rows + i] = a[i * len + k];
        }
    }
    t
}

/// The right singular vector of the smallest singular value of a 4×4 matrix
/// (last row of Vᵀ), through the same Jacobi procedure but on the stack:
/// recoverPose calls it for every point and candidate.
pub fn null_vector_4x4(a: &[[f64; 4]; 4]) -> [f64; 4] {
    // m = n = 4: the working vectors are the columns of A.
    let mut at = [0.0f64; 16];
    for i in 0..4 {
        for k in 0..4 {
            at[i * 4 + k] = a[k][i];
        }
    }
    let mut w = [0.0f64; 4];
    let mut vt = [0.0f64; 16];
    jacobi_impl(&mut at, 4, 4, 4, &mut w, &mut vt);
    [vt[12], vt[13], vt[14], vt[15]]
}

/// The null vectors (last rows of Vᵀ) of four 4×4 matrices, each exactly
/// [`null_vector_4x4`] of that matrix: recoverPose triangulates every point
/// under two rotations, and each triangulation is a 4×4 Jacobi SVD of a few
/// hundred dependent f64 operations (3.4 % of a `view_trajectory` profile,
/// `hypot` included). With AVX2 the four run as the lanes of f64 vectors.
pub fn null_vectors_4x4(ms: &[[[f64; 4]; 4]; 4]) -> [[f64; 4]; 4] {
    #[cfg(target_arch = "x86_64")]
    if crate::simd::avx2() {
        // SAFETY: the CPU has AVX2, the only feature the function enables.
        return unsafe { x86::null_vectors_avx2(ms) };
    }
    std::array::from_fn(|l| null_vector_4x4(&ms[l]))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn svd_reconstructs_and_sorts() {
        let a = [4.0, 1.0, -2.0, 1.0, 3.0, 0.5, -2.0, 0.5, 5.0];
        let s = svd(&a, 3, 3, false);
        assert!(s.w[0] >= s.w[1] && s.w[1] >= s.w[2]);
        for r in 0..3 {
            for c in 0..3 {
                let v: f64 = (0..3).map(|k| s.u[r * 3 + k] * s.w[k] * s.vt[k * 3 + c]).sum();
                assert!((v - a[r * 3 + c]).abs() < 1e-13, "{v} vs {}", a[r * 3 + c]);
            }
        }
    }

    #[test]
    fn svd_wide_full_completes_an_orthonormal_basis() {
        // 2×4: the Jacobi runs on the 2 rows, rows 2 and 3 of Vᵀ are generated.
        let a = [1.0, 2.0, 3.0, 4.0, 0.0, 1.0, 0.0, 1.0];
        let s = svd(&a, 2, 4, true);
        assert_eq!(s.vrows, 4);
        for i in 0..4 {
            for j in 0..4 {
                let d: f64 = (0..4).map(|k| s.vt[i * 4 + k] * s.vt[j * 4 + k]).sum();
                let want = if i == j { 1.0 } else { 0.0 };
                assert!((d - want).abs() < 1e-14, "({i},{j}) {d}");
            }
        }
        for i in 2..4 {
            for r in 0..2 {
                let d: f64 = (0..4).map(|k| a[r * 4 + k] * s.vt[i * 4 + k]).sum();
                assert!(d.abs() < 1e-14);
            }
        }
    }

    fn assert_close(got: &[f64], want: &[f64], tol: f64) {
        assert_eq!(got.len(), want.len());
        for (i, (g, w)) in got.iter().zip(want).enumerate() {
            assert!((g - w).abs() <= tol, "[{i}] {g} vs {w}");
        }
    }

    #[test]
    fn svd_matches_cv2_svdecomp() {
        // cv2.SVDecomp(np.array([[2,0,1],[1,3,0],[0,1,4]], np.float64)), 4.8.0.
        let a = [2.0, 0.0, 1.0, 1.0, 3.0, 0.0, 0.0, 1.0, 4.0];
        let s = svd(&a, 3, 3, false);
        assert_close(&s.w, &[4.413270182325494, 2.988206974406626, 1.895696541090981], 1e-15);
        assert_close(
            &s.u,
            &[
                0.29393238748230277,
                -0.07991740139595123,
                0.9524793753898673,
                0.3442939681958901,
                -0.9207540831782229,
                -0.1835036287776279,
                0.8916644071918991,
                0.3818705634959947,
                -0.24312436669813803,
            ],
            1e-15,
        );
        assert_close(
            &s.vt,
            &[
                0.21121723906541148,
                0.43608168824267746,
                0.8747685631645671,
                -0.361617818051141,
                -0.7965953183384676,
                0.48442589987444684,
                0.9080858062922891,
                -0.4186510002145606,
                -0.01055975519750874,
            ],
            1e-15,
        );
    }

    #[test]
    fn svd_full_generates_opencvs_seeded_null_space() {
        // cv2.SVDecomp(np.array([[1,2,3,4],[0,1,0,1]], np.float64), flags=cv2.SVD_FULL_UV):
        // rows 2 and 3 of Vt come from cv::RNG(0x12345678), so this checks the
        // RNG and the completion procedure against the wheel.
        let a = [1.0, 2.0, 3.0, 4.0, 0.0, 1.0, 0.0, 1.0];
        let s = svd(&a, 2, 4, true);
        assert_close(&s.w, &[5.588519143004506, 0.8766149601006039], 1e-15);
        assert_close(
            &s.vt,
            &[
                0.1752839522841622,
                0.3865462858036976,
                0.5258518568524866,
                0.7371141903720221,
                -0.2293662342302739,
                0.6587224774248254,
                -0.6880987026908219,
                0.19999000896427752,
                -0.903696114115064,
                0.12909944487358055,
                0.3872983346207416,
                -0.12909944487358047,
                -0.31622776601683783,
                -0.6324555320336759,
                -0.316227766016838,
                0.6324555320336759,
            ],
            1e-15,
        );
    }

    /// Four lanes against four scalar SVDs, bit for bit: triangulation
    /// matrices like recoverPose's (rank 4 with a small last singular value),
    /// random ones, and degenerate ones (zero columns, repeated columns,
    /// already diagonal) that take the lanes through different numbers of
    /// sweeps and rotations.
    #[test]
    fn four_lanes_are_four_scalar_svds() {
        let mut rnd = crate::testutil::signed_units(0x2545_f491_4f6c_dd1d);
        let mut kinds = [0usize; 4];
        for n in 0..20_000 {
            let ms: [[[f64; 4]; 4]; 4] = std::array::from_fn(|l| match (n + l) % 4 {
                0 => {
                    // DLT rows of a point seen from [I|0] and a slightly
                    // rotated, translated camera.
                    let (x1, y1) = (rnd(), rnd() * 0.5);
                    let (x2, y2) = (x1 + 0.02 * rnd(), y1 + 0.02 * rnd());
                    let p = [
                        [1.0, 0.01 * rnd(), 0.02 * rnd(), 0.1 * rnd()],
                        [0.01 * rnd(), 1.0, 0.01 * rnd(), 0.05 * rnd()],
                        [0.02 * rnd(), 0.01 * rnd(), 1.0, -0.99],
                    ];
                    [
                        [-1.0, 0.0, x1, 0.0],
                        [0.0, -1.0, y1, 0.0],
                        std::array::from_fn(|k| x2 * p[2][k] - p[0][k]),
                        std::array::from_fn(|k| y2 * p[2][k] - p[1][k]),
                    ]
                }
                1 => std::array::from_fn(|_| std::array::from_fn(|_| rnd())),
                2 => {
                    let mut m: [[f64; 4]; 4] = std::array::from_fn(|_| std::array::from_fn(|_| rnd()));
                    let (c, d) = ((n / 4) % 4, (n / 16) % 4);
                    for row in m.iter_mut() {
                        row[c] = if n % 2 == 0 { 0.0 } else { row[d] };
                    }
                    m
                }
                _ => std::array::from_fn(|r| std::array::from_fn(|c| if r == c { rnd() } else { 0.0 })),
            });
            kinds[n % 4] += 1;
            let got = null_vectors_4x4(&ms);
            for l in 0..4 {
                let want = null_vector_4x4(&ms[l]);
                assert_eq!(got[l].map(f64::to_bits), want.map(f64::to_bits), "lane {l} of draw {n}: {:?}", ms[l]);
            }
        }
        assert!(kinds.iter().all(|&k| k == 5_000));
    }
}
