//! [`Lanes`] for x86-64: AVX-512 F (16 lanes) and AVX2 with FMA (8 lanes).

use super::token::{Kernel, Lanes};
use std::arch::x86_64::*;

/// AVX-512 F; only made after the run-time check.
#[derive(Clone, Copy)]
pub(super) struct Avx512(());

/// AVX2 and FMA; only made after the run-time check (or from an
/// AVX-512 token: every AVX-512 CPU has both).
#[derive(Clone, Copy)]
pub(super) struct Avx2(());

#[target_feature(enable = "avx512f,avx2,fma")]
fn on_avx512<K: Kernel>(k: &mut K, start: usize) -> usize {
    k.apply(Avx512(()), start)
}

#[target_feature(enable = "avx2,fma")]
fn on_avx2<K: Kernel>(k: &mut K, start: usize) -> usize {
    k.apply(Avx2(()), start)
}

#[inline(always)]
pub(super) fn run<K: Kernel>(k: &mut K) -> usize {
    if crate::simd::avx512f_fma() {
        // SAFETY: the CPU has AVX-512 F and FMA, and with them AVX2.
        let done = unsafe { on_avx512(k, 0) };
        // SAFETY: as above.
        return unsafe { on_avx2(k, done) };
    }
    if crate::simd::avx2_fma() {
        // SAFETY: the CPU has AVX2 and FMA.
        return unsafe { on_avx2(k, 0) };
    }
    0
}

// Every method below runs only with a token, so the CPU has the feature
// its intrinsics need; the raw-pointer ones add the caller's promise.

impl Lanes for Avx512 {
    one_intrinsic_each! {
        N = 16, F = __m512, I = __m512i, M = __mmask16; ff: add = _mm512_add_ps, sub = _mm512_sub_ps, mul = _mm512_mul_ps, max = _mm512_max_ps, min = _mm512_min_ps; fff: fma = _mm512_fmadd_ps;
        cmp: gt = _mm512_cmp_ps_mask::<_CMP_GT_OQ>, lt = _mm512_cmp_ps_mask::<_CMP_LT_OQ>, ge = _mm512_cmp_ps_mask::<_CMP_GE_OQ>, le = _mm512_cmp_ps_mask::<_CMP_LE_OQ>;
        mm: and = std::ops::BitAnd::bitand, or = std::ops::BitOr::bitor; ii: add_i = _mm512_add_epi32, mul_i = _mm512_mullo_epi32;
        load = _mm512_loadu_ps, store = _mm512_storeu_ps, store_i = _mm512_storeu_si512, splat = _mm512_set1_ps, splat_i = _mm512_set1_epi32, to_f = _mm512_cvtepi32_ps;
    }

    #[inline(always)]
    fn bits(self, m: __mmask16) -> u32 {
        m as u32
    }
    #[inline(always)]
    fn floor(self, v: __m512) -> __m512i {
        // SAFETY: AVX-512 F (the token).
        unsafe { _mm512_cvt_roundps_epi32::<{ _MM_FROUND_TO_NEG_INF | _MM_FROUND_NO_EXC }>(v) }
    }
    #[inline(always)]
    fn wrap(self, o: __m512i, n: __m512i) -> __m512i {
        // SAFETY: AVX-512 F (the token).
        unsafe {
            let o = _mm512_mask_add_epi32(o, _mm512_cmplt_epi32_mask(o, _mm512_setzero_si512()), o, n);
            _mm512_mask_sub_epi32(o, _mm512_cmpge_epi32_mask(o, n), o, n)
        }
    }
    #[inline(always)]
    unsafe fn compress_store(self, p: *mut f32, keep: u32, v: __m512) {
        // SAFETY: AVX-512 F; writes the kept lanes only, inside p..p + 16
        // (the caller's promise).
        unsafe { _mm512_mask_compressstoreu_ps(p.cast(), keep as __mmask16, v) }
    }
}

/// For each 8-bit mask of kept lanes, the lanes to move to the front (in
/// order): AVX2 has no compress-store, `vpermps` by this table does it.
static COMPRESS: [[u32; 8]; 256] = {
    let mut t = [[0u32; 8]; 256];
    let mut m = 0;
    while m < 256 {
        let (mut k, mut l) = (0, 0);
        while l < 8 {
            if m & (1 << l) != 0 {
                t[m][k] = l as u32;
                k += 1;
            }
            l += 1;
        }
        m += 1;
    }
    t
};

impl Lanes for Avx2 {
    one_intrinsic_each! {
        N = 8, F = __m256, I = __m256i, M = __m256; ff: add = _mm256_add_ps, sub = _mm256_sub_ps, mul = _mm256_mul_ps, max = _mm256_max_ps, min = _mm256_min_ps; fff: fma = _mm256_fmadd_ps;
        cmp: gt = _mm256_cmp_ps::<_CMP_GT_OQ>, lt = _mm256_cmp_ps::<_CMP_LT_OQ>, ge = _mm256_cmp_ps::<_CMP_GE_OQ>, le = _mm256_cmp_ps::<_CMP_LE_OQ>;
        mm: and = _mm256_and_ps, or = _mm256_or_ps; ii: add_i = _mm256_add_epi32, mul_i = _mm256_mullo_epi32;
        load = _mm256_loadu_ps, store = _mm256_storeu_ps, store_i = _mm256_storeu_si256, splat = _mm256_set1_ps, splat_i = _mm256_set1_epi32, to_f = _mm256_cvtepi32_ps;
    }

    #[inline(always)]
    fn bits(self, m: __m256) -> u32 {
        // SAFETY: AVX (the token).
        unsafe { _mm256_movemask_ps(m) as u32 }
    }
    #[inline(always)]
    fn floor(self, v: __m256) -> __m256i {
        // SAFETY: AVX (the token).
        unsafe { _mm256_cvttps_epi32(_mm256_floor_ps(v)) }
    }
    #[inline(always)]
    fn wrap(self, o: __m256i, n: __m256i) -> __m256i {
        // SAFETY: AVX2 (the token).
        unsafe {
            let o = _mm256_add_epi32(o, _mm256_and_si256(_mm256_cmpgt_epi32(_mm256_setzero_si256(), o), n));
            _mm256_sub_epi32(o, _mm256_andnot_si256(_mm256_cmpgt_epi32(n, o), n))
        }
    }
    #[inline(always)]
    unsafe fn compress_store(self, p: *mut f32, keep: u32, v: __m256) {
        // SAFETY: AVX2; a COMPRESS entry is eight u32, one vector, and the
        // store writes p..p + 8 (the caller's promise).
        unsafe {
            let perm = _mm256_loadu_si256(COMPRESS[keep as usize & 255].as_ptr().cast());
            _mm256_storeu_ps(p, _mm256_permutevar8x32_ps(v, perm))
        }
    }
}
