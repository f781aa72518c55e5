//! Scale-space extrema: the 26-neighbour scan, sub-pixel refinement with
//! OpenCV's exact arithmetic, contrast and edge tests (docs/fidelity.md §SIFT-6, §SIFT-7).

use super::image::Plane;
use super::num::{fma, rne, rne64};
use super::orientation::{prefetch_histogram_window, push_oriented};
use super::{KeyPoint, SiftParams};

pub const IMG_BORDER: usize = 5;
const MAX_INTERP_STEPS: usize = 5;

const IMG_SCALE: f32 = 1.0 / 255.0;
const DERIV_SCALE: f32 = IMG_SCALE * 0.5;
const SECOND_DERIV_SCALE: f32 = IMG_SCALE;
const CROSS_DERIV_SCALE: f32 = IMG_SCALE * 0.25;

/// One DoG level, read through the two Gaussian levels it is the difference
/// of: the value OpenCV stores in its DoG pyramid is this same f32
/// subtraction, so every refinement step sees the same numbers.
#[derive(Clone, Copy)]
struct Dog<'a> {
    hi: &'a Plane,
    lo: &'a Plane,
}

impl Dog<'_> {
    #[inline(always)]
    fn at(&self, r: usize, c: usize) -> f32 {
        self.hi.at(r, c) - self.lo.at(r, c)
    }
}

/// DoG level `j` of an octave whose Gaussian levels are `levels`.
#[inline(always)]
fn dog(levels: &[Plane], j: usize) -> Dog<'_> {
    Dog { hi: &levels[j + 1], lo: &levels[j] }
}

/// Finds the keypoints of octave `o`, rows `[r0, r1)` of its DoG layers
/// 1..=nl, appending them with every orientation peak (unordered; §SIFT-10
/// sorts).
///
/// OpenCV scans one stored DoG image at a time. The DoG rows come instead
/// from a rolling window of three rows per DoG level, each row the f32
/// difference of two Gaussian rows taken once; the three layers' scans of
/// a row then read it from cache. That moves each Gaussian level through
/// memory once, instead of writing five DoG planes per octave and reading
/// them back nine times (a third of SIFT's memory traffic on a KITTI frame).
pub fn scan_octave(levels: &[Plane], o: usize, rows: std::ops::Range<usize>, p: &SiftParams, out: &mut Vec<KeyPoint>) {
    let nl = p.n_octave_layers;
    let (w, h) = (levels[0].width, levels[0].height);
    // floor(0.5 * contrastThreshold / nOctaveLayers * 255 * SIFT_FIXPT_SCALE),
    // an int compared as float: 1 with the defaults.
    let threshold = (0.5 * p.contrast_threshold / nl as f64 * 255.0).floor() as i32 as f32;
    let r_start = rows.start.max(IMG_BORDER);
    let r_end = rows.end.min(h.saturating_sub(IMG_BORDER));
    if w <= 2 * IMG_BORDER || r_start >= r_end {
        return;
    }
    // Row y of DoG level j is window row 3j + y % 3.
    let mut window = Plane::for_overwrite(w, 3 * (nl + 2));
    let slot = |j: usize, y: usize| 3 * j + y % 3;
    let fill = |window: &mut Plane, y: usize| differences(levels, y, window);
    fill(&mut window, r_start - 1);
    fill(&mut window, r_start);
    let mut candidates = Vec::new();
    let mut scratch = ColumnExtremes::default();
    let mut pending: Option<Refined> = None;
    for r in r_start..r_end {
        fill(&mut window, r + 1);
        for layer in 1..=nl {
            let row = |j: usize, y: usize| window.row(slot(j, y));
            let rows = [
                row(layer - 1, r - 1),
                row(layer - 1, r),
                row(layer - 1, r + 1),
                row(layer, r - 1),
                row(layer, r),
                row(layer, r + 1),
                row(layer + 1, r - 1),
                row(layer + 1, r),
                row(layer + 1, r + 1),
            ];
            candidates.clear();
            row_extrema(&rows, threshold, IMG_BORDER..w - IMG_BORDER, &mut candidates, &mut scratch);
            for &c in &candidates {
                if let Some(refined) = adjust_local_extremum(levels, o, layer, r, c, p) {
                    // Each histogram is taken one keypoint late, so its
                    // window's rows (most of them below the scan, not read
                    // yet) arrive while the one before is counted.
                    prefetch_histogram_window(levels, &refined);
                    if let Some(before) = pending.replace(refined) {
                        push_oriented(levels, before, p, out);
                    }
                }
            }
        }
    }
    if let Some(last) = pending {
        push_oriented(levels, last, p, out);
    }
}

