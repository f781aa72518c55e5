//! Scale-space extrema (docs/fidelity.md §SIFT-5 to §SIFT-7): the difference
//! of Gaussians taken row by row, OpenCV's 26-neighbour scan, and each
//! candidate's sub-pixel refinement with the contrast and edge tests
//! (`refine.rs`). Every accepted extremum goes to the caller's sink, in scan
//! order; this stage knows nothing of what follows it.
//!
//! This file is the scan in OpenCV's order and the dispatch; the vector forms
//! live beside it: the 26-neighbour test once for every width in `vector.rs`,
//! the DoG rows with AVX2 in `x86.rs`.

use super::image::Plane;
use super::keypoint::Refined;
use super::observer::Observer;
use super::params::SiftParams;

mod refine;
mod vector;
#[cfg(target_arch = "x86_64")]
mod x86;

pub use refine::IMG_BORDER;
use vector::ColumnExtremes;

/// Finds the extrema of octave `o`, rows `[r0, r1)` of its DoG layers
/// 1..=nl, and hands each refined one to `sink` (§SIFT-6: the scan order does
/// not matter, §SIFT-10 sorts everything). `sink` is a generic closure, so
/// it is compiled into the scan loop. `watch` sees every scan extremum and
/// every rejection with its reason; the plain pipeline passes `&()`, whose
/// empty methods compile away.
///
/// OpenCV scans one stored DoG image at a time. The DoG rows come instead
/// from a rolling window of three rows per DoG level, each row the f32
/// difference of two Gaussian rows taken once; the three layers' scans of
/// a row then read it from cache. That moves each Gaussian level through
/// memory once, instead of writing five DoG planes per octave and reading
/// them back nine times (a third of SIFT's memory traffic on a KITTI frame).
pub fn scan_octave(
    levels: &[Plane],
    o: usize,
    rows: std::ops::Range<usize>,
    p: &SiftParams,
    watch: &impl Observer,
    mut sink: impl FnMut(Refined),
) {
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
                watch.extremum(o, layer, r, c);
                match refine::adjust_local_extremum(levels, refine::Candidate { o, layer, r, c }, p) {
                    Ok(refined) => sink(refined),
                    Err(why) => watch.rejected(o, layer, r, c, why),
                }
            }
        }
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
        // SAFETY: window row 3j + y % 3 < 15 <= window.height, inside the plane.
        let d: [*mut f32; 5] = std::array::from_fn(|j| unsafe { base.add((3 * j + y % 3) * w) });
        // SAFETY: the CPU has AVX2; the six Gaussian rows and the five
        // distinct window rows each hold w floats.
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
        fn avx2(hi: &[f32], lo: &[f32], d: &mut [f32]) {
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

/// The 26-neighbour test of one scan row: vectors where the target has
/// them (and the rows have a pixel on each side of `cols`), then the scalar
/// test on the columns left.
fn row_extrema(
    rows: &[&[f32]; 9],
    thr: f32,
    cols: std::ops::Range<usize>,
    out: &mut Vec<usize>,
    scratch: &mut ColumnExtremes,
) {
    let mut k = vector::RowExtrema { rows, thr, cols: cols.clone(), out, scratch, columns_done: false };
    let done = cols.start + super::lanes::run(&mut k);
    row_extrema_generic(rows, thr, done..cols.end, out)
}

#[cfg(test)]
mod tests {
    use super::*;

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
        let mut rng = crate::rng::CvRng::new(0x2545_f491);
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
}
