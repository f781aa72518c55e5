//! The tracker's window kernels in AVX2, bit-identical to the scalar ones:
//! 16-bit windows in the layout of [`super::wide`], `vpmaddwd` for the
//! interpolation and the pair sums, exact integer sums with OpenCV's f32
//! order replayed only where a bound requires it (docs/fidelity.md §VO-2.4;
//! the layout and the exactness rule are in `wide`).
//!
//! This file holds the AVX2 kernels; beside it, `x86/rows.rs` loads, blends
//! and stores one window row, `x86/replay.rs` replays OpenCV's f32 order where
//! a bound fails, and `x86/avx512.rs` is the AVX-512 BW mismatch.

use super::wide::{self, Acc, Patch, Win16};
use super::{Deriv, Kernels, Level, WIN};
use rows::{blend, load, pairs_i16, pairs_u8, store, weight_pairs};
use std::arch::x86_64::*;

mod avx512;
mod replay;
mod rows;

pub use avx512::Avx512;
pub(super) use replay::mismatch_lanes_replay;
use replay::tensor_sums_replay;

pub struct Avx2;

/// Interpolates the 21 rows of an 8-bit level window at `p` into `out`.
///
/// # Safety
/// 32 bytes must be readable at `p + y·stride` for y = 0..=21, and the CPU
/// must have AVX2.
#[target_feature(enable = "avx2")]
#[inline]
unsafe fn warp_u8(p: *const u8, stride: usize, w: &[i32; 4], out: &mut Win16) {
    let (wt, wb) = weight_pairs(w);
    // SAFETY: row 0; the caller vouches for rows 0 ..= 21.
    let mut top = unsafe { pairs_u8(p) };
    for (y, row) in out.iter_mut().enumerate() {
        // SAFETY: row y + 1 ≤ 21 of the same window (see above).
        let bot = unsafe { pairs_u8(p.add((y + 1) * stride)) };
        let (lo, tail) = blend::<9>(&top, &bot, wt, wb);
        store(row, lo, tail);
        top = bot;
    }
}

/// The same for a 16-bit derivative plane; columns 21..23 are zeroed so that
/// every product with them vanishes.
///
/// # Safety
/// 28 elements must be readable at `p + y·stride` for y = 0..=21, and the
/// CPU must have AVX2.
#[target_feature(enable = "avx2")]
#[inline]
unsafe fn warp_i16(p: *const i16, stride: usize, w: &[i32; 4], out: &mut Win16, abs: &mut Win16) {
    let (wt, wb) = weight_pairs(w);
    let keep = _mm_setr_epi16(-1, -1, -1, -1, -1, 0, 0, 0);
    // SAFETY: row 0; the caller vouches for rows 0 ..= 21.
    let mut top = unsafe { pairs_i16(p) };
    for (y, (row, arow)) in out.iter_mut().zip(abs.iter_mut()).enumerate() {
        // SAFETY: row y + 1 ≤ 21 of the same window (see above).
        let bot = unsafe { pairs_i16(p.add((y + 1) * stride)) };
        let (lo, tail) = blend::<14>(&top, &bot, wt, wb);
        let tail = _mm_and_si128(tail, keep);
        store(row, lo, tail);
        store(arow, _mm256_abs_epi16(lo), _mm_abs_epi16(tail));
        top = bot;
    }
}

/// Running i32 sums of pairwise products of rows (block part, tail part).
struct Sum(__m256i, __m128i);

impl Sum {
    #[target_feature(enable = "avx2")]
    #[inline]
    fn new() -> Sum {
        Sum(_mm256_setzero_si256(), _mm_setzero_si128())
    }

    #[target_feature(enable = "avx2")]
    #[inline]
    fn add(&mut self, a: (__m256i, __m128i), b: (__m256i, __m128i)) {
        self.0 = _mm256_add_epi32(self.0, _mm256_madd_epi16(a.0, b.0));
        self.1 = _mm_add_epi32(self.1, _mm_madd_epi16(a.1, b.1));
    }