/// Row y of every DoG level at once into the scan window (DoG level j at
/// window row 3j + y % 3): with the default three layers, the six Gaussian
/// rows are read side by side in one pass, each once, so their memory
/// streams run together rather than two at a time.
fn differences(levels: &[Plane], y: usize, window: &mut Plane) {
    #[cfg(target_arch = "x86_64")]
    if crate::simd::avx2()
        && levels.len() == 6
        && window.height >= 15
        && levels.iter().all(|l| l.width == window.width && y < l.height)
    {
        let w = window.width;
        let g: [*const f32; 6] = std::array::from_fn(|k| levels[k].row(y).as_ptr());
        let base = window.data.as_mut_ptr();
        // SAFETY: distinct window rows (3j + y % 3 < 15), each w floats.
        let d: [*mut f32; 5] = std::array::from_fn(|j| unsafe { base.add((3 * j + y % 3) * w) });
        // SAFETY: the CPU has AVX2; every row holds w floats.
        unsafe { x86::differences6_avx2(g, d, w) };
        return;
    }
    for j in 0..levels.len() - 1 {
        difference(levels[j + 1].row(y), levels[j].row(y), window.row_mut(3 * j + y % 3));
    }
}

/// `d = hi − lo`, element by element: one row of a DoG level.
fn difference(hi: &[f32], lo: &[f32], d: &mut [f32]) {
    #[inline(always)]
    fn body(hi: &[f32], lo: &[f32], d: &mut [f32]) {
        for ((d, &a), &b) in d.iter_mut().zip(hi).zip(lo) {
            *d = a - b;
        }
    }
    #[cfg(target_arch = "x86_64")]
    {
        #[target_feature(enable = "avx2")]
        unsafe fn avx2(hi: &[f32], lo: &[f32], d: &mut [f32]) {
            body(hi, lo, d)
        }
        if crate::simd::avx2() {
            // SAFETY: the CPU has AVX2, the only feature `avx2` enables.
            return unsafe { avx2(hi, lo, d) };
        }
    }
    body(hi, lo, d)
}

/// Pixels per block of the vectorised 26-neighbour test.
const LANES: usize = 16;

