//! [`exp32f`](super::exp32f) eight lanes at a time with AVX2: the same
//! operations in the same order per lane (the table read by a gather), so the
//! same bits (docs/fidelity.md §SIFT-12).

use super::exp::{EXP_A1, EXP_A2, EXP_A3, EXP_A4, EXP_TAB};
use std::arch::x86_64::*;

/// `exp32f` of `args[0..]` (whole groups of eight) into `out`; returns
/// how many.
#[target_feature(enable = "avx2,fma")]
pub fn exp32f(args: &[f32], out: &mut [f32]) -> usize {
    let n = args.len().min(out.len()) / 8 * 8;
    let k = _mm256_set1_ps;
    let ki = _mm256_set1_epi32;
    let mut i = 0;
    while i < n {
        // SAFETY: i + 8 <= n <= args.len().
        let x = unsafe { _mm256_loadu_ps(args.as_ptr().add(i)) };
        let x =
            _mm256_mul_ps(_mm256_min_ps(_mm256_max_ps(x, k(-2079.4417)), k(2079.4417)), k(f32::from_bits(0x42B8AA3B)));
        // rne: ties to even, as the current rounding mode does.
        let xi = _mm256_cvtps_epi32(_mm256_round_ps::<{ _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC }>(x));
        let xf = _mm256_mul_ps(_mm256_sub_ps(x, _mm256_cvtepi32_ps(xi)), k(0.015625));
        let e =
            _mm256_min_epi32(_mm256_max_epi32(_mm256_add_epi32(_mm256_srai_epi32::<6>(xi), ki(127)), ki(0)), ki(255));
        // SAFETY: every index is `xi & 63`, inside the 64-entry table.
        let t = unsafe { _mm256_i32gather_ps::<4>(EXP_TAB.as_ptr() as *const f32, _mm256_and_si256(xi, ki(63))) };
        let tab = _mm256_mul_ps(t, _mm256_castsi256_ps(_mm256_slli_epi32::<23>(e)));
        let mut z = _mm256_add_ps(xf, k(EXP_A1));
        z = _mm256_fmadd_ps(z, xf, k(EXP_A2));
        z = _mm256_fmadd_ps(z, xf, k(EXP_A3));
        z = _mm256_fmadd_ps(z, xf, k(EXP_A4));
        // SAFETY: i + 8 <= n <= out.len().
        unsafe { _mm256_storeu_ps(out.as_mut_ptr().add(i), _mm256_mul_ps(z, tab)) };
        i += 8;
    }
    n
}

#[cfg(test)]
mod tests {
    use super::super::exp32f as scalar_exp32f;

    /// The AVX2 `exp32f` against the scalar one, bit for bit, over the
    /// arguments the orientation weights take (−d²/(2σ²), down to about −9)
    /// and far beyond, both clamps included.
    #[test]
    fn vector_exp32f_is_the_scalar_one() {
        if !crate::simd::avx2_fma() {
            return;
        }
        let args: Vec<f32> = (0..40_000)
            .map(|i| -2500.0 + i as f32 * 0.0625 + (i % 7) as f32 * 1e-3)
            .chain([0.0, -0.0, 3000.0, -3000.0])
            .collect();
        let mut out = vec![0f32; args.len()];
        // SAFETY: the CPU has AVX2 and FMA (checked above).
        let done = unsafe { super::exp32f(&args, &mut out) };
        assert_eq!(done, args.len() / 8 * 8);
        for (k, (&a, &o)) in args.iter().zip(&out).enumerate().take(done) {
            assert_eq!(o.to_bits(), crate::with_hw_fma!(f32, scalar_exp32f(a)).to_bits(), "exp32f({a}) at {k}");
        }
    }
}
