//! The tracker's window kernels in wasm SIMD (simd128), bit-identical to the
//! scalar ones: the AVX2 kernels' algorithm on 128-bit vectors, with
//! `i8x16.swizzle` building the (I(c), I(c+1)) pairs and `i32x4.dot_i16x8_s`
//! doing the multiply-adds (layout and exactness rule in [`super::wide`]).

use super::wide::{self, Acc, Patch, Row, Win16};
use super::{Deriv, Kernels, Level, WIN};
use core::arch::wasm32::*;

pub struct Simd128;

/// One row as three vectors: positions 0..8, 8..16, 16..24.
type Parts = [v128; 3];

/// Pairs of one source row: [a0, b0, a1, b1, ta, tb], where packing a_k with
/// b_k gives part k of the row layout (a0 = columns 0 4 1 5, b0 = 2 6 3 7,
/// a1 = 8 12 9 13, b1 = 10 14 11 15, ta = 16..19, tb = 20..23).
type Pairs = [v128; 6];

const Z: u8 = 0x80; // out of range: swizzle writes 0
const MA: v128 = u8x16(0, Z, 1, Z, 4, Z, 5, Z, 1, Z, 2, Z, 5, Z, 6, Z);
const MB: v128 = u8x16(2, Z, 3, Z, 6, Z, 7, Z, 3, Z, 4, Z, 7, Z, 8, Z);
const MTA: v128 = u8x16(0, Z, 1, Z, 1, Z, 2, Z, 2, Z, 3, Z, 3, Z, 4, Z);
const MTB: v128 = u8x16(4, Z, 5, Z, 5, Z, 6, Z, 6, Z, 7, Z, 7, Z, 8, Z);
/// (e, e+1), (e+4, e+5), (e+1, e+2), (e+5, e+6) of 8 loaded i16.
const M16: v128 = u8x16(0, 1, 2, 3, 8, 9, 10, 11, 2, 3, 4, 5, 10, 11, 12, 13);
/// (e, e+1) … (e+3, e+4).
const MT16: v128 = u8x16(0, 1, 2, 3, 2, 3, 4, 5, 4, 5, 6, 7, 6, 7, 8, 9);

/// Byte pairs of an 8-bit row at `p` (reads `p[0..32]`), zero-extended.
///
/// # Safety
/// `p[0..32]` must be readable.
#[inline(always)]
unsafe fn pairs_u8(p: *const u8) -> Pairs {
    // SAFETY: the caller vouches for p[0..32]; wasm loads need no alignment.
    let (s0, s1, s2) = unsafe {
        (v128_load(p as *const v128), v128_load(p.add(8) as *const v128), v128_load(p.add(16) as *const v128))
    };
    [
        i8x16_swizzle(s0, MA),
        i8x16_swizzle(s0, MB),
        i8x16_swizzle(s1, MA),
        i8x16_swizzle(s1, MB),
        i8x16_swizzle(s2, MTA),
        i8x16_swizzle(s2, MTB),
    ]
}

/// Element pairs of a 16-bit row at `p` (reads `p[0..28]`).
///
/// # Safety
/// `p[0..28]` must be readable.
#[inline(always)]
unsafe fn pairs_i16(p: *const i16) -> Pairs {
    // SAFETY: k ≤ 20 below, so each 8-element load ends within p[0..28],
    // which the caller vouches for; wasm loads need no alignment.
    let at = |k: usize| unsafe { v128_load(p.add(k) as *const v128) };
    [
        i8x16_swizzle(at(0), M16),
        i8x16_swizzle(at(2), M16),
        i8x16_swizzle(at(8), M16),
        i8x16_swizzle(at(10), M16),
        i8x16_swizzle(at(16), MT16),
        i8x16_swizzle(at(20), MT16),
    ]
}

/// `(top·(w00, w01) + bottom·(w10, w11) + 2^(s−1)) >> s`, packed to the row
/// layout.
#[inline(always)]
fn blend(top: &Pairs, bot: &Pairs, wt: v128, wb: v128, s: u32) -> Parts {
    let round = i32x4_splat(1 << (s - 1));
    let mix =
        |k: usize| i32x4_shr(i32x4_add(i32x4_add(i32x4_dot_i16x8(top[k], wt), i32x4_dot_i16x8(bot[k], wb)), round), s);
    [i16x8_narrow_i32x4(mix(0), mix(1)), i16x8_narrow_i32x4(mix(2), mix(3)), i16x8_narrow_i32x4(mix(4), mix(5))]
}