/// The columns of the middle row of `rows` (three rows each of the previous,
/// current and next DoG layer, centred on the scanned row) where OpenCV's
/// test holds: |v| above the threshold and v ≥ all 26 neighbours if positive,
/// ≤ all of them if negative. OpenCV's scalar form stops at the first failed
/// comparison; comparing v with the neighbours' max and min decides the same
/// (no NaN can arise from 8-bit images) for a block of pixels at once.
#[inline(always)]
fn row_extrema_generic(rows: &[&[f32]; 9], thr: f32, cols: std::ops::Range<usize>, out: &mut Vec<usize>) {
    let centre = rows[4];
    let is_extremum = |v: f32, mx: f32, mn: f32| (v > thr && v >= mx) || (v < -thr && v <= mn);
    let mut x = cols.start;
    while x + LANES <= cols.end {
        let (mut mx, mut mn) = ([f32::NEG_INFINITY; LANES], [f32::INFINITY; LANES]);
        for (i, row) in rows.iter().enumerate() {
            for dx in 0..3 {
                if i == 4 && dx == 1 {
                    continue; // the pixel itself
                }
                let s = &row[x + dx - 1..x + dx - 1 + LANES];
                for l in 0..LANES {
                    mx[l] = if s[l] > mx[l] { s[l] } else { mx[l] };
                    mn[l] = if s[l] < mn[l] { s[l] } else { mn[l] };
                }
            }
        }
        let v = &centre[x..x + LANES];
        let mut mask = 0u32;
        for l in 0..LANES {
            mask |= (is_extremum(v[l], mx[l], mn[l]) as u32) << l;
        }
        while mask != 0 {
            out.push(x + mask.trailing_zeros() as usize);
            mask &= mask - 1;
        }
        x += LANES;
    }
    for c in x..cols.end {
        let (mut mx, mut mn) = (f32::NEG_INFINITY, f32::INFINITY);
        for (i, row) in rows.iter().enumerate() {
            for dx in 0..3 {
                if i != 4 || dx != 1 {
                    mx = mx.max(row[c + dx - 1]);
                    mn = mn.min(row[c + dx - 1]);
                }
            }
        }
        if is_extremum(centre[c], mx, mn) {
            out.push(c);
        }
    }
}

/// The same test with intrinsics, AVX-512 and AVX2, against the separable
/// 3×3×3 maximum and minimum.
#[cfg(target_arch = "x86_64")]
mod x86 {
    use std::arch::x86_64::*;

    /// [`super::differences`] for six Gaussian rows, eight columns at a
    /// time (a last block overlapping the one before).
    #[target_feature(enable = "avx2")]
    pub unsafe fn differences6_avx2(g: [*const f32; 6], d: [*mut f32; 5], w: usize) {
        let block = |x: usize| {
            let v: [__m256; 6] = std::array::from_fn(|k| _mm256_loadu_ps(g[k].add(x)));
            for k in 0..5 {
                _mm256_storeu_ps(d[k].add(x), _mm256_sub_ps(v[k + 1], v[k]));
            }
        };
        if w < 8 {
            for x in 0..w {
                for k in 0..5 {
                    *d[k].add(x) = *g[k + 1].add(x) - *g[k].add(x);
                }
            }
            return;
        }
        let mut x = 0;
        while x + 8 <= w {
            block(x);
            x += 8;
        }
        if x < w {
            block(w - 8);
        }
    }