    #[target_feature(enable = "avx2")]
    #[inline]
    fn acc(&self) -> Acc {
        let mut a = Acc::default();
        // SAFETY: `blocks` holds 8 i32 (32 bytes), `tail` 4 (16 bytes);
        // unaligned stores.
        unsafe {
            _mm256_storeu_si256(a.blocks.as_mut_ptr() as *mut __m256i, self.0);
            _mm_storeu_si128(a.tail.as_mut_ptr() as *mut __m128i, self.1);
        }
        a
    }
}

#[target_feature(enable = "avx2")]
fn load_patch(prev: &Level, deriv: &Deriv, ix: i32, iy: i32, w: &[i32; 4], p: &mut Patch) -> (f32, f32, f32) {
    let base = prev.offset(ix, iy);
    assert!(base + WIN * prev.stride + 32 <= prev.padded.len());
    // SAFETY: row 21 of the window starts at base + 21·stride and its 32
    // bytes end inside the padded level (asserted just above).
    unsafe { warp_u8(prev.padded[base..].as_ptr(), prev.stride, w, &mut p.t) };
    let dbase = deriv.offset(ix, iy);
    assert!(dbase + WIN * deriv.stride + 28 <= deriv.ix.len() && deriv.ix.len() == deriv.iy.len());
    // SAFETY: likewise, 28 elements of row 21 end inside each plane.
    unsafe { warp_i16(deriv.ix[dbase..].as_ptr(), deriv.stride, w, &mut p.x, &mut p.ax) };
    // SAFETY: as for the X plane.
    unsafe { warp_i16(deriv.iy[dbase..].as_ptr(), deriv.stride, w, &mut p.y, &mut p.ay) };

    // X², Y² are their own bounds; XY is bounded by |X||Y|.
    let (mut xx, mut yy, mut xy, mut bxy) = (Sum::new(), Sum::new(), Sum::new(), Sum::new());
    for y in 0..WIN {
        let (x, g) = (load(&p.x[y]), load(&p.y[y]));
        xx.add(x, x);
        yy.add(g, g);
        xy.add(x, g);
        bxy.add(load(&p.ax[y]), load(&p.ay[y]));
    }
    let (xx, xy, yy, bxy) = (xx.acc(), xy.acc(), yy.acc(), bxy.acc());
    let lanes_exact = xx.groups_exact() && bxy.groups_exact() && yy.groups_exact();
    let tails_exact = xx.tail_exact() && bxy.tail_exact() && yy.tail_exact();
    if lanes_exact && tails_exact {
        return (
            wide::tensor_sum(&xx, &xx, &p.x, &p.x),
            wide::tensor_sum(&xy, &bxy, &p.x, &p.y),
            wide::tensor_sum(&yy, &yy, &p.y, &p.y),
        );
    }
    // Replayed, a tensor sum was a chain of 336 + 105 dependent f32 adds;
    // the three replayed together in vectors run their chains side by side.
    // Where a bound holds the replay equals the exact integer anyway.
    let (lanes, tails) = tensor_sums_replay(&p.x, &p.y);
    let sum = |k: usize| {
        let l = lanes[k];
        tails[k] + ((l[0] + l[2]) + (l[1] + l[3]))
    };
    (sum(0), sum(1), sum(2))
}

/// The first byte of the next image's window at (jx, jy) and the level's
/// stride, with the one bounds check the kernels' raw reads rely on: rows
/// 0 ..= 21 of the window, whose last 32 bytes end inside the padded level.
fn window_start(next: &Level, jx: i32, jy: i32) -> (*const u8, usize) {
    let base = next.offset(jx, jy);
    assert!(base + WIN * next.stride + 32 <= next.padded.len());
    (next.padded[base..].as_ptr(), next.stride)
}

