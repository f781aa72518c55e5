//! One window row with AVX2: the (I(c), I(c+1)) pairs of a source row, their
//! bilinear blend packed to the row layout of `wide`, and the row's loads and
//! stores; what the AVX2 kernels, the replays and the AVX-512 kernel share.

use super::super::wide::Row;
use std::arch::x86_64::*;

/// (I(c), I(c+1)) pairs of one source row, as 32-bit lanes of two i16, in
/// the order that packs to the row layout: `a` = columns 0 4 1 5 | 8 12 9 13,
/// `b` = 2 6 3 7 | 10 14 11 15, `ta` = 16..19, `tb` = 20..23.
#[derive(Clone, Copy)]
pub(super) struct Pairs {
    a: __m256i,
    b: __m256i,
    ta: __m128i,
    tb: __m128i,
}

/// Byte pairs of an 8-bit row at `p` (reads `p[0..32]`), zero-extended.
///
/// # Safety
/// `p[0..32]` must be readable, and the CPU must have AVX2.
#[target_feature(enable = "avx2")]
#[inline]
pub(super) unsafe fn pairs_u8(p: *const u8) -> Pairs {
    const Z: i8 = -128;
    // SAFETY: the caller vouches for p[0..32]; unaligned loads.
    let (src, tail) = unsafe {
        (
            _mm256_loadu2_m128i(p.add(8) as *const __m128i, p as *const __m128i),
            _mm_loadu_si128(p.add(16) as *const __m128i),
        )
    };
    #[rustfmt::skip]
    let ma = _mm256_setr_epi8(
        0, Z, 1, Z, 4, Z, 5, Z, 1, Z, 2, Z, 5, Z, 6, Z,
        0, Z, 1, Z, 4, Z, 5, Z, 1, Z, 2, Z, 5, Z, 6, Z);
    #[rustfmt::skip]
    let mb = _mm256_setr_epi8(
        2, Z, 3, Z, 6, Z, 7, Z, 3, Z, 4, Z, 7, Z, 8, Z,
        2, Z, 3, Z, 6, Z, 7, Z, 3, Z, 4, Z, 7, Z, 8, Z);
    let mta = _mm_setr_epi8(0, Z, 1, Z, 1, Z, 2, Z, 2, Z, 3, Z, 3, Z, 4, Z);
    let mtb = _mm_setr_epi8(4, Z, 5, Z, 5, Z, 6, Z, 6, Z, 7, Z, 7, Z, 8, Z);
    Pairs {
        a: _mm256_shuffle_epi8(src, ma),
        b: _mm256_shuffle_epi8(src, mb),
        ta: _mm_shuffle_epi8(tail, mta),
        tb: _mm_shuffle_epi8(tail, mtb),
    }
}

/// Element pairs of a 16-bit row at `p` (reads `p[0..28]`).
///
/// # Safety
/// `p[0..28]` must be readable, and the CPU must have AVX2.
#[target_feature(enable = "avx2")]
#[inline]
pub(super) unsafe fn pairs_i16(p: *const i16) -> Pairs {
    // (e, e+1), (e+4, e+5), (e+1, e+2), (e+5, e+6) of 8 loaded elements; the
    // second half of each block is the same pattern loaded 2 further on.
    #[rustfmt::skip]
    let m = _mm256_setr_epi8(
        0, 1, 2, 3, 8, 9, 10, 11, 2, 3, 4, 5, 10, 11, 12, 13,
        0, 1, 2, 3, 8, 9, 10, 11, 2, 3, 4, 5, 10, 11, 12, 13);
    let mt = _mm_setr_epi8(0, 1, 2, 3, 2, 3, 4, 5, 4, 5, 6, 7, 6, 7, 8, 9);
    // SAFETY: the caller vouches for p[0..28]; the last load, 8 elements
    // from p + 20, ends there. Unaligned loads.
    let (a, b, ta, tb) = unsafe {
        (
            _mm256_loadu2_m128i(p.add(8) as *const __m128i, p as *const __m128i),
            _mm256_loadu2_m128i(p.add(10) as *const __m128i, p.add(2) as *const __m128i),
            _mm_loadu_si128(p.add(16) as *const __m128i),
            _mm_loadu_si128(p.add(20) as *const __m128i),
        )
    };
    Pairs {
        a: _mm256_shuffle_epi8(a, m),
        b: _mm256_shuffle_epi8(b, m),
        ta: _mm_shuffle_epi8(ta, mt),
        tb: _mm_shuffle_epi8(tb, mt),
    }
}