    /// Returns the first column not examined (the scalar tail starts there).
    /// Needs every row to extend one pixel past `cols.end` and `cols.start >= 1`.
    ///
    /// v ≥ all 26 neighbours ⟺ v ≥ the maximum of the 3×3×3 block (v itself
    /// included), and that maximum is separable: first per column over the
    /// nine rows (three layers × three rows), then over three columns. That
    /// is 10 max and 10 min per pixel instead of 26 of each.
    #[target_feature(enable = "avx512f")]
    pub unsafe fn row_extrema_avx512(
        rows: &[&[f32]; 9],
        thr: f32,
        cols: std::ops::Range<usize>,
        out: &mut Vec<usize>,
        col_max: &mut Vec<f32>,
        col_min: &mut Vec<f32>,
    ) -> usize {
        let p: [*const f32; 9] = std::array::from_fn(|i| rows[i].as_ptr());
        let w = cols.end + 1;
        col_max.resize(w + 16, 0.0);
        col_min.resize(w + 16, 0.0);
        let (cmax, cmin) = (col_max.as_mut_ptr(), col_min.as_mut_ptr());
        let mut x = cols.start - 1;
        while x < w {
            let valid: __mmask16 = if w - x >= 16 { 0xFFFF } else { (1u16 << (w - x)) - 1 };
            let first = _mm512_maskz_loadu_ps(valid, p[0].add(x));
            let (mut mx, mut mn) = (first, first);
            for &row in &p[1..] {
                let s = _mm512_maskz_loadu_ps(valid, row.add(x));
                mx = _mm512_max_ps(mx, s);
                mn = _mm512_min_ps(mn, s);
            }
            _mm512_mask_storeu_ps(cmax.add(x), valid, mx);
            _mm512_mask_storeu_ps(cmin.add(x), valid, mn);
            x += 16;
        }
        let (hi, lo) = (_mm512_set1_ps(thr), _mm512_set1_ps(-thr));
        let mut x = cols.start;
        while x + 16 <= cols.end {
            let v = _mm512_loadu_ps(p[4].add(x));
            let (pos, neg) = (_mm512_cmp_ps_mask::<_CMP_GT_OQ>(v, hi), _mm512_cmp_ps_mask::<_CMP_LT_OQ>(v, lo));
            if pos | neg != 0 {
                let mx = _mm512_max_ps(
                    _mm512_max_ps(_mm512_loadu_ps(cmax.add(x - 1)), _mm512_loadu_ps(cmax.add(x))),
                    _mm512_loadu_ps(cmax.add(x + 1)),
                );
                let mn = _mm512_min_ps(
                    _mm512_min_ps(_mm512_loadu_ps(cmin.add(x - 1)), _mm512_loadu_ps(cmin.add(x))),
                    _mm512_loadu_ps(cmin.add(x + 1)),
                );
                let hit =
                    (pos & _mm512_cmp_ps_mask::<_CMP_GE_OQ>(v, mx)) | (neg & _mm512_cmp_ps_mask::<_CMP_LE_OQ>(v, mn));
                let mut mask = hit as u32;
                while mask != 0 {
                    out.push(x + mask.trailing_zeros() as usize);
                    mask &= mask - 1;
                }
            }
            x += 16;
        }
        x
    }

    /// [`row_extrema_avx512`]'s separable test with AVX2, eight lanes,
    /// without branches but the rare hit. It replaced a test that took the
    /// threshold first, then the 8 neighbours in the layer, then the 18
    /// around it, leaving a block as soon as no pixel could still be an
    /// extremum: with the threshold at 1 most blocks went on, and those
    /// data-dependent branches cost more than the max and min the separable
    /// form always does (the test fell from 10.0 to 7.7 % of a
    /// view_trajectory profile; CPU time −5.7 %, median of 6 rounds).
    #[target_feature(enable = "avx2")]
    pub unsafe fn row_extrema_avx2_separable(
        rows: &[&[f32]; 9],
        thr: f32,
        cols: std::ops::Range<usize>,
        out: &mut Vec<usize>,
        col_max: &mut Vec<f32>,
        col_min: &mut Vec<f32>,
    ) -> usize {
        let p: [*const f32; 9] = std::array::from_fn(|i| rows[i].as_ptr());
        // Columns cols.start − 1 ..= cols.end: every row holds them.
        let (x0, w) = (cols.start - 1, cols.end + 1);
        col_max.resize(w + 8, 0.0);
        col_min.resize(w + 8, 0.0);
        let (cmax, cmin) = (col_max.as_mut_ptr(), col_min.as_mut_ptr());
        let column = |x: usize| {
            let first = _mm256_loadu_ps(p[0].add(x));
            let (mut mx, mut mn) = (first, first);
            for &row in &p[1..] {
                let s = _mm256_loadu_ps(row.add(x));
                mx = _mm256_max_ps(mx, s);
                mn = _mm256_min_ps(mn, s);
            }
            _mm256_storeu_ps(cmax.add(x), mx);
            _mm256_storeu_ps(cmin.add(x), mn);
        };
        if w - x0 < 8 {
            return cols.start;
        }
        let mut x = x0;
        while x + 8 <= w {
            column(x);
            x += 8;
        }
        if x < w {
            column(w - 8);
        }
        let (hi, lo) = (_mm256_set1_ps(thr), _mm256_set1_ps(-thr));
        // Room for a hit in every column, so the loop writes hits through a
        // pointer: with `push` (which may call the allocator) in it, the
        // loop's pointers and thresholds were reloaded from the stack on
        // every block.
        out.reserve(cols.end - cols.start);
        let (hits, mut n) = (out.as_mut_ptr(), out.len());
        let mut x = cols.start;
        while x + 8 <= cols.end {
            let v = _mm256_loadu_ps(p[4].add(x));
            let (pos, neg) = (_mm256_cmp_ps::<_CMP_GT_OQ>(v, hi), _mm256_cmp_ps::<_CMP_LT_OQ>(v, lo));
            let mx = _mm256_max_ps(
                _mm256_max_ps(_mm256_loadu_ps(cmax.add(x - 1)), _mm256_loadu_ps(cmax.add(x))),
                _mm256_loadu_ps(cmax.add(x + 1)),
            );
            let mn = _mm256_min_ps(
                _mm256_min_ps(_mm256_loadu_ps(cmin.add(x - 1)), _mm256_loadu_ps(cmin.add(x))),
                _mm256_loadu_ps(cmin.add(x + 1)),
            );
            let hit = _mm256_or_ps(
                _mm256_and_ps(pos, _mm256_cmp_ps::<_CMP_GE_OQ>(v, mx)),
                _mm256_and_ps(neg, _mm256_cmp_ps::<_CMP_LE_OQ>(v, mn)),
            );
            let mut mask = _mm256_movemask_ps(hit) as u32;
            while mask != 0 {
                hits.add(n).write(x + mask.trailing_zeros() as usize);
                n += 1;
                mask &= mask - 1;
            }
            x += 8;
        }
        // SAFETY: the first n entries are written (n − len ≤ the columns
        // examined ≤ the room reserved).
        out.set_len(n);
        x
    }
}

