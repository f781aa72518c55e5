//! The separable 26-neighbour test of `x86.rs` with WebAssembly SIMD, four
//! lanes: per-column maximum and minimum over the nine rows, then over three
//! columns, then the threshold and comparison. `pmax`/`pmin` are one
//! instruction each and equal `max`/`min` here: no NaN arises from 8-bit
//! images, and the ±0 ties where they differ cannot decide a test whose value
//! lies beyond the threshold (docs/fidelity.md §SIFT-6).

use super::super::num::{load4 as load, store4 as store};
use core::arch::wasm32::*;

/// Returns the first column not examined (the scalar tail starts there).
/// Needs every row to extend one pixel past `cols.end` and `cols.start >= 1`.
pub fn row_extrema_simd128(
    rows: &[&[f32]; 9],
    thr: f32,
    cols: std::ops::Range<usize>,
    out: &mut Vec<usize>,
    col_max: &mut Vec<f32>,
    col_min: &mut Vec<f32>,
) -> usize {
    let w = cols.end + 1;
    col_max.resize(w, 0.0);
    col_min.resize(w, 0.0);
    let mut x = cols.start - 1;
    while x + 4 <= w {
        let first = load(rows[0], x);
        let (mut mx, mut mn) = (first, first);
        for row in &rows[1..] {
            let s = load(row, x);
            mx = f32x4_pmax(mx, s);
            mn = f32x4_pmin(mn, s);
        }
        store(col_max, x, mx);
        store(col_min, x, mn);
        x += 4;
    }
    for x in x..w {
        col_max[x] = rows.iter().map(|r| r[x]).fold(f32::NEG_INFINITY, |a, b| if b > a { b } else { a });
        col_min[x] = rows.iter().map(|r| r[x]).fold(f32::INFINITY, |a, b| if b < a { b } else { a });
    }
    let (hi, lo) = (f32x4_splat(thr), f32x4_splat(-thr));
    let mut x = cols.start;
    while x + 4 <= cols.end {
        let v = load(rows[4], x);
        let (pos, neg) = (f32x4_gt(v, hi), f32x4_lt(v, lo));
        if v128_any_true(v128_or(pos, neg)) {
            let mx = f32x4_pmax(f32x4_pmax(load(col_max, x - 1), load(col_max, x)), load(col_max, x + 1));
            let mn = f32x4_pmin(f32x4_pmin(load(col_min, x - 1), load(col_min, x)), load(col_min, x + 1));
            let hit = v128_or(v128_and(pos, f32x4_ge(v, mx)), v128_and(neg, f32x4_le(v, mn)));
            let mut mask = i32x4_bitmask(hit) as u32;
            while mask != 0 {
                out.push(x + mask.trailing_zeros() as usize);
                mask &= mask - 1;
            }
        }
        x += 4;
    }
    x
}
