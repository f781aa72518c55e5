//! [`Lanes`] for WebAssembly SIMD128, four lanes. The FMA is the engine's
//! fused `relaxed_madd` where the relaxed build found it fused, else the
//! exact emulation (`num::wasm`).

use super::super::num::wasm::{Emulated, Fma4};
use super::token::{Kernel, Lanes};
use core::arch::wasm32::*;

/// SIMD128 with the FMA `F`.
#[derive(Clone, Copy)]
pub(super) struct Simd128<F>(F);

#[inline(always)]
pub(super) fn run<K: Kernel>(k: &mut K) -> usize {
    #[cfg(feature = "relaxed-simd")]
    if crate::sift::num::relaxed_madd_is_fused() {
        // Compiled with relaxed SIMD so that each `relaxed_madd` inlines.
        #[target_feature(enable = "relaxed-simd")]
        fn fused<K: Kernel>(k: &mut K) -> usize {
            k.apply(Simd128(super::super::num::wasm::Fused::new()), 0)
        }
        return fused(k);
    }
    k.apply(Simd128(Emulated), 0)
}

/// Byte shuffles that move the lanes set in a 4-bit mask to the front.
const COMPRESS: [v128; 16] = {
    let mut table = [u8x16(0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0); 16];
    let mut m = 0;
    while m < 16 {
        let mut bytes = [0u8; 16];
        let (mut lane, mut at) = (0, 0);
        while lane < 4 {
            if m & (1 << lane) != 0 {
                let mut b = 0;
                while b < 4 {
                    bytes[4 * at + b] = (4 * lane + b) as u8;
                    b += 1;
                }
                at += 1;
            }
            lane += 1;
        }
        table[m] = u8x16(
            bytes[0], bytes[1], bytes[2], bytes[3], bytes[4], bytes[5], bytes[6], bytes[7], bytes[8], bytes[9],
            bytes[10], bytes[11], bytes[12], bytes[13], bytes[14], bytes[15],
        );
        m += 1;
    }
    table
};

impl<F: Fma4> Lanes for Simd128<F> {
    // `pmax`/`pmin` are one instruction each and equal `max`/`min` here: no
    // NaN arises from 8-bit images, and the ±0 ties where they differ cannot
    // decide a test whose value lies beyond the threshold (docs/fidelity.md §SIFT-6).
    one_intrinsic_each! {
        N = 4, F = v128, I = v128, M = v128; ff: add = f32x4_add, sub = f32x4_sub, mul = f32x4_mul, max = f32x4_pmax, min = f32x4_pmin; fff: ;
        cmp: gt = f32x4_gt, lt = f32x4_lt, ge = f32x4_ge, le = f32x4_le; mm: and = v128_and, or = v128_or; ii: add_i = i32x4_add, mul_i = i32x4_mul;
        load = v128_load, store = v128_store, store_i = v128_store, splat = f32x4_splat, splat_i = i32x4_splat, to_f = f32x4_convert_i32x4;
    }

    #[inline(always)]
    fn fma(self, a: v128, b: v128, c: v128) -> v128 {
        self.0.fma(a, b, c)
    }
    #[inline(always)]
    fn bits(self, m: v128) -> u32 {
        i32x4_bitmask(m) as u32
    }
    #[inline(always)]
    fn floor(self, v: v128) -> v128 {
        i32x4_trunc_sat_f32x4(f32x4_floor(v))
    }
    #[inline(always)]
    fn wrap(self, o: v128, n: v128) -> v128 {
        let o = i32x4_add(o, v128_and(i32x4_lt(o, i32x4_splat(0)), n));
        i32x4_sub(o, v128_and(i32x4_ge(o, n), n))
    }
    #[inline(always)]
    unsafe fn compress_store(self, p: *mut f32, keep: u32, v: v128) {
        // SAFETY: p..p + 4 writable (the caller's promise).
        unsafe { v128_store(p.cast(), i8x16_swizzle(v, COMPRESS[keep as usize & 15])) }
    }
}