/// The separable test of `row_extrema_avx512` with WebAssembly SIMD, four
/// lanes: per-column maximum and minimum over the nine rows, then over three
/// columns, then the threshold and comparison. `pmax`/`pmin` are one
/// instruction each and equal `max`/`min` here: no NaN arises from 8-bit
/// images, and the ±0 ties where they differ cannot decide a test whose value
/// lies beyond the threshold.
#[cfg(target_arch = "wasm32")]
mod wasm {
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
}

/// Scratch rows of the separable test (per-column maximum and minimum).
#[derive(Default)]
#[cfg_attr(not(any(target_arch = "x86_64", target_arch = "wasm32")), allow(dead_code))]
struct ColumnExtremes {
    max: Vec<f32>,
    min: Vec<f32>,
}

fn row_extrema(
    rows: &[&[f32]; 9],
    thr: f32,
    cols: std::ops::Range<usize>,
    out: &mut Vec<usize>,
    scratch: &mut ColumnExtremes,
) {
    #[cfg(target_arch = "x86_64")]
    if rows.iter().all(|r| r.len() > cols.end) && cols.start >= 1 {
        // SAFETY (both calls): the CPU supports the features the function was
        // compiled for, and every row has a pixel on each side of `cols`.
        let done = if crate::simd::avx512f() {
            unsafe { x86::row_extrema_avx512(rows, thr, cols.clone(), out, &mut scratch.max, &mut scratch.min) }
        } else if crate::simd::avx2() {
            unsafe { x86::row_extrema_avx2_separable(rows, thr, cols.clone(), out, &mut scratch.max, &mut scratch.min) }
        } else {
            cols.start
        };
        return row_extrema_generic(rows, thr, done..cols.end, out);
    }
    #[cfg(target_arch = "wasm32")]
    if rows.iter().all(|r| r.len() > cols.end) && cols.start >= 1 {
        let done = wasm::row_extrema_simd128(rows, thr, cols.clone(), out, &mut scratch.max, &mut scratch.min);
        return row_extrema_generic(rows, thr, done..cols.end, out);
    }
    let _ = scratch;
    row_extrema_generic(rows, thr, cols, out)
}