#[inline(always)]
fn weight_pairs(w: &[i32; 4]) -> (v128, v128) {
    (i32x4_splat((w[1] << 16) | (w[0] & 0xffff)), i32x4_splat((w[3] << 16) | (w[2] & 0xffff)))
}

#[inline(always)]
fn load(row: &Row) -> Parts {
    let p = row.0.as_ptr();
    // SAFETY: a Row holds 32 i16; the loads read positions 0..24.
    unsafe { [v128_load(p as *const v128), v128_load(p.add(8) as *const v128), v128_load(p.add(16) as *const v128)] }
}

#[inline(always)]
fn store(row: &mut Row, v: Parts) {
    let p = row.0.as_mut_ptr();
    // SAFETY: as in `load`.
    unsafe {
        v128_store(p as *mut v128, v[0]);
        v128_store(p.add(8) as *mut v128, v[1]);
        v128_store(p.add(16) as *mut v128, v[2]);
    }
}

/// Running i32 sums of pairwise products, per part.
#[derive(Clone, Copy)]
struct Sum([v128; 3]);

impl Sum {
    fn new() -> Sum {
        Sum([i32x4_splat(0); 3])
    }

    #[inline(always)]
    fn add(&mut self, a: &Parts, b: &Parts) {
        for k in 0..3 {
            self.0[k] = i32x4_add(self.0[k], i32x4_dot_i16x8(a[k], b[k]));
        }
    }

    fn acc(&self) -> Acc {
        let lane = |v: v128| {
            [
                i32x4_extract_lane::<0>(v),
                i32x4_extract_lane::<1>(v),
                i32x4_extract_lane::<2>(v),
                i32x4_extract_lane::<3>(v),
            ]
        };
        let (b0, b1) = (lane(self.0[0]), lane(self.0[1]));
        Acc { blocks: [b0[0], b0[1], b0[2], b0[3], b1[0], b1[1], b1[2], b1[3]], tail: lane(self.0[2]) }
    }
}

fn abs(v: &Parts) -> Parts {
    [i16x8_abs(v[0]), i16x8_abs(v[1]), i16x8_abs(v[2])]
}

fn load_patch(prev: &Level, deriv: &Deriv, ix: i32, iy: i32, w: &[i32; 4], p: &mut Patch) -> (f32, f32, f32) {
    let base = prev.offset(ix, iy);
    assert!(base + WIN * prev.stride + 32 <= prev.padded.len());
    let (wt, wb) = weight_pairs(w);
    let src = prev.padded[base..].as_ptr();
    // SAFETY: rows 0 ..= 21 of the window, whose last 32 bytes end
    // inside `prev.padded` (asserted above).
    let mut top = unsafe { pairs_u8(src) };
    for y in 0..WIN {
        // SAFETY: row y + 1 ≤ 21 of the same window (see above).
        let bot = unsafe { pairs_u8(src.add((y + 1) * prev.stride)) };
        store(&mut p.t[y], blend(&top, &bot, wt, wb, 9));
        top = bot;
    }
    let dbase = deriv.offset(ix, iy);
    assert!(dbase + WIN * deriv.stride + 28 <= deriv.ix.len() && deriv.ix.len() == deriv.iy.len());
    // Columns 21..23 of X and Y are zeroed so every product with them vanishes.
    let keep = i16x8(-1, -1, -1, -1, -1, 0, 0, 0);
    for (plane, out, mag) in [(&deriv.ix, &mut p.x, &mut p.ax), (&deriv.iy, &mut p.y, &mut p.ay)] {
        let src = plane[dbase..].as_ptr();
        // SAFETY: rows 0 ..= 21, whose last 28 elements end inside
        // the plane (asserted above).
        let mut top = unsafe { pairs_i16(src) };
        for y in 0..WIN {
            // SAFETY: row y + 1 ≤ 21 of the same window (see above).
            let bot = unsafe { pairs_i16(src.add((y + 1) * deriv.stride)) };
            let mut v = blend(&top, &bot, wt, wb, 14);
            v[2] = v128_and(v[2], keep);
            store(&mut out[y], v);
            store(&mut mag[y], abs(&v));
            top = bot;
        }
    }
    // X², Y² are their own bounds; XY is bounded by |X||Y|.
    let (mut xx, mut yy, mut xy, mut bxy) = (Sum::new(), Sum::new(), Sum::new(), Sum::new());
    for y in 0..WIN {
        let (x, g) = (load(&p.x[y]), load(&p.y[y]));
        xx.add(&x, &x);
        yy.add(&g, &g);
        xy.add(&x, &g);
        bxy.add(&load(&p.ax[y]), &load(&p.ay[y]));
    }
    let (xx, xy, yy, bxy) = (xx.acc(), xy.acc(), yy.acc(), bxy.acc());
    (
        wide::tensor_sum(&xx, &xx, &p.x, &p.x),
        wide::tensor_sum(&xy, &bxy, &p.x, &p.y),
        wide::tensor_sum(&yy, &yy, &p.y, &p.y),
    )
}

