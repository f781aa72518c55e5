//! The window kernels with AVX-512 BW: only the mismatch has its own kernel;
//! the patch and the absolute differences are the AVX2 ones.

use super::super::wide::{self, Acc, Patch, Row};
use super::super::{Deriv, Kernels, Level, WIN};
use super::{mismatch_lanes_replay, window_start, Avx2};
use std::arch::x86_64::*;

/// The mismatch with AVX-512 BW: a whole window row (block part, tail and
/// the zero padding of `Row`) is one 32-lane vector, each 128-bit chunk
/// doing what the AVX2 kernel's ymm and xmm halves do in that chunk: the
/// same products, pair sums and packs, so the same integers.
pub struct Avx512;

/// `pairs_u8` as one vector: chunks 0–1 the block pairs, chunk 2 the tail
/// pairs, chunk 3 zero (reads `p[0..32]`).
///
/// # Safety
/// `p[0..32]` must be readable, and the CPU must have AVX-512 BW.
#[target_feature(enable = "avx512bw,avx512f,avx2")]
#[inline]
unsafe fn pairs_u8_512(p: *const u8) -> (__m512i, __m512i) {
    const Z: i8 = -128;
    // SAFETY: the caller vouches for p[0..32]; unaligned loads.
    let (lo, hi) = unsafe {
        (
            _mm256_loadu2_m128i(p.add(8) as *const __m128i, p as *const __m128i),
            _mm_loadu_si128(p.add(16) as *const __m128i),
        )
    };
    let hi = _mm256_castsi128_si256(hi);
    let src = _mm512_inserti64x4::<1>(_mm512_castsi256_si512(lo), hi);
    // Two shuffles of the four 128-bit chunks (chunk 3 first, as
    // `_mm512_set_epi8` takes them), 32 bytes a line.
    #[rustfmt::skip]
    let ma = _mm512_set_epi8(
        Z, Z, Z, Z, Z, Z, Z, Z, Z, Z, Z, Z, Z, Z, Z, Z, Z, 4, Z, 3, Z, 3, Z, 2, Z, 2, Z, 1, Z, 1, Z, 0,
        Z, 6, Z, 5, Z, 2, Z, 1, Z, 5, Z, 4, Z, 1, Z, 0, Z, 6, Z, 5, Z, 2, Z, 1, Z, 5, Z, 4, Z, 1, Z, 0);
    #[rustfmt::skip]
    let mb = _mm512_set_epi8(
        Z, Z, Z, Z, Z, Z, Z, Z, Z, Z, Z, Z, Z, Z, Z, Z, Z, 8, Z, 7, Z, 7, Z, 6, Z, 6, Z, 5, Z, 5, Z, 4,
        Z, 8, Z, 7, Z, 4, Z, 3, Z, 7, Z, 6, Z, 3, Z, 2, Z, 8, Z, 7, Z, 4, Z, 3, Z, 7, Z, 6, Z, 3, Z, 2);
    (_mm512_shuffle_epi8(src, ma), _mm512_shuffle_epi8(src, mb))
}

#[target_feature(enable = "avx512bw,avx512f,avx2")]
#[inline]
fn mix_512<const S: u32>(t: __m512i, b: __m512i, wt: __m512i, wb: __m512i) -> __m512i {
    let v = _mm512_add_epi32(_mm512_madd_epi16(t, wt), _mm512_madd_epi16(b, wb));
    _mm512_srai_epi32::<S>(_mm512_add_epi32(v, _mm512_set1_epi32(1i32 << (S - 1))))
}

/// Splits an i32 sum vector into `Acc`: lanes 0–7 the blocks, 8–11 the tail.
#[target_feature(enable = "avx512bw,avx512f,avx2")]
#[inline]
fn acc_512(v: __m512i) -> Acc {
    let mut lanes = [0i32; 16];
    // SAFETY: 16 i32 into a [i32; 16]; an unaligned store.
    unsafe { _mm512_storeu_si512(lanes.as_mut_ptr() as *mut _, v) };
    let mut a = Acc::default();
    a.blocks.copy_from_slice(&lanes[..8]);
    a.tail.copy_from_slice(&lanes[8..12]);
    a
}

#[target_feature(enable = "avx512bw,avx512f,avx2")]
fn mismatch_512(next: &Level, jx: i32, jy: i32, w: &[i32; 4], p: &mut Patch) -> (f32, f32) {
    let (src, stride) = window_start(next, jx, jy);
    let wt = _mm512_set1_epi32((w[1] << 16) | (w[0] & 0xffff));
    let wb = _mm512_set1_epi32((w[3] << 16) | (w[2] & 0xffff));
    // SAFETY: a Row is 32 i16, exactly the 64 bytes loaded (unaligned).
    let row = |r: &Row| unsafe { _mm512_loadu_si512(r.0.as_ptr() as *const _) };
    let zero = _mm512_setzero_si512();
    let (mut sx, mut sy, mut bx, mut by) = (zero, zero, zero, zero);
    // SAFETY: rows 0 ..= 21 of the window, whose last 32 bytes end
    // inside the padded level (`window_start` checked them).
    let mut top = unsafe { pairs_u8_512(src) };
    for y in 0..WIN {
        // SAFETY: row y + 1 ≤ 21 of the same window (see above).
        let bot = unsafe { pairs_u8_512(src.add((y + 1) * stride)) };
        // Chunk 3 mixes zeros: (0 + 2^8) >> 9 = 0, so the padding stays 0.
        let j = _mm512_packs_epi32(mix_512::<9>(top.0, bot.0, wt, wb), mix_512::<9>(top.1, bot.1, wt, wb));
        top = bot;
        let d = _mm512_sub_epi16(j, row(&p.t[y]));
        // SAFETY: the 64 bytes of the row p.d[y] (unaligned store).
        unsafe { _mm512_storeu_si512(p.d[y].0.as_mut_ptr() as *mut _, d) };
        sx = _mm512_add_epi32(sx, _mm512_madd_epi16(d, row(&p.x[y])));
        sy = _mm512_add_epi32(sy, _mm512_madd_epi16(d, row(&p.y[y])));
        let ad = _mm512_abs_epi16(d);
        bx = _mm512_add_epi32(bx, _mm512_madd_epi16(ad, row(&p.ax[y])));
        by = _mm512_add_epi32(by, _mm512_madd_epi16(ad, row(&p.ay[y])));
    }
    let (sx, sy, bx, by) = (acc_512(sx), acc_512(sy), acc_512(bx), acc_512(by));
    wide::finish_mismatch(p, &sx, &sy, &bx, &by, |p| mismatch_lanes_replay(p))
}

impl Kernels for Avx512 {
    type Patch = Patch;

    // Only the mismatch differs from the AVX2 kernels (an AVX-512 BW CPU has AVX2).
    #[inline(always)]
    fn load_patch(prev: &Level, deriv: &Deriv, ix: i32, iy: i32, w: &[i32; 4], p: &mut Patch) -> (f32, f32, f32) {
        Avx2::load_patch(prev, deriv, ix, iy, w, p)
    }

    #[inline(always)]
    fn mismatch(next: &Level, jx: i32, jy: i32, w: &[i32; 4], p: &mut Patch) -> (f32, f32) {
        // SAFETY: this kernel set is only used on AVX-512 BW CPUs (run_job
        // checks), the features the function enables.
        unsafe { mismatch_512(next, jx, jy, w, p) }
    }

    #[inline(always)]
    fn abs_diff_sum(next: &Level, jx: i32, jy: i32, w: &[i32; 4], p: &mut Patch) -> f32 {
        Avx2::abs_diff_sum(next, jx, jy, w, p)
    }
}