/// A refined extremum, before orientation: the keypoint fields plus the
/// integer pixel and layer the orientation histogram is centred on.
pub struct Refined {
    pub kp: KeyPoint,
    pub o: usize,
    pub layer: usize,
    pub r: usize,
    pub c: usize,
}

struct Derivs {
    d: [f32; 3],
    dxx: f32,
    dyy: f32,
    dss: f32,
    dxy: f32,
    dxs: f32,
    dys: f32,
}

#[inline(always)]
fn first_derivs(cur: Dog, prev: Dog, next: Dog, r: usize, c: usize) -> [f32; 3] {
    [
        (cur.at(r, c + 1) - cur.at(r, c - 1)) * DERIV_SCALE,
        (cur.at(r + 1, c) - cur.at(r - 1, c)) * DERIV_SCALE,
        (next.at(r, c) - prev.at(r, c)) * DERIV_SCALE,
    ]
}

#[inline(always)]
fn xy_second_derivs(cur: Dog, r: usize, c: usize) -> (f32, f32, f32) {
    let v2 = cur.at(r, c) * 2.0;
    let dxx = ((cur.at(r, c + 1) + cur.at(r, c - 1)) - v2) * SECOND_DERIV_SCALE;
    let dyy = ((cur.at(r + 1, c) + cur.at(r - 1, c)) - v2) * SECOND_DERIV_SCALE;
    let dxy = (((cur.at(r + 1, c + 1) - cur.at(r + 1, c - 1)) - cur.at(r - 1, c + 1)) + cur.at(r - 1, c - 1))
        * CROSS_DERIV_SCALE;
    (dxx, dyy, dxy)
}

#[inline(always)]
fn derivs(cur: Dog, prev: Dog, next: Dog, r: usize, c: usize) -> Derivs {
    let d = first_derivs(cur, prev, next, r, c);
    let (dxx, dyy, dxy) = xy_second_derivs(cur, r, c);
    let v2 = cur.at(r, c) * 2.0;
    let dss = ((next.at(r, c) + prev.at(r, c)) - v2) * SECOND_DERIV_SCALE;
    let dxs = (((next.at(r, c + 1) - next.at(r, c - 1)) - prev.at(r, c + 1)) + prev.at(r, c - 1)) * CROSS_DERIV_SCALE;
    let dys = (((next.at(r + 1, c) - next.at(r - 1, c)) - prev.at(r + 1, c)) + prev.at(r - 1, c)) * CROSS_DERIV_SCALE;
    Derivs { d, dxx, dyy, dss, dxy, dxs, dys }
}

/// `Matx33f::solve(DECOMP_LU)`: Cramer's rule with the common subexpressions
/// and fusions GCC produced (docs/fidelity.md §SIFT-7). Returns the offsets (xc, xr, xi).
#[inline(always)]
fn solve_offsets(g: &Derivs) -> (f32, f32, f32) {
    let Derivs { d, dxx, dyy, dss, dxy, dxs, dys } = *g;
    let [d0, d1, d2] = d;
    let a = fma(dyy, dss, -(dys * dys));
    let b = fma(dss, dxy, -(dxs * dys));
    let cc = fma(dxy, dys, -(dyy * dxs));
    let det = fma(dxs, cc, fma(dxx, a, -(dxy * b)));
    if det == 0.0 {
        return (-0.0, -0.0, -0.0);
    }
    let dinv = 1.0 / det;
    let t177 = d2 * dyy;
    let pp = fma(d1, dss, -(d2 * dys));
    let q = fma(d1, dys, -t177);
    let rr = fma(d2, dxy, -(d1 * dxs));
    let s = fma(-d1, dys, t177);
    let x0 = dinv * fma(dxs, q, fma(d0, a, -(dxy * pp)));
    let x1 = dinv * fma(dxs, rr, fma(dxx, pp, -(d0 * b)));
    let x2 = dinv * fma(d0, cc, fma(dxx, s, -(dxy * rr)));
    (-x0, -x1, -x2)
}