/// The next image's window at (jx, jy), row by row: each row y of 0..21
/// bilinearly warped from rows y and y + 1 (`blend`, scale 2^-9), handed to
/// `row` with its index.
#[target_feature(enable = "avx2")]
#[inline]
fn warped_rows(next: &Level, jx: i32, jy: i32, w: &[i32; 4], mut row: impl FnMut(usize, (__m256i, __m128i))) {
    let (src, stride) = window_start(next, jx, jy);
    let (wt, wb) = weight_pairs(w);
    // SAFETY: row 0 of the window (`window_start` checked rows 0 ..= 21).
    let mut top = unsafe { pairs_u8(src) };
    for y in 0..WIN {
        // SAFETY: row y + 1 ≤ 21 of the same window.
        let bot = unsafe { pairs_u8(src.add((y + 1) * stride)) };
        row(y, blend::<9>(&top, &bot, wt, wb));
        top = bot;
    }
}

#[target_feature(enable = "avx2")]
fn mismatch(next: &Level, jx: i32, jy: i32, w: &[i32; 4], p: &mut Patch) -> (f32, f32) {
    let (mut sx, mut sy, mut bx, mut by) = (Sum::new(), Sum::new(), Sum::new(), Sum::new());
    warped_rows(next, jx, jy, w, |y, (j, tj)| {
        let (t, tt) = load(&p.t[y]);
        let d = (_mm256_sub_epi16(j, t), _mm_sub_epi16(tj, tt));
        store(&mut p.d[y], d.0, d.1);
        sx.add(d, load(&p.x[y]));
        sy.add(d, load(&p.y[y]));
    });
    // The bounds in a second pass over the stored differences: in the first
    // their two accumulators would not fit in the 16 registers beside the
    // others, and one would go through the stack every row. Integer sums, so
    // the order is free.
    for y in 0..WIN {
        let d = load(&p.d[y]);
        let ad = (_mm256_abs_epi16(d.0), _mm_abs_epi16(d.1));
        bx.add(ad, load(&p.ax[y]));
        by.add(ad, load(&p.ay[y]));
    }
    let (sx, sy, bx, by) = (sx.acc(), sy.acc(), bx.acc(), by.acc());
    wide::finish_mismatch(p, &sx, &sy, &bx, &by, |p| mismatch_lanes_replay(p))
}

#[target_feature(enable = "avx2")]
fn abs_diff_sum(next: &Level, jx: i32, jy: i32, w: &[i32; 4], p: &Patch) -> f32 {
    let ones = _mm256_set1_epi16(1);
    let tail_ones = _mm_setr_epi16(1, 1, 1, 1, 1, 0, 0, 0);
    let mut total = Sum::new();
    warped_rows(next, jx, jy, w, |y, (j, tj)| {
        let (t, tt) = load(&p.t[y]);
        let ad = (_mm256_abs_epi16(_mm256_sub_epi16(j, t)), _mm_abs_epi16(_mm_sub_epi16(tj, tt)));
        total.add(ad, (ones, tail_ones));
    });
    wide::abs_diff_total(&total.acc())
}

impl Kernels for Avx2 {
    type Patch = Patch;

    #[inline(always)]
    fn load_patch(prev: &Level, deriv: &Deriv, ix: i32, iy: i32, w: &[i32; 4], p: &mut Patch) -> (f32, f32, f32) {
        // SAFETY: this kernel set is only used on AVX2 CPUs (run_job checks),
        // the feature the function enables.
        unsafe { load_patch(prev, deriv, ix, iy, w, p) }
    }

    #[inline(always)]
    fn mismatch(next: &Level, jx: i32, jy: i32, w: &[i32; 4], p: &mut Patch) -> (f32, f32) {
        // SAFETY: only used on AVX2 CPUs, as for `load_patch`.
        unsafe { mismatch(next, jx, jy, w, p) }
    }

    #[inline(always)]
    fn abs_diff_sum(next: &Level, jx: i32, jy: i32, w: &[i32; 4], p: &mut Patch) -> f32 {
        // SAFETY: only used on AVX2 CPUs, as for `load_patch`.
        unsafe { abs_diff_sum(next, jx, jy, w, p) }
    }
}
