//! [`super::null_vectors_4x4`] with AVX2: four 4×4 Jacobi SVDs as the four
//! lanes of each f64 vector. Every lane sees the scalar code's operations in
//! the scalar code's order (no FMA: OpenCV's `lapack.cpp` is baseline code),
//! the data-dependent branches become per-lane selects, and `hypot` is
//! glibc's algorithm as [`crate::vo::linalg::hypot`] writes it, so each
//! lane's null vector is the scalar one bit for bit (the tests compare them,
//! and the vector `hypot` with the scalar one). docs/fidelity.md §VO-3.5 (the
//! SVD), §VO-4 (its use).

use crate::vo::linalg::hypot::{EPS, LARGE, TINY};
use std::arch::x86_64::*;

#[target_feature(enable = "avx2")]
#[inline]
fn splat(v: f64) -> __m256d {
    _mm256_set1_pd(v)
}

/// `lane ? b : a`, lane by lane (`mask` all ones or all zeros).
#[target_feature(enable = "avx2")]
#[inline]
fn select(mask: __m256d, a: __m256d, b: __m256d) -> __m256d {
    _mm256_blendv_pd(a, b, mask)
}

/// The four lanes of `v`.
#[target_feature(enable = "avx2")]
#[inline]
fn lanes(v: __m256d) -> [f64; 4] {
    let mut out = [0.0; 4];
    // SAFETY: 4 f64 into a [f64; 4]; an unaligned store.
    unsafe { _mm256_storeu_pd(out.as_mut_ptr(), v) };
    out
}

/// A vector of the four values.
#[target_feature(enable = "avx2")]
#[inline]
fn from_lanes(v: &[f64; 4]) -> __m256d {
    // SAFETY: 4 f64 from a [f64; 4]; an unaligned load.
    unsafe { _mm256_loadu_pd(v.as_ptr()) }
}

/// [`crate::vo::linalg::hypot`] (glibc's, the kernel without FMA), lane by
/// lane, for the common case: both inputs finite, the larger not above
/// 2^511 and the smaller not below 2^-459. Lanes outside it (zeros, NaN, extreme magnitudes) are handed to the scalar
/// function one by one, those of `live` only (the others' results are
/// thrown away).
///
/// # Safety
/// The CPU must have AVX2. (Not a `#[target_feature]` function, so that it
/// can be `#[inline(always)]` into the SVD's inner loop.)
#[inline(always)]
unsafe fn hypot(x: __m256d, y: __m256d, live: __m256d) -> __m256d {
    // SAFETY: the caller vouches for AVX2, the feature of every intrinsic
    // and helper called here; memory is touched only through `lanes` and
    // `from_lanes` on local arrays.
    unsafe {
        let abs = _mm256_castsi256_pd(_mm256_set1_epi64x(i64::MAX));
        let (x, y) = (_mm256_and_pd(x, abs), _mm256_and_pd(y, abs));
        // ax = x < y ? y : x; ay = x < y ? x : y.
        let lt = _mm256_cmp_pd::<_CMP_LT_OQ>(x, y);
        let (ax, ay) = (select(lt, x, y), select(lt, y, x));
        let two = splat(2.0);
        // kernel(ax, ay): h = sqrt(ax² + ay²), then Borges' correction.
        let h = _mm256_sqrt_pd(_mm256_add_pd(_mm256_mul_pd(ax, ax), _mm256_mul_pd(ay, ay)));
        let near = _mm256_cmp_pd::<_CMP_LE_OQ>(h, _mm256_mul_pd(two, ay));
        // h <= 2·ay: δ = h − ay, t1 = ax·(2δ − ax), t2 = (δ − 2(ax − ay))·δ.
        let d_near = _mm256_sub_pd(h, ay);
        let t1_near = _mm256_mul_pd(ax, _mm256_sub_pd(_mm256_mul_pd(two, d_near), ax));
        let t2_near = _mm256_mul_pd(_mm256_sub_pd(d_near, _mm256_mul_pd(two, _mm256_sub_pd(ax, ay))), d_near);
        // else: δ = h − ax, t1 = 2δ·(ax − 2ay), t2 = (4δ − ay)·ay + δ·δ.
        let d_far = _mm256_sub_pd(h, ax);
        let t1_far = _mm256_mul_pd(_mm256_mul_pd(two, d_far), _mm256_sub_pd(ax, _mm256_mul_pd(two, ay)));
        let t2_far = _mm256_add_pd(
            _mm256_mul_pd(_mm256_sub_pd(_mm256_mul_pd(splat(4.0), d_far), ay), ay),
            _mm256_mul_pd(d_far, d_far),
        );
        let (t1, t2) = (select(near, t1_far, t1_near), select(near, t2_far, t2_near));
        let kernel = _mm256_sub_pd(h, _mm256_div_pd(_mm256_add_pd(t1, t2), _mm256_mul_pd(two, h)));
        // ay <= ax·2^-54: ax + ay (ay is below half an ulp of ax).
        let widely = _mm256_cmp_pd::<_CMP_LE_OQ>(ay, _mm256_mul_pd(ax, splat(EPS)));
        let r = select(widely, kernel, _mm256_add_pd(ax, ay));
        // The common case: ax <= 2^511 and ay >= 2^-459 (false for NaN;
        // an infinite ax fails the first test).
        let common =
            _mm256_and_pd(_mm256_cmp_pd::<_CMP_LE_OQ>(ax, splat(LARGE)), _mm256_cmp_pd::<_CMP_GE_OQ>(ay, splat(TINY)));
        let common = _mm256_or_pd(common, _mm256_xor_pd(live, _mm256_castsi256_pd(_mm256_set1_epi64x(-1))));
        if _mm256_movemask_pd(common) == 0b1111 {
            return r;
        }
        let (xs, ys, mut rs) = (lanes(x), lanes(y), lanes(r));
        let m = _mm256_movemask_pd(common);
        for l in 0..4 {
            if m >> l & 1 == 0 {
                rs[l] = crate::vo::linalg::hypot(xs[l], ys[l]);
            }
        }
        from_lanes(&rs)
    }
}