/// `adjustLocalExtrema`: up to five Newton steps, then the contrast and
/// edge tests. `None` when OpenCV rejects the candidate.
///
/// Compiled with FMA where the CPU has it: its two dozen `fma`s and
/// roundings were calls to `fmaf` and `rintf` otherwise.
fn adjust_local_extremum(
    levels: &[Plane],
    o: usize,
    layer0: usize,
    r0: usize,
    c0: usize,
    p: &SiftParams,
) -> Option<Refined> {
    crate::with_hw_fma!(Option<Refined>, refine(levels, o, layer0, r0, c0, p))
}

#[inline(always)]
fn refine(levels: &[Plane], o: usize, layer0: usize, r0: usize, c0: usize, p: &SiftParams) -> Option<Refined> {
    let nl = p.n_octave_layers;
    let (w, h) = (levels[0].width as i64, levels[0].height as i64);
    let border = IMG_BORDER as i64;
    let (mut layer, mut r, mut c) = (layer0 as i64, r0 as i64, c0 as i64);
    let (mut xi, mut xr, mut xc) = (0f32, 0f32, 0f32);
    let mut converged = false;
    for _ in 0..MAX_INTERP_STEPS {
        let li = layer as usize;
        let g = derivs(dog(levels, li), dog(levels, li - 1), dog(levels, li + 1), r as usize, c as usize);
        (xc, xr, xi) = solve_offsets(&g);
        if xi.abs() < 0.5 && xr.abs() < 0.5 && xc.abs() < 0.5 {
            converged = true;
            break;
        }
        let lim = (i32::MAX / 3) as f32;
        if xi.abs() > lim || xr.abs() > lim || xc.abs() > lim {
            return None;
        }
        c += rne(xc) as i64;
        r += rne(xr) as i64;
        layer += rne(xi) as i64;
        if layer < 1 || layer > nl as i64 || c < border || c >= w - border || r < border || r >= h - border {
            return None;
        }
    }
    if !converged {
        return None;
    }
    let (layer, r, c) = (layer as usize, r as usize, c as usize);
    let (cur, prev, next) = (dog(levels, layer), dog(levels, layer - 1), dog(levels, layer + 1));

    let [d0, d1, d2] = first_derivs(cur, prev, next, r, c);
    let t = fma(d2, xi, fma(d1, xr, d0 * xc));
    let contr = fma(cur.at(r, c), IMG_SCALE, t * 0.5);
    if contr.abs() * (nl as f32) < (p.contrast_threshold as f32) {
        return None;
    }

    let (dxx, dyy, dxy) = xy_second_derivs(cur, r, c);
    let tr = dxx + dyy;
    let det = fma(dxx, dyy, -(dxy * dxy));
    let e = p.edge_threshold as f32;
    if det <= 0.0 || tr * tr * e >= (e + 1.0) * (e + 1.0) * det {
        return None;
    }

    let scale = (1u32 << o) as f32;
    let kp = KeyPoint {
        x: (c as f32 + xc) * scale,
        y: (r as f32 + xr) * scale,
        octave: o as i32 + ((layer as i32) << 8) + (rne64((xi as f64 + 0.5) * 255.0) << 16),
        size: ((p.sigma as f32) * super::num::pow2f((layer as f32 + xi) / nl as f32)) * scale * 2.0,
        response: contr.abs(),
        angle: 0.0,
    };
    Some(Refined { kp, o, layer, r, c })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solve_identity_hessian() {
        let g = Derivs { d: [0.25, -0.5, 0.125], dxx: 1.0, dyy: 1.0, dss: 1.0, dxy: 0.0, dxs: 0.0, dys: 0.0 };
        assert_eq!(solve_offsets(&g), (-0.25, 0.5, -0.125));
    }

    /// All DoG rows of a scan row at once equal the level-by-level
    /// differences, bit for bit, for widths with and without a vector tail.
    #[test]
    fn differences_of_six_rows_match_level_by_level() {
        let mut s = 0x1234_5677u32;
        for w in [1usize, 7, 8, 9, 23, 64, 2482] {
            let levels: Vec<Plane> = (0..6)
                .map(|_| {
                    let mut p = Plane::for_overwrite(w, 3);
                    for v in p.data.iter_mut() {
                        s ^= s << 13;
                        s ^= s >> 17;
                        s ^= s << 5;
                        *v = (s % 65_536) as f32 / 256.0 - 100.0;
                    }
                    p
                })
                .collect();
            for y in 0..3 {
                let mut window = Plane::for_overwrite(w, 15);
                differences(&levels, y, &mut window);
                for j in 0..5 {
                    let mut want = vec![0f32; w];
                    difference(levels[j + 1].row(y), levels[j].row(y), &mut want);
                    let got: Vec<u32> = window.row(3 * j + y % 3).iter().map(|v| v.to_bits()).collect();
                    assert_eq!(got, want.iter().map(|v| v.to_bits()).collect::<Vec<_>>(), "w {w}, y {y}, level {j}");
                }
            }
        }
    }

    /// The vectorised 26-neighbour test (AVX2, AVX-512 or simd128, as the
    /// host has) against the scalar definition, on rows of small integers
    /// where ties with neighbours and plateaus are common, at widths that
    /// leave every kind of tail. A tie must keep a pixel (v ≥ max), and
    /// ±threshold itself must not pass (|v| > thr).
    #[test]
    fn vector_extremum_test_matches_the_scalar_one() {
        let mut rng = crate::vo::linalg::CvRng::new(0x2545_f491);
        let mut next = move || rng.next_u32();
        let mut found = 0;
        for w in [10usize, 17, 40, 67, 130] {
            for round in 0..40 {
                // Values −3..=3: threshold 1, so 0, ±1 fail and ties abound.
                let data: Vec<Vec<f32>> = (0..9).map(|_| (0..w).map(|_| (next() % 7) as f32 - 3.0).collect()).collect();
                let mut data = data;
                if round % 4 == 0 {
                    // A plateau: the centre equal to all its neighbours.
                    for row in data.iter_mut() {
                        row[w / 2 - 1..=w / 2 + 1].fill(3.0);
                    }
                }
                let rows: [&[f32]; 9] = std::array::from_fn(|i| &data[i][..]);
                let cols = 1..w - 1;
                let mut expected = Vec::new();
                for c in cols.clone() {
                    let v = rows[4][c];
                    let neighbours =
                        (0..9).flat_map(|i| (0..3).map(move |d| (i, d))).filter(|&(i, d)| (i, d) != (4, 1));
                    let ok = (v > 1.0 && neighbours.clone().all(|(i, d)| v >= rows[i][c + d - 1]))
                        || (v < -1.0 && neighbours.clone().all(|(i, d)| v <= rows[i][c + d - 1]));
                    if ok {
                        expected.push(c);
                    }
                }
                let mut got = Vec::new();
                row_extrema(&rows, 1.0, cols, &mut got, &mut ColumnExtremes::default());
                got.sort_unstable();
                assert_eq!(got, expected, "width {w}, round {round}");
                found += expected.len();
            }
        }
        // The plateaus alone give 50 extrema; random rows add some.
        assert!(found >= 50, "{found}");
    }

    #[test]
    fn singular_hessian_gives_zero_step() {
        let g = Derivs { d: [1.0, 1.0, 1.0], dxx: 0.0, dyy: 0.0, dss: 0.0, dxy: 0.0, dxs: 0.0, dys: 0.0 };
        let (a, b, c) = solve_offsets(&g);
        assert_eq!((a, b, c), (0.0, 0.0, 0.0));
    }
}
