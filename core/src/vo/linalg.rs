//! The three small numeric routines OpenCV's five-point solver, RANSAC and
//! recoverPose run through (docs/fidelity.md §VO-3.5 to §VO-3.7): its one-sided Jacobi
//! SVD with the seeded null-space completion, the small LU inverse and the
//! Durand–Kerner `solvePoly`. All of them live in OpenCV files compiled for the
//! baseline ISA, so every operation here is a plain f64 operation (no FMA).

/// `cv::RNG`: the multiply-with-carry generator OpenCV seeds per call.
#[derive(Clone, Copy, Debug)]
pub struct CvRng {
    state: u64,
}

impl CvRng {
    /// `CV_RNG_COEFF` in core/include/opencv2/core/operations.hpp.
    const COEFF: u64 = 4_164_903_690;

    pub fn new(seed: u64) -> Self {
        CvRng { state: seed }
    }

    #[inline]
    pub fn next_u32(&mut self) -> u32 {
        self.state = (self.state & 0xFFFF_FFFF).wrapping_mul(Self::COEFF).wrapping_add(self.state >> 32);
        self.state as u32
    }

    /// `RNG::uniform(0, n)` for ints: `next() % n` in unsigned 32-bit.
    #[inline]
    pub fn uniform(&mut self, n: u32) -> u32 {
        self.next_u32() % n
    }
}

/// Result of [`svd`]: `w` descending, `u` (m×ucols, row-major) and `vt`
/// (vrows×n, row-major).
#[derive(Clone, Debug)]
pub struct Svd {
    pub w: Vec<f64>,
    pub u: Vec<f64>,
    pub ucols: usize,
    pub vt: Vec<f64>,
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
                let gamma = p.hypot(beta);
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

    // Selection sort, descending; only a strictly greater value moves the pick.
    for i in 0..n.saturating_sub(1) {
        let mut j = i;
        for k in i + 1..n {
            if w[j] < w[k] {
                j = k;
            }
        }
        if i != j {
            w.swap(i, j);
            for k in 0..m {
                at.swap(i * m + k, j * m + k);
            }
            for k in 0..n {
                vt.swap(i * n + k, j * n + k);
            }
        }
    }

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
        let mut u = vec![0.0; count * count];
        for i in 0..count {
            for k in 0..count {
                u[k * count + i] = v[i * count + k];
            }
        }
        Svd { w, u, ucols: count, vt: at, vrows: n1 }
    } else {
        let mut u = vec![0.0; len * n1];
        for i in 0..n1 {
            for k in 0..len {
                u[k * n1 + i] = at[i * len + k];
            }
        }
        Svd { w, u, ucols: n1, vt: v, vrows: count }
    }
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

