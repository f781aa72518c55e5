//! The tracker's window kernels in AVX2, bit-identical to the scalar ones:
//! 16-bit windows in the layout of [`super::wide`], `vpmaddwd` for the
//! interpolation and the pair sums, exact integer sums with OpenCV's f32
//! order replayed only where a bound requires it (docs/fidelity.md §VO-2.4;
//! the layout and the exactness rule are in `wide`).

use super::wide::{self, Acc, Patch, Row, Win16};
use super::{Deriv, Kernels, Level, WIN};
use std::arch::x86_64::*;

pub struct Avx2;

/// (I(c), I(c+1)) pairs of one source row, as 32-bit lanes of two i16, in
/// the order that packs to the row layout: `a` = columns 0 4 1 5 | 8 12 9 13,
/// `b` = 2 6 3 7 | 10 14 11 15, `ta` = 16..19, `tb` = 20..23.
#[derive(Clone, Copy)]
struct Pairs {
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
unsafe fn pairs_u8(p: *const u8) -> Pairs {
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
unsafe fn pairs_i16(p: *const i16) -> Pairs {
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
fn blend<const S: i32>(top: &Pairs, bot: &Pairs, wt: __m256i, wb: __m256i) -> (__m256i, __m128i) {
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
fn weight_pairs(w: &[i32; 4]) -> (__m256i, __m256i) {
    (_mm256_set1_epi32((w[1] << 16) | (w[0] & 0xffff)), _mm256_set1_epi32((w[3] << 16) | (w[2] & 0xffff)))
}

/// Stores positions 0..16 and 16..24 of a row.
#[target_feature(enable = "avx2")]
#[inline]
fn store(row: &mut Row, lo: __m256i, tail: __m128i) {
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
fn load(row: &Row) -> (__m256i, __m128i) {
    // SAFETY: as in `store`, both aligned loads are inside the row.
    unsafe {
        (_mm256_load_si256(row.0.as_ptr() as *const __m256i), _mm_load_si128(row.0.as_ptr().add(16) as *const __m128i))
    }
}

/// Positions `at .. at + 8` of a row, `at` ≤ 24.
#[target_feature(enable = "avx2")]
#[inline]
fn load8(row: &Row, at: usize) -> __m128i {
    assert!(at <= 24);
    // SAFETY: 8 of the row's 32 i16 from `at` ≤ 24; an unaligned load.
    unsafe { _mm_loadu_si128(row.0.as_ptr().add(at) as *const __m128i) }
}

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

/// OpenCV's tensor lanes L0..L3 and tail sums S of ΣX², ΣXY and ΣY² (in
/// that order), in OpenCV's order (`wide::tensor_lanes_replay`,
/// `wide::tail_replay`), the three sums at once: each row's block products
/// as i32, converted to f32 (rounding as OpenCV's conversion does), split
/// into columns B..B+3 and B+4..B+7 and added to the lanes in column order;
/// the tail's five columns as vectors (X², XY, Y², 0) added in order.
#[target_feature(enable = "avx2")]
fn tensor_sums_replay(x: &Win16, y: &Win16) -> ([[f32; 4]; 3], [f32; 3]) {
    // Row layout positions B, B+1, .. hold columns B, B+4, B+1, B+5, ...
    let split = _mm256_setr_epi32(0, 2, 4, 6, 1, 3, 5, 7);
    let (mut lxx, mut lxy, mut lyy) = (_mm_setzero_ps(), _mm_setzero_ps(), _mm_setzero_ps());
    let mut tail = _mm_setzero_ps();
    let products =
        |a: __m256i, b: __m256i| _mm256_permutevar8x32_ps(_mm256_cvtepi32_ps(_mm256_mullo_epi32(a, b)), split);
    for (xr, yr) in x.iter().zip(y) {
        for block in [0, 8] {
            let xv = _mm256_cvtepi16_epi32(load8(xr, block));
            let yv = _mm256_cvtepi16_epi32(load8(yr, block));
            let (pxx, pxy, pyy) = (products(xv, xv), products(xv, yv), products(yv, yv));
            lxx = _mm_add_ps(_mm_add_ps(lxx, _mm256_castps256_ps128(pxx)), _mm256_extractf128_ps::<1>(pxx));
            lxy = _mm_add_ps(_mm_add_ps(lxy, _mm256_castps256_ps128(pxy)), _mm256_extractf128_ps::<1>(pxy));
            lyy = _mm_add_ps(_mm_add_ps(lyy, _mm256_castps256_ps128(pyy)), _mm256_extractf128_ps::<1>(pyy));
        }
        // Columns 16..23 (21..23 are scratch, never added).
        let xv = _mm256_cvtepi16_epi32(load8(xr, 16));
        let yv = _mm256_cvtepi16_epi32(load8(yr, 16));
        let f = |a: __m256i, b: __m256i| _mm256_cvtepi32_ps(_mm256_mullo_epi32(a, b));
        let (fxx, fxy, fyy) = (f(xv, xv), f(xv, yv), f(yv, yv));
        // Transposed: term vector c = (X²(c), XY(c), Y²(c), 0).
        let zero = _mm256_setzero_ps();
        let a = _mm256_unpacklo_ps(fxx, fxy); // xx0 xy0 xx1 xy1 | xx4 xy4 ..
        let b = _mm256_unpacklo_ps(fyy, zero); // yy0 0 yy1 0 | yy4 0 ..
        let c = _mm256_unpackhi_ps(fxx, fxy); // xx2 xy2 xx3 xy3 | ..
        let d = _mm256_unpackhi_ps(fyy, zero);
        let t0 = _mm256_shuffle_ps::<0b01_00_01_00>(a, b);
        let t1 = _mm256_shuffle_ps::<0b11_10_11_10>(a, b);
        let t2 = _mm256_shuffle_ps::<0b01_00_01_00>(c, d);
        let t3 = _mm256_shuffle_ps::<0b11_10_11_10>(c, d);
        for t in [t0, t1, t2, t3] {
            tail = _mm_add_ps(tail, _mm256_castps256_ps128(t));
        }
        tail = _mm_add_ps(tail, _mm256_extractf128_ps::<1>(t0));
    }
    let (mut out, mut t) = ([[0f32; 4]; 3], [0f32; 4]);
    // SAFETY: each store writes 4 f32 into a [f32; 4]; unaligned stores.
    unsafe {
        for (o, l) in out.iter_mut().zip([lxx, lxy, lyy]) {
            _mm_storeu_ps(o.as_mut_ptr(), l);
        }
        _mm_storeu_ps(t.as_mut_ptr(), tail);
    }
    (out, [t[0], t[1], t[2]])
}

/// OpenCV's T0..T3 (= P + Q: X of groups 0+2, Y of 0+2, X of 1+3, Y of
/// 1+3) replayed from the stored J − T, for when a lanes bound fails.
#[target_feature(enable = "avx2")]
pub(super) fn mismatch_lanes_replay(p: &Patch) -> [f32; 4] {
    let (mut acc_p, mut acc_q) = (_mm_setzero_ps(), _mm_setzero_ps());
    for y in 0..WIN {
        let (d, _) = load(&p.d[y]);
        let (x, _) = load(&p.x[y]);
        let (g, _) = load(&p.y[y]);
        let ux = _mm256_madd_epi16(d, x);
        let uy = _mm256_madd_epi16(d, g);
        // Per block: P += (uX(B), uY(B), uX(B+1), uY(B+1)), Q += the next two.
        let pv = _mm256_cvtepi32_ps(_mm256_unpacklo_epi32(ux, uy));
        let qv = _mm256_cvtepi32_ps(_mm256_unpackhi_epi32(ux, uy));
        acc_p = _mm_add_ps(acc_p, _mm256_castps256_ps128(pv));
        acc_q = _mm_add_ps(acc_q, _mm256_castps256_ps128(qv));
        acc_p = _mm_add_ps(acc_p, _mm256_extractf128_ps::<1>(pv));
        acc_q = _mm_add_ps(acc_q, _mm256_extractf128_ps::<1>(qv));
    }
    let mut t = [0f32; 4];
    // SAFETY: 4 f32 into a [f32; 4]; an unaligned store.
    unsafe { _mm_storeu_ps(t.as_mut_ptr(), _mm_add_ps(acc_p, acc_q)) };
    t
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
