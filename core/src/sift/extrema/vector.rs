//! The 26-neighbour test of a scan row with vectors ([`Lanes`]: AVX-512,
//! AVX2 or SIMD128): v ≥ all 26 neighbours ⟺ v ≥ the maximum of the 3×3×3
//! block (v itself included), and that maximum is separable: first per
//! column over the nine rows (three layers × three rows), then over three
//! columns. That is 10 max and 10 min per pixel instead of 26 of each, and
//! the threshold and both comparisons are taken without a branch but the
//! rare hit (docs/fidelity.md §SIFT-6). The result is
//! [`super::row_extrema_generic`]'s, column for column.
//!
//! The separable test replaced one that took the threshold first, then the
//! 8 neighbours in the layer, then the 18 around it, leaving a block as soon
//! as no pixel could still be an extremum: with the threshold at 1 most
//! blocks went on, and those data-dependent branches cost more than the max
//! and min the separable form always does (the test fell from 10.0 to 7.7 %
//! of a view_trajectory profile; CPU time −5.7 %, median of 6 rounds).

use super::super::lanes::{Kernel, Lanes};
use std::ops::Range;

/// Scratch rows of the separable test (per-column maximum and minimum).
#[derive(Default)]
pub(super) struct ColumnExtremes {
    max: Vec<f32>,
    min: Vec<f32>,
}

/// One scan row's test; positions are columns from `cols.start`.
pub(super) struct RowExtrema<'a> {
    /// The nine rows; vectors run only where they extend one pixel past
    /// `cols` on each side.
    pub rows: &'a [&'a [f32]; 9],
    pub thr: f32,
    pub cols: Range<usize>,
    pub out: &'a mut Vec<usize>,
    pub scratch: &'a mut ColumnExtremes,
    /// Whether the per-column maxima and minima of the whole row are in
    /// `scratch` (a narrower width goes on from the wider one's columns).
    pub columns_done: bool,
}

impl Kernel for RowExtrema<'_> {
    #[inline(always)]
    fn apply<L: Lanes>(&mut self, l: L, start: usize) -> usize {
        let n = L::N;
        let cols = self.cols.clone();
        // The raw reads below need every row to hold columns
        // cols.start − 1 ..= cols.end; rows without that margin (or too
        // short for one vector) are left to the scalar test.
        if cols.start == 0 {
            return start;
        }
        let (x0, w) = (cols.start - 1, cols.end + 1);
        if self.rows.iter().any(|r| r.len() < w) || w < x0 + n {
            return start;
        }
        let p: [*const f32; 9] = std::array::from_fn(|i| self.rows[i].as_ptr());
        if !self.columns_done {
            let ColumnExtremes { max, min } = &mut *self.scratch;
            max.resize(w, 0.0);
            min.resize(w, 0.0);
            let (cmax, cmin) = (max.as_mut_ptr(), min.as_mut_ptr());
            let mut x = x0;
            while x + n <= w {
                // SAFETY: x0 <= x and x + n <= w: columns every row holds
                // (checked above), inside the scratch rows (w).
                unsafe { column(l, &p, cmax, cmin, x) };
                x += n;
            }
            // The last block overlaps the one before: max and min again.
            if x < w {
                // SAFETY: as above, with x = w − n >= x0.
                unsafe { column(l, &p, cmax, cmin, w - n) };
            }
            self.columns_done = true;
        }
        let (cmax, cmin) = (self.scratch.max.as_ptr(), self.scratch.min.as_ptr());
        let (hi, lo) = (l.splat(self.thr), l.splat(-self.thr));
        // Room for a hit in every column, so the loop writes hits through a
        // pointer: with `push` (which may call the allocator) in it, the
        // loop's pointers and thresholds were reloaded from the stack on
        // every block.
        let out = &mut *self.out;
        out.reserve(cols.len());
        let (hits, mut k) = (out.as_mut_ptr(), out.len());
        let mut x = cols.start + start;
        while x + n <= cols.end {
            // SAFETY: columns x..x + n <= cols.end of the centre row, and
            // x − 1 ..= x + n <= w − 1 of the scratch rows (written above).
            let (v, mx, mn) = unsafe {
                (
                    l.load(p[4].add(x)),
                    l.max(l.max(l.load(cmax.add(x - 1)), l.load(cmax.add(x))), l.load(cmax.add(x + 1))),
                    l.min(l.min(l.load(cmin.add(x - 1)), l.load(cmin.add(x))), l.load(cmin.add(x + 1))),
                )
            };
            let hit = l.or(l.and(l.gt(v, hi), l.ge(v, mx)), l.and(l.lt(v, lo), l.le(v, mn)));
            let mut mask = l.bits(hit);
            while mask != 0 {
                // SAFETY: k − len <= the columns examined so far < the room
                // reserved, so slot k is inside the buffer.
                unsafe { hits.add(k).write(x + mask.trailing_zeros() as usize) };
                k += 1;
                mask &= mask - 1;
            }
            x += n;
        }
        // SAFETY: the first k entries are written (k − len ≤ the columns
        // examined ≤ the room reserved).
        unsafe { out.set_len(k) };
        x - cols.start
    }
}

/// The maximum and minimum over the nine rows of columns `x..x + N`.
/// (A function, not a closure: a closure is compiled without the ISA's
/// target features, and its intrinsics would stay calls.)
///
/// # Safety
/// Columns `x..x + N` of the nine rows and of `cmax`, `cmin` exist.
#[inline(always)]
unsafe fn column<L: Lanes>(l: L, p: &[*const f32; 9], cmax: *mut f32, cmin: *mut f32, x: usize) {
    // SAFETY: the caller's promise.
    unsafe {
        let first = l.load(p[0].add(x));
        let (mut mx, mut mn) = (first, first);
        for &row in &p[1..] {
            let s = l.load(row.add(x));
            mx = l.max(mx, s);
            mn = l.min(mn, s);
        }
        l.store(cmax.add(x), mx);
        l.store(cmin.add(x), mn);
    }
}