/// `cv::invert(A, DECOMP_LU)` for an n×n block (§VO-3.6): `LUImpl<double>`
/// against the identity. Returns `None` where OpenCV would return an all-zero
/// inverse (pivot below 100·DBL_EPSILON).
pub fn lu_inverse(a: &[f64], n: usize) -> Option<Vec<f64>> {
    let mut a = a.to_vec();
    let mut b = vec![0.0; n * n];
    for i in 0..n {
        b[i * n + i] = 1.0;
    }
    let eps = f64::EPSILON * 100.0;
    for i in 0..n {
        let mut k = i;
        for j in i + 1..n {
            if a[j * n + i].abs() > a[k * n + i].abs() {
                k = j;
            }
        }
        if a[k * n + i].abs() < eps {
            return None;
        }
        if k != i {
            for j in i..n {
                a.swap(i * n + j, k * n + j);
            }
            for j in 0..n {
                b.swap(i * n + j, k * n + j);
            }
        }
        let d = -1.0 / a[i * n + i];
        for j in i + 1..n {
            let alpha = a[j * n + i] * d;
            for k in i + 1..n {
                a[j * n + k] += alpha * a[i * n + k];
            }
            for k in 0..n {
                b[j * n + k] += alpha * b[i * n + k];
            }
        }
    }
    for i in (0..n).rev() {
        for j in 0..n {
            let mut s = b[i * n + j];
            for k in i + 1..n {
                s -= a[i * n + k] * b[k * n + j];
            }
            b[i * n + j] = s / a[i * n + i];
        }
    }
    Some(b)
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Complex {
    pub re: f64,
    pub im: f64,
}

impl Complex {
    const fn new(re: f64, im: f64) -> Self {
        Complex { re, im }
    }
    #[inline]
    fn mul(self, o: Complex) -> Complex {
        Complex::new(self.re * o.re - self.im * o.im, self.re * o.im + self.im * o.re)
    }
    #[inline]
    fn add(self, o: Complex) -> Complex {
        Complex::new(self.re + o.re, self.im + o.im)
    }
    #[inline]
    fn sub(self, o: Complex) -> Complex {
        Complex::new(self.re - o.re, self.im - o.im)
    }
    /// `cv::Complex` division: one reciprocal of |o|², then two products.
    #[inline]
    fn div(self, o: Complex) -> Complex {
        let t = 1.0 / (o.re * o.re + o.im * o.im);
        Complex::new((self.re * o.re + self.im * o.im) * t, (-self.re * o.im + self.im * o.re) * t)
    }
}

/// `cv::solvePoly` (§VO-3.7): Durand–Kerner with in-place updates. `c[k]` is the
/// coefficient of z^k. Returns the roots in index order.
pub fn solve_poly(c: &[f64], max_iters: usize) -> Vec<Complex> {
    durand_kerner(c, max_iters, true).0
}

/// OpenCV runs all `max_iters` sweeps unless every step is exactly 0, which
/// converged roots rarely reach: rounding leaves them cycling through a few
/// states whose last bits differ (periods of 1 to 12 sweeps, entered after
/// 15 to 50). A sweep is a function of the roots alone, so once a state
/// repeats, every later state is known: with `skip_cycles` the roots after
/// `max_iters` sweeps are read from the cycle instead of computed — OpenCV's
/// roots, bit for bit (the 300 sweeps were 85 % of findEssentialMat). Some
/// polynomials never repeat within 300 sweeps (their last bits wander) and
/// still take all of them. Returns the roots and the sweeps computed.
fn durand_kerner(c: &[f64], max_iters: usize, skip_cycles: bool) -> (Vec<Complex>, usize) {
    let n0 = c.len().saturating_sub(1);
    let coeffs: Vec<Complex> = c.iter().map(|&v| Complex::new(v, 0.0)).collect();
    let mut n = n0;
    while n > 1 {
        // An absolute test on the leading coefficient, as OpenCV writes it.
        if coeffs[n].re.abs() + coeffs[n].im.abs() > f64::EPSILON {
            break;
        }
        n -= 1;
    }
    let mut roots = vec![Complex::new(0.0, 0.0); n0];
    let mut p = Complex::new(1.0, 0.0);
    let r = Complex::new(1.0, 1.0);
    for root in roots.iter_mut().take(n) {
        *root = p;
        p = p.mul(r);
    }
    // history[t·n..] = the roots after t sweeps, fingerprints[t] a hash of
    // their bits (the states are compared in full when the hashes agree).
    let fingerprint = |r: &[Complex]| {
        r.iter()
            .flat_map(|z| [z.re.to_bits(), z.im.to_bits()])
            .fold(0u64, |h, v| (h ^ v).wrapping_mul(0x9E37_79B9_7F4A_7C15).rotate_left(29))
    };
    let same = |a: &[Complex], b: &[Complex]| {
        a.iter().zip(b).all(|(x, y)| x.re.to_bits() == y.re.to_bits() && x.im.to_bits() == y.im.to_bits())
    };
    let mut history: Vec<Complex> = Vec::new();
    let mut fingerprints: Vec<u64> = Vec::new();
    let mut sweeps = 0;
    while sweeps < max_iters {
        if skip_cycles {
            let f = fingerprint(&roots[..n]);
            let repeat = (0..sweeps).find(|&t| fingerprints[t] == f && same(&history[t * n..(t + 1) * n], &roots[..n]));
            if let Some(first) = repeat {
                // States first..sweeps−1 repeat forever, and each of them
                // moved a root (else the loop had stopped): no early stop
                // comes, and the last state is the cycle's entry at max_iters.
                let t = first + (max_iters - first) % (sweeps - first);
                roots[..n].copy_from_slice(&history[t * n..(t + 1) * n]);
                break;
            }
            fingerprints.push(f);
            history.extend_from_slice(&roots[..n]);
        }
        sweeps += 1;
        if !sweep(&coeffs[..=n], &mut roots[..n]) {
            break;
        }
    }
    for root in roots.iter_mut() {
        if root.im.abs() < 1e-100 {
            root.im = 0.0;
        }
    }
    roots.truncate(n);
    (roots, sweeps)
}

/// One Durand–Kerner sweep over `roots` in place, for the polynomial of
/// degree `roots.len()` with coefficients `coeffs` (ascending). Returns
/// whether OpenCV's maxDiff became positive (else it stops).
fn sweep(coeffs: &[Complex], roots: &mut [Complex]) -> bool {
    let n = roots.len();
    // OpenCV keeps maxDiff = max(maxDiff, |Δ|) and stops when it is 0; only
    // "is it still 0" matters, so the hypot is replaced by the exact test
    // of when it is positive (see `moved`).
    let mut changed = false;
    for i in 0..n {
        let p = roots[i];
        let mut num = coeffs[n];
        let mut den = coeffs[n];
        for j in 0..n {
            num = num.mul(p).add(coeffs[n - j - 1]);
            if j != i {
                let d = p.sub(roots[j]);
                // OpenCV skips an exactly coinciding root (p == roots[j]).
                if d.re != 0.0 || d.im != 0.0 {
                    den = den.mul(d);
                }
            }
        }
        let delta = num.div(den);
        roots[i] = p.sub(delta);
        changed |= moved(delta);
    }
    changed
}

/// Whether `std::max(maxDiff, hypot(Δ))` makes a zero maxDiff positive:
/// hypot is +inf when a part is infinite (even with a NaN beside it), NaN
/// when a part is NaN otherwise (and max keeps the 0 then), and positive
/// for any finite Δ ≠ 0 (it does not underflow).
#[inline]
fn moved(d: Complex) -> bool {
    d.re.is_infinite() || d.im.is_infinite() || (!d.re.is_nan() && !d.im.is_nan() && (d.re != 0.0 || d.im != 0.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn moved_is_hypot_making_max_positive() {
        let v = [0.0, -0.0, 5e-324, -1e-300, 1.0, f64::INFINITY, f64::NEG_INFINITY, f64::NAN];
        for &re in &v {
            for &im in &v {
                let d = Complex::new(re, im);
                assert_eq!(moved(d), 0.0f64.max(re.hypot(im)) > 0.0, "{re} {im}");
            }
        }
    }

    #[test]
    fn rng_follows_the_mwc_recurrence() {
        // The first draws of cv::RNG((uint64)-1), the state findEssentialMat's
        // RANSAC starts from (state = lo32 * 4164903690 + hi32).
        let mut rng = CvRng::new(u64::MAX);
        assert_eq!([rng.next_u32(), rng.next_u32(), rng.next_u32()], [130_063_605, 3_133_359_004, 2_578_348_940]);
        assert_eq!(CvRng::new(u64::MAX).uniform(1000), 605);
    }

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

    #[test]
    fn lu_inverse_inverts_and_flags_singular() {
        let a = [2.0, 1.0, 0.0, 1.0, 3.0, 1.0, 0.0, 1.0, 4.0];
        let inv = lu_inverse(&a, 3).unwrap();
        for r in 0..3 {
            for c in 0..3 {
                let v: f64 = (0..3).map(|k| a[r * 3 + k] * inv[k * 3 + c]).sum();
                assert!((v - if r == c { 1.0 } else { 0.0 }).abs() < 1e-15);
            }
        }
        assert!(lu_inverse(&[1.0, 2.0, 2.0, 4.0], 2).is_none());
    }

    #[test]
    fn solve_poly_finds_known_roots_in_start_order() {
        // (z-1)(z-2)(z+3) = z^3 - 7z + 6
        let roots = solve_poly(&[6.0, -7.0, 0.0, 1.0], 300);
        assert_eq!(roots.len(), 3);
        let mut re: Vec<f64> = roots.iter().map(|r| r.re).collect();
        for r in &roots {
            assert!(r.im.abs() < 1e-10);
        }
        re.sort_by(|a, b| a.partial_cmp(b).unwrap());
        for (got, want) in re.iter().zip([-3.0, 1.0, 2.0]) {
            assert!((got - want).abs() < 1e-12, "{got}");
        }
        // z^2 + 1: a complex pair.
        let roots = solve_poly(&[1.0, 0.0, 1.0], 300);
        assert!(roots.iter().all(|r| (r.im.abs() - 1.0).abs() < 1e-12 && r.re.abs() < 1e-12));
    }

    /// Reading the roots off a cycle gives those of all 300 sweeps bit for
    /// bit, and does save sweeps, on the five-point solver's kind of input:
    /// degree 10, real roots and complex pairs over several magnitudes
    /// (expanded from chosen roots), and plain random coefficients.
    #[test]
    fn solve_poly_skips_cycles_with_the_full_runs_roots() {
        let mut rng = CvRng::new(24011);
        let mut unit = || rng.next_u32() as f64 / u32::MAX as f64 * 2.0 - 1.0;
        let mut sweeps = Vec::new();
        for case in 0..300 {
            let c: Vec<f64> = if case % 2 == 0 {
                // Π (z − rₖ), rₖ real or in conjugate pairs, |rₖ| from 1e-3 to 1e3.
                let mut poly = vec![Complex::new(1.0, 0.0)];
                while poly.len() < 11 {
                    let scale = 10f64.powf(3.0 * unit());
                    let root = Complex::new(
                        scale * unit(),
                        if poly.len() < 10 && unit() > 0.0 { scale * unit() } else { 0.0 },
                    );
                    let pair = if root.im != 0.0 { vec![root, Complex::new(root.re, -root.im)] } else { vec![root] };
                    for r in pair {
                        let mut next = vec![Complex::new(0.0, 0.0); poly.len() + 1];
                        for (k, &a) in poly.iter().enumerate() {
                            next[k + 1] = next[k + 1].add(a);
                            next[k] = next[k].sub(a.mul(r));
                        }
                        poly = next;
                    }
                }
                poly.iter().map(|z| z.re).collect()
            } else {
                (0..11).map(|_| unit() * 10f64.powf(2.0 * unit())).collect()
            };
            let (fast, n) = durand_kerner(&c, 300, true);
            let (full, m) = durand_kerner(&c, 300, false);
            let bits = |r: &[Complex]| r.iter().map(|z| (z.re.to_bits(), z.im.to_bits())).collect::<Vec<_>>();
            assert_eq!(bits(&fast), bits(&full), "case {case}: {c:?}");
            assert!(n <= m);
            sweeps.push(n);
        }
        sweeps.sort();
        let median = sweeps[sweeps.len() / 2];
        assert!(median < 100, "median sweeps {median}: cycles are no longer skipped");
        eprintln!("solve_poly sweeps: median {median}, max {}", sweeps[sweeps.len() - 1]);
    }
}