/// Interpolates the next-level window at `(jx, jy)` row by row into `each`
/// (row index, J − T).
#[inline(always)]
fn for_each_difference(next: &Level, jx: i32, jy: i32, w: &[i32; 4], t: &Win16, mut each: impl FnMut(usize, Parts)) {
    let base = next.offset(jx, jy);
    assert!(base + WIN * next.stride + 32 <= next.padded.len());
    let (wt, wb) = weight_pairs(w);
    let src = next.padded[base..].as_ptr();
    // SAFETY: rows 0 ..= 21 of the window, whose last 32 bytes end
    // inside `next.padded` (asserted above).
    let mut top = unsafe { pairs_u8(src) };
    for (y, trow) in t.iter().enumerate() {
        // SAFETY: row y + 1 ≤ 21 of the same window (see above).
        let bot = unsafe { pairs_u8(src.add((y + 1) * next.stride)) };
        let j = blend(&top, &bot, wt, wb, 9);
        let t = load(trow);
        each(y, [i16x8_sub(j[0], t[0]), i16x8_sub(j[1], t[1]), i16x8_sub(j[2], t[2])]);
        top = bot;
    }
}

fn mismatch(next: &Level, jx: i32, jy: i32, w: &[i32; 4], p: &mut Patch) -> (f32, f32) {
    let (mut sx, mut sy, mut bx, mut by) = (Sum::new(), Sum::new(), Sum::new(), Sum::new());
    let Patch { t, x, y, ax, ay, d } = p;
    for_each_difference(next, jx, jy, w, t, |r, dv| {
        store(&mut d[r], dv);
        sx.add(&dv, &load(&x[r]));
        sy.add(&dv, &load(&y[r]));
        let ad = abs(&dv);
        bx.add(&ad, &load(&ax[r]));
        by.add(&ad, &load(&ay[r]));
    });
    wide::finish_mismatch(p, &sx.acc(), &sy.acc(), &bx.acc(), &by.acc(), wide::mismatch_lanes_replay)
}

fn abs_diff_sum(next: &Level, jx: i32, jy: i32, w: &[i32; 4], p: &Patch) -> f32 {
    let ones = i16x8_splat(1);
    let mask: Parts = [ones, ones, i16x8(1, 1, 1, 1, 1, 0, 0, 0)];
    let mut total = Sum::new();
    for_each_difference(next, jx, jy, w, &p.t, |_, dv| total.add(&abs(&dv), &mask));
    wide::abs_diff_total(&total.acc())
}

impl Kernels for Simd128 {
    type Patch = Patch;

    #[inline(always)]
    fn load_patch(prev: &Level, deriv: &Deriv, ix: i32, iy: i32, w: &[i32; 4], p: &mut Patch) -> (f32, f32, f32) {
        load_patch(prev, deriv, ix, iy, w, p)
    }

    #[inline(always)]
    fn mismatch(next: &Level, jx: i32, jy: i32, w: &[i32; 4], p: &mut Patch) -> (f32, f32) {
        mismatch(next, jx, jy, w, p)
    }

    #[inline(always)]
    fn abs_diff_sum(next: &Level, jx: i32, jy: i32, w: &[i32; 4], p: &mut Patch) -> f32 {
        abs_diff_sum(next, jx, jy, w, p)
    }
}
