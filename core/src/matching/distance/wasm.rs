//! The simd128 distance kernel on the exact integer sums of `super`: the
//! same distances bit for bit (docs/fidelity.md §SIFT-16).

use core::arch::wasm32::*;

/// Bytes `16k .. 16k + 16` of a descriptor, `k < 8`.
#[inline(always)]
fn load(d: &[u8; 128], k: usize) -> v128 {
    assert!(k < 8);
    // SAFETY: 16 * k + 16 <= 128 bytes of `d` are readable; wasm loads
    // need no alignment.
    unsafe { v128_load(d.as_ptr().add(16 * k) as *const v128) }
}

/// simd128: the query as sixteen i16x8 vectors, `i32x4.dot_i16x8_s`
/// squares and pairs the differences.
pub(super) fn row_simd128(q: &[u8; 128], train: &[[u8; 128]], out: &mut [f32]) {
    let qv: [v128; 16] = std::array::from_fn(|k| {
        let b = load(q, k / 2);
        if k % 2 == 0 {
            u16x8_extend_low_u8x16(b)
        } else {
            u16x8_extend_high_u8x16(b)
        }
    });
    let row = |t: &[u8; 128]| -> v128 {
        let mut acc = i32x4_splat(0);
        for k in 0..8 {
            let b = load(t, k);
            let lo = i16x8_sub(qv[2 * k], u16x8_extend_low_u8x16(b));
            let hi = i16x8_sub(qv[2 * k + 1], u16x8_extend_high_u8x16(b));
            acc = i32x4_add(acc, i32x4_add(i32x4_dot_i16x8(lo, lo), i32x4_dot_i16x8(hi, hi)));
        }
        acc
    };
    let mut t4 = train.chunks_exact(4);
    let mut o4 = out.chunks_exact_mut(4);
    for (t, o) in (&mut t4).zip(&mut o4) {
        let (a, b, c, d) = (row(&t[0]), row(&t[1]), row(&t[2]), row(&t[3]));
        // The same two interleave-and-add levels as the x86 reduction.
        let ab = i32x4_add(i32x4_shuffle::<0, 4, 1, 5>(a, b), i32x4_shuffle::<2, 6, 3, 7>(a, b));
        let cd = i32x4_add(i32x4_shuffle::<0, 4, 1, 5>(c, d), i32x4_shuffle::<2, 6, 3, 7>(c, d));
        let s = i32x4_add(i64x2_shuffle::<0, 2>(ab, cd), i64x2_shuffle::<1, 3>(ab, cd));
        let r = f32x4_sqrt(f32x4_convert_i32x4(s));
        o[0] = f32x4_extract_lane::<0>(r);
        o[1] = f32x4_extract_lane::<1>(r);
        o[2] = f32x4_extract_lane::<2>(r);
        o[3] = f32x4_extract_lane::<3>(r);
    }
    super::scalar::row_generic(q, t4.remainder(), o4.into_remainder());
}