/// One interpolated output row: `(top·(w00, w01) + bottom·(w10, w11) +
/// 2^(S−1)) >> S`, packed to i16 in the row layout (block part, tail part).
#[target_feature(enable = "avx2")]
#[inline]
pub(super) fn blend<const S: i32>(top: &Pairs, bot: &Pairs, wt: __m256i, wb: __m256i) -> (__m256i, __m128i) {
    (
        _mm256_packs_epi32(mix::<S>(top.a, bot.a, wt, wb), mix::<S>(top.b, bot.b, wt, wb)),
        _mm_packs_epi32(
            mix4::<S>(top.ta, bot.ta, _mm256_castsi256_si128(wt), _mm256_castsi256_si128(wb)),
            mix4::<S>(top.tb, bot.tb, _mm256_castsi256_si128(wt), _mm256_castsi256_si128(wb)),
        ),
    )
}

#[target_feature(enable = "avx2")]
#[inline]
fn mix<const S: i32>(t: __m256i, b: __m256i, wt: __m256i, wb: __m256i) -> __m256i {
    let v = _mm256_add_epi32(_mm256_madd_epi16(t, wt), _mm256_madd_epi16(b, wb));
    _mm256_srai_epi32::<S>(_mm256_add_epi32(v, _mm256_set1_epi32(1 << (S - 1))))
}

#[target_feature(enable = "avx2")]
#[inline]
fn mix4<const S: i32>(t: __m128i, b: __m128i, wt: __m128i, wb: __m128i) -> __m128i {
    let v = _mm_add_epi32(_mm_madd_epi16(t, wt), _mm_madd_epi16(b, wb));
    _mm_srai_epi32::<S>(_mm_add_epi32(v, _mm_set1_epi32(1 << (S - 1))))
}

/// The two weight pairs as i16 lanes: (w00, w01) for the top row, (w10, w11)
/// for the bottom one (all ≤ 16384).
#[target_feature(enable = "avx2")]
#[inline]
pub(super) fn weight_pairs(w: &[i32; 4]) -> (__m256i, __m256i) {
    (_mm256_set1_epi32((w[1] << 16) | (w[0] & 0xffff)), _mm256_set1_epi32((w[3] << 16) | (w[2] & 0xffff)))
}

/// Stores positions 0..16 and 16..24 of a row.
#[target_feature(enable = "avx2")]
#[inline]
pub(super) fn store(row: &mut Row, lo: __m256i, tail: __m128i) {
    // SAFETY: a Row is 32 i16 aligned to 32 bytes, so both aligned stores
    // (bytes 0..32 and 32..48) are inside it.
    unsafe {
        _mm256_store_si256(row.0.as_mut_ptr() as *mut __m256i, lo);
        _mm_store_si128(row.0.as_mut_ptr().add(16) as *mut __m128i, tail);
    }
}

/// Loads positions 0..16 and 16..24 of a row.
#[target_feature(enable = "avx2")]
#[inline]
pub(super) fn load(row: &Row) -> (__m256i, __m128i) {
    // SAFETY: as in `store`, both aligned loads are inside the row.
    unsafe {
        (_mm256_load_si256(row.0.as_ptr() as *const __m256i), _mm_load_si128(row.0.as_ptr().add(16) as *const __m128i))
    }
}

/// Positions `at .. at + 8` of a row, `at` ≤ 24.
#[target_feature(enable = "avx2")]
#[inline]
pub(super) fn load8(row: &Row, at: usize) -> __m128i {
    assert!(at <= 24);
    // SAFETY: 8 of the row's 32 i16 from `at` ≤ 24; an unaligned load.
    unsafe { _mm_loadu_si128(row.0.as_ptr().add(at) as *const __m128i) }
}