/// Rows i < j of `m`, both mutable.
#[inline(always)]
fn split_pair(m: &mut [[__m256d; 4]; 4], i: usize, j: usize) -> (&mut [__m256d; 4], &mut [__m256d; 4]) {
    let (lo, hi) = m.split_at_mut(j);
    (&mut lo[i], &mut hi[0])
}

/// `jacobi_impl` with m = n = n1 = 4 on four matrices, one a lane, then
/// each lane's selection sort of the singular values to find which row
/// of Vᵀ comes last. A lane whose sweep changes nothing would have left
/// the scalar loop; here it goes on with the others, but a sweep that
/// changed nothing leaves the state as it was, so it changes nothing
/// again: the lane's values stay exactly the scalar ones.
#[target_feature(enable = "avx2")]
pub(super) fn null_vectors_avx2(ms: &[[[f64; 4]; 4]; 4]) -> [[f64; 4]; 4] {
    // at[i][k] = column i of A, element k; lane l = matrix l.
    let mut at = [[_mm256_setzero_pd(); 4]; 4];
    for (i, col) in at.iter_mut().enumerate() {
        for (k, v) in col.iter_mut().enumerate() {
            *v = _mm256_setr_pd(ms[0][k][i], ms[1][k][i], ms[2][k][i], ms[3][k][i]);
        }
    }
    let zero = _mm256_setzero_pd();
    let dot = |a: &[__m256d; 4], b: &[__m256d; 4]| {
        let mut s = zero;
        for k in 0..4 {
            s = _mm256_add_pd(s, _mm256_mul_pd(a[k], b[k]));
        }
        s
    };
    let mut w: [__m256d; 4] = std::array::from_fn(|i| dot(&at[i], &at[i]));
    let mut vt: [[__m256d; 4]; 4] = std::array::from_fn(|i| std::array::from_fn(|k| splat((i == k) as u8 as f64)));
    let eps = splat(f64::EPSILON * 10.0);
    let abs = _mm256_castsi256_pd(_mm256_set1_epi64x(i64::MAX));
    let (two, half) = (splat(2.0), splat(0.5));
    // JacobiSVD's max(m, 30) sweeps at most.
    for _ in 0..30 {
        let mut changed = 0;
        for i in 0..3 {
            for j in i + 1..4 {
                let (a, b) = (w[i], w[j]);
                let p = dot(&at[i], &at[j]);
                // |p| <= eps·sqrt(a·b): the pair is left alone (false
                // for NaN, as in the scalar code).
                let skip = _mm256_cmp_pd::<_CMP_LE_OQ>(
                    _mm256_and_pd(p, abs),
                    _mm256_mul_pd(eps, _mm256_sqrt_pd(_mm256_mul_pd(a, b))),
                );
                let skip_bits = _mm256_movemask_pd(skip);
                if skip_bits == 0b1111 {
                    continue;
                }
                let p = _mm256_mul_pd(p, two);
                let beta = _mm256_sub_pd(a, b);
                let live = _mm256_xor_pd(skip, _mm256_castsi256_pd(_mm256_set1_epi64x(-1)));
                // SAFETY: this function runs with AVX2, all `hypot` needs.
                let gamma = unsafe { hypot(p, beta, live) };
                // beta < 0: δ = (γ − β)·0.5, s = sqrt(δ/γ), c = p/(γ·s·2);
                // else c = sqrt((γ + β)/(γ·2)), s = p/(γ·c·2).
                let neg = _mm256_cmp_pd::<_CMP_LT_OQ>(beta, zero);
                let neg_bits = _mm256_movemask_pd(neg);
                let (mut c, mut s) = (zero, zero);
                if neg_bits != 0 {
                    let delta = _mm256_mul_pd(_mm256_sub_pd(gamma, beta), half);
                    let sn = _mm256_sqrt_pd(_mm256_div_pd(delta, gamma));
                    let cn = _mm256_div_pd(p, _mm256_mul_pd(_mm256_mul_pd(gamma, sn), two));
                    (c, s) = (cn, sn);
                }
                if neg_bits != 0b1111 {
                    let cp = _mm256_sqrt_pd(_mm256_div_pd(_mm256_add_pd(gamma, beta), _mm256_mul_pd(gamma, two)));
                    let sp = _mm256_div_pd(p, _mm256_mul_pd(_mm256_mul_pd(gamma, cp), two));
                    (c, s) = (select(neg, cp, c), select(neg, sp, s));
                }
                let ms = _mm256_xor_pd(s, splat(-0.0));
                // (x, y) ← (c·x + s·y, −s·x + c·y) where the pair is
                // rotated; returns the rotated values.
                let rotate = |x: &mut __m256d, y: &mut __m256d| {
                    let t0 = _mm256_add_pd(_mm256_mul_pd(c, *x), _mm256_mul_pd(s, *y));
                    let t1 = _mm256_add_pd(_mm256_mul_pd(ms, *x), _mm256_mul_pd(c, *y));
                    (*x, *y) = (select(skip, t0, *x), select(skip, t1, *y));
                    (t0, t1)
                };
                let (mut na, mut nb) = (zero, zero);
                let (ati, atj) = split_pair(&mut at, i, j);
                for (x, y) in ati.iter_mut().zip(atj.iter_mut()) {
                    let (t0, t1) = rotate(x, y);
                    na = _mm256_add_pd(na, _mm256_mul_pd(t0, t0));
                    nb = _mm256_add_pd(nb, _mm256_mul_pd(t1, t1));
                }
                w[i] = select(skip, na, a);
                w[j] = select(skip, nb, b);
                let (vti, vtj) = split_pair(&mut vt, i, j);
                for (x, y) in vti.iter_mut().zip(vtj.iter_mut()) {
                    rotate(x, y);
                }
                changed |= !skip_bits & 0b1111;
            }
        }
        if changed == 0 {
            break;
        }
    }
    // Singular values, then each lane's selection sort (descending, a
    // strictly greater value moves the pick): the row of Vᵀ that ends
    // last is the null vector.
    let sv: [[f64; 4]; 4] = std::array::from_fn(|i| lanes(_mm256_sqrt_pd(dot(&at[i], &at[i]))));
    let vts: [[[f64; 4]; 4]; 4] = std::array::from_fn(|i| std::array::from_fn(|k| lanes(vt[i][k])));
    std::array::from_fn(|l| {
        let mut w = [sv[0][l], sv[1][l], sv[2][l], sv[3][l]];
        let mut row = [0, 1, 2, 3];
        super::sort::sort_descending(&mut w, |i, j| row.swap(i, j));
        std::array::from_fn(|k| vts[row[3]][k][l])
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The vector `hypot` of four lane pairs, all lanes live.
    #[target_feature(enable = "avx2")]
    fn hypot_lanes(x: [f64; 4], y: [f64; 4]) -> [f64; 4] {
        let all = _mm256_castsi256_pd(_mm256_set1_epi64x(-1));
        // SAFETY: this function runs with AVX2, all `hypot` needs.
        lanes(unsafe { hypot(from_lanes(&x), from_lanes(&y), all) })
    }

    /// The vector `hypot` against the scalar one, bit for bit, over
    /// every magnitude relation the kernel distinguishes and the lanes
    /// it hands back (zeros, subnormals, huge, infinite, NaN).
    #[test]
    fn vector_hypot_is_the_scalar_one() {
        if !crate::simd::avx2() {
            return;
        }
        let mut rng = crate::testutil::XorShift64::new(0x0123_4567_89ab_cdef);
        let mut next = move || rng.next_u64();
        let special = [0.0, -0.0, 5e-324, 1e-310, 2.2e-308, 1e-300, 1.0, 1e300, f64::MAX, f64::INFINITY, f64::NAN];
        for n in 0..400_000 {
            let pick = |r: u64| -> f64 {
                match r % 8 {
                    0 => special[(r >> 8) as usize % special.len()],
                    // Exponents over the whole range.
                    1 => f64::from_bits(r >> 1),
                    // Near 1, and nearly equal pairs below.
                    _ => f64::from_bits(0x3ff0_0000_0000_0000 | (r >> 12)) * [1.0, -1.0][(r >> 3) as usize & 1],
                }
            };
            let x: [f64; 4] = std::array::from_fn(|_| pick(next()));
            let y: [f64; 4] = std::array::from_fn(|l| match n % 3 {
                0 => pick(next()),
                // A second operand close to the first (h ≈ 2·ay).
                1 => x[l] * (1.0 + (next() >> 40) as f64 * 1e-12),
                // One far below (the widely-varying branch).
                _ => x[l] * f64::from_bits(0x3c00_0000_0000_0000 | (next() >> 12)),
            });
            // SAFETY: AVX2 checked above.
            let got = unsafe { hypot_lanes(x, y) };
            for l in 0..4 {
                let want = crate::vo::linalg::hypot(x[l], y[l]);
                assert!(
                    got[l].to_bits() == want.to_bits() || (got[l].is_nan() && want.is_nan()),
                    "hypot({:e}, {:e}) = {:e}, scalar {:e}",
                    x[l],
                    y[l],
                    got[l],
                    want
                );
            }
        }
    }
}
