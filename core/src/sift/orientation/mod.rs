//! Orientation assignment, `calcOrientationHist` (docs/fidelity.md §SIFT-8): a 36-bin
//! gradient histogram around the refined pixel, smoothed, one keypoint per
//! peak above 80% of the maximum.
//!
//! The extremum scan hands each refined extremum to an [`Orienter`], which
//! counts its histogram and pushes the oriented keypoints. This file is the
//! histogram in OpenCV's order and the dispatch; `x86.rs` holds the AVX2 form
//! of the binning of OpenCV's SIMD body.

use super::image::Plane;
use super::keypoint::{KeyPoint, Refined};
use super::num::{exp32f_into, fma, gradient_directions_into, rne, FLT_EPSILON};
use super::params::SiftParams;

mod bins;
#[cfg(target_arch = "x86_64")]
mod x86;

use bins::ORI_HIST_BINS;

// §SIFT-1: window σ factor 1.5, radius factor 4.5, peak ratio 0.8.
const ORI_SIG_FCTR: f32 = 1.5;
const ORI_RADIUS: f32 = 4.5;
const ORI_PEAK_RATIO: f32 = 0.8;

/// Orients the refined extrema of one scan, in the order they come, into
/// `out`: each histogram is taken one extremum late, so its window's rows
/// (most of them below the scan, not read yet) arrive while the one before
/// is counted. Call [`Orienter::finish`] after the last one.
pub struct Orienter<'a> {
    levels: &'a [Plane],
    p: &'a SiftParams,
    out: &'a mut Vec<KeyPoint>,
    pending: Option<Refined>,
}

impl<'a> Orienter<'a> {
    /// For the extrema of the octave whose Gaussian levels are `levels`.
    pub fn new(levels: &'a [Plane], p: &'a SiftParams, out: &'a mut Vec<KeyPoint>) -> Self {
        Orienter { levels, p, out, pending: None }
    }

    /// Takes the next refined extremum: asks for its window, and orients
    /// the one before it.
    #[inline(always)]
    pub fn push(&mut self, refined: Refined) {
        prefetch_histogram_window(self.levels, &refined);
        if let Some(before) = self.pending.replace(refined) {
            push_oriented(self.levels, before, self.p, self.out);
        }
    }

    /// Orients the last extremum.
    pub fn finish(self) {
        if let Some(last) = self.pending {
            push_oriented(self.levels, last, self.p, self.out);
        }
    }
}

/// The keypoint's scale in its octave's pixels, and its Gaussian level
/// (`levels` are its octave's).
fn scale_and_level<'g>(levels: &'g [Plane], refined: &Refined) -> (f32, &'g Plane) {
    let scl = refined.kp.size * 0.5 / (1u32 << refined.o) as f32;
    (scl, &levels[refined.layer])
}

/// Asks for the rows of the window [`push_oriented`] will read for
/// `refined`, ahead of it.
fn prefetch_histogram_window(levels: &[Plane], refined: &Refined) {
    let (scl, img) = scale_and_level(levels, refined);
    prefetch_window(img, refined.r, refined.c, rne(ORI_RADIUS * scl).max(0) as usize + 1);
}

/// Pushes one copy of the refined keypoint per qualifying histogram peak.
fn push_oriented(levels: &[Plane], refined: Refined, p: &SiftParams, out: &mut Vec<KeyPoint>) {
    let (scl, img) = scale_and_level(levels, &refined);
    let Refined { kp, r, c, .. } = refined;
    let (radius, sigma, lanes) = (rne(ORI_RADIUS * scl), ORI_SIG_FCTR * scl, p.opencv_lanes);
    let hist = crate::with_hw_fma!([f32; 36], orientation_hist(img, r, c, radius, sigma, lanes));
    for_each_peak(&hist, |_, angle| out.push(KeyPoint { angle, ..kp }));
}

/// Calls `f(bin, angle)` for each smoothed-histogram peak that gets a
/// keypoint: above both neighbours and at least 80 % of the highest bin,
/// its bin refined by a parabola (§SIFT-8). Shared by the pipeline and the
/// anatomy view, so both take the same peaks.
#[inline(always)]
fn for_each_peak(hist: &[f32; 36], mut f: impl FnMut(f32, f32)) {
    let omax = hist.iter().copied().fold(hist[0], f32::max);
    let mag_thr = omax * ORI_PEAK_RATIO;
    let n = ORI_HIST_BINS;
    for j in 0..n {
        let l = if j > 0 { j - 1 } else { n - 1 };
        let q = if j < n - 1 { j + 1 } else { 0 };
        if hist[j] > hist[l] && hist[j] > hist[q] && hist[j] >= mag_thr {
            let mut bin = j as f32 + 0.5 * (hist[l] - hist[q]) / ((hist[l] - 2.0 * hist[j]) + hist[q]);
            if bin < 0.0 {
                bin += n as f32;
            } else if bin >= n as f32 {
                bin -= n as f32;
            }
            // 360 − (360/n)·bin contracted by GCC into one FMA (§SIFT-8).
            let mut angle = fma(-bin, 360.0 / n as f32, 360.0);
            if (angle - 360.0).abs() < FLT_EPSILON {
                angle = 0.0;
            }
            f(bin, angle);
        }
    }
}

/// One keypoint's orientation histogram as the anatomy view shows it.
#[derive(Clone, Debug, PartialEq)]
pub struct Histogram {
    /// The 36 bins before smoothing.
    pub raw: [f32; 36],
    /// After OpenCV's [1 4 6 4 1]/16 smoothing: the bins the peaks are taken from.
    pub smoothed: [f32; 36],
    /// 80 % of the highest smoothed bin.
    pub threshold: f32,
    /// Each peak taken: its refined bin and the keypoint angle it gives.
    pub peaks: Vec<(f32, f32)>,
}

/// The histogram the pipeline computes for `refined` (its octave's Gaussian
/// `levels`), by the same code, raw and smoothed.
pub fn histogram(levels: &[Plane], refined: &Refined, p: &SiftParams) -> Histogram {
    let (scl, img) = scale_and_level(levels, refined);
    let (radius, sigma, lanes) = (rne(ORI_RADIUS * scl), ORI_SIG_FCTR * scl, p.opencv_lanes);
    let mut s = SCRATCH.with(|cell| cell.take());
    let t = crate::with_hw_fma!([f32; 40], raw_hist_with(img, refined.r, refined.c, radius, sigma, lanes, &mut s));
    SCRATCH.with(|cell| cell.set(s));
    let smoothed = crate::with_hw_fma!([f32; 36], smooth(&t));
    let mut raw = [0f32; 36];
    raw.copy_from_slice(&t[2..38]);
    let mut peaks = Vec::new();
    for_each_peak(&smoothed, |bin, angle| peaks.push((bin, angle)));
    let omax = smoothed.iter().copied().fold(smoothed[0], f32::max);
    Histogram { raw, smoothed, threshold: omax * ORI_PEAK_RATIO, peaks }
}

/// The buffers of one histogram, kept per thread between calls: a KITTI
/// frame takes a few thousand histograms, too many to allocate six buffers
/// for each (docs/performance.md, Orientation and descriptors).
#[derive(Default)]
struct Scratch {
    dxs: Vec<f32>,
    dys: Vec<f32>,
    wts: Vec<f32>,
    w_args: Vec<f32>,
    weight_rows: Vec<f32>,
    oris: Vec<f32>,
    mags: Vec<f32>,
    /// `bin_products`' first pass: each sample's bin (as its masks' byte
    /// offset) and rounded product.
    offsets: Vec<u32>,
    prods: Vec<f32>,
}

std::thread_local! {
    static SCRATCH: std::cell::Cell<Scratch> = std::cell::Cell::new(Scratch::default());
}

/// The smoothed 36-bin histogram (§SIFT-8). `lanes` is the SIMD width OpenCV's
/// dispatched kernel used: the first `len − len % lanes` samples add a
/// rounded product, the scalar tail is FMA-contracted (§SIFT-13).
#[inline(always)]
fn orientation_hist(img: &Plane, r: usize, c: usize, radius: i32, sigma: f32, lanes: usize) -> [f32; 36] {
    // Taken out and put back rather than borrowed in a closure: a closure
    // would be compiled apart from this FMA-enabled body.
    let mut s = SCRATCH.with(|cell| cell.take());
    let t = raw_hist_with(img, r, c, radius, sigma, lanes, &mut s);
    SCRATCH.with(|cell| cell.set(s));
    smooth(&t)
}

/// The raw bins with their cyclic pads: `t[2..38]` holds bins 0..35,
/// `t[0..2]` and `t[38..40]` copies of the bins across the wrap.
#[inline(always)]
fn raw_hist_with(img: &Plane, r: usize, c: usize, radius: i32, sigma: f32, lanes: usize, s: &mut Scratch) -> [f32; 40] {
    let expf_scale = -1.0 / ((2.0 * sigma) * sigma);
    let (rows, cols) = (img.height as i64, img.width as i64);
    let Scratch { dxs, dys, wts, w_args, weight_rows, oris, mags, offsets, prods } = s;
    // Row |i| of the window's Gaussian weights exp((i² + j²)·scale),
    // j = −rr..=rr, the rows for i and −i being the same: each window row
    // then copies its span. The arguments first, then one pass of the
    // exponential over them, eight lanes on AVX2 (cheaper than one scalar
    // exp per distinct distance and a lookup per entry).
    let rr = radius.max(0) as usize;
    let span = 2 * rr + 1;
    w_args.clear();
    for i in 0..=rr {
        w_args.extend(
            (0..span).map(|k| ((i * i + (k as isize - rr as isize).pow(2) as usize) as i32) as f32 * expf_scale),
        );
    }
    // Eight floats of room after the last row (see the samples below).
    weight_rows.clear();
    weight_rows.resize(w_args.len() + 8, 0.0);
    exp32f_into(w_args, &mut weight_rows[..w_args.len()]);
    // The samples are written eight at a time, each row's last group
    // running on into the next row's place (then overwritten) or the eight
    // floats of room at the end: window rows are 19 to 33 samples, and
    // their remainders taken one by one cost as much as the groups.
    let room = span * span + 8;
    for b in [&mut *dxs, &mut *dys, &mut *wts] {
        if b.len() < room {
            b.resize(room, 0.0);
        }
    }
    let mut len = 0;
    for i in -radius..=radius {
        let y = r as i64 + i as i64;
        if y <= 0 || y >= rows - 1 {
            continue;
        }
        let (up, row, down) = (img.row(y as usize - 1), img.row(y as usize), img.row(y as usize + 1));
        // The window's row AHEAD rows further down, asked for now: the
        // keypoint-ahead prefetch (`prefetch_histogram_window`) alone leaves
        // the first load of each window's bottom row waiting on memory.
        let ahead = y as usize + 1 + AHEAD;
        if ahead < img.height {
            prefetch_span(img.row(ahead), c.saturating_sub(rr + 1), c + rr + 8);
        }
        // The columns with both horizontal neighbours inside the image, as
        // OpenCV's per-sample test keeps them, taken as one slice.
        let j0 = (-radius as i64).max(1 - c as i64);
        let j1 = (radius as i64).min(cols - 2 - c as i64);
        if j0 > j1 {
            continue;
        }
        let (x0, x1) = ((c as i64 + j0) as usize, (c as i64 + j1) as usize + 1);
        let n = x1 - x0;
        let wrow = &weight_rows[i.unsigned_abs() as usize * span + (j0 + rr as i64) as usize..];
        let groups = n.div_ceil(8);
        if x0 + 8 * groups < row.len() {
            for g in 0..groups {
                let (o, x) = (len + 8 * g, x0 + 8 * g);
                let (right, left) = (&row[x + 1..x + 9], &row[x - 1..x + 7]);
                let (above, below) = (&up[x..x + 8], &down[x..x + 8]);
                // Through arrays, so each group is one vector subtraction.
                let (mut dx, mut dy) = ([0f32; 8], [0f32; 8]);
                for l in 0..8 {
                    dx[l] = right[l] - left[l];
                    dy[l] = above[l] - below[l];
                }
                dxs[o..o + 8].copy_from_slice(&dx);
                dys[o..o + 8].copy_from_slice(&dy);
                wts[o..o + 8].copy_from_slice(&wrow[8 * g..8 * g + 8]);
            }
        } else {
            // At the right edge of the image: one by one.
            for k in 0..n {
                let x = x0 + k;
                dxs[len + k] = row[x + 1] - row[x - 1];
                dys[len + k] = up[x] - down[x];
                wts[len + k] = wrow[k];
            }
        }
        len += n;
    }
    let (dxs, dys, wts) = (&dxs[..len], &dys[..len], &wts[..len]);
    let simd_len = len - len % lanes;
    let mut t = [0f32; 36 + 4];
    // t[2..38] holds bins 0..35; t[0..2] and t[38..40] are the cyclic pads.
    gradient_directions_into(dxs, dys, oris, mags);
    let (oris, mags) = (&oris[..], &mags[..]);
    #[cfg(target_arch = "x86_64")]
    let first = if crate::simd::avx2_fma() {
        // SAFETY: the CPU has AVX2 and FMA, the kernel's features.
        unsafe { x86::bin_products(wts, oris, mags, simd_len, offsets, prods, &mut t) };
        simd_len
    } else {
        0
    };
    #[cfg(not(target_arch = "x86_64"))]
    let (first, _) = (0, (offsets, prods));
    for k in first..len {
        let (wt, ori, mag) = (wts[k], oris[k], mags[k]);
        let mut bin = rne((ORI_HIST_BINS as f32 / 360.0) * ori);
        if bin >= 36 {
            bin -= 36;
        }
        if bin < 0 {
            bin += 36;
        }
        let slot = &mut t[bin as usize + 2];
        *slot = if k < simd_len { *slot + wt * mag } else { fma(wt, mag, *slot) };
    }
    t[0] = t[36];
    t[1] = t[37];
    t[38] = t[2];
    t[39] = t[3];
    t
}

/// OpenCV's [1 4 6 4 1]/16 smoothing of the padded raw bins.
#[inline(always)]
fn smooth(t: &[f32; 40]) -> [f32; 36] {
    let mut h = [0f32; 36];
    for (i, hi) in h.iter_mut().enumerate() {
        let a = t[i] + t[i + 4];
        let b = t[i + 1] + t[i + 3];
        let ci = t[i + 2];
        // Bins 0..31 go through the SIMD loop, 32..35 through the scalar
        // tail, which GCC fused in a different order (§SIFT-8, smoothing).
        *hi = if i < 32 { fma(a, 0.0625, fma(b, 0.25, ci * 0.375)) } else { fma(ci, 0.375, fma(a, 0.0625, b * 0.25)) };
    }
    h
}

/// Asks for the cache lines of the (2R+1)² window around (r, c) all at once.
/// The window's rows lie a plane-row apart, a stride the hardware
/// prefetcher does not follow, so otherwise each row is a cache miss the
/// gradient loop waits for in turn.
#[inline(always)]
fn prefetch_window(img: &Plane, r: usize, c: usize, reach: usize) {
    if img.width == 0 || img.height == 0 {
        return;
    }
    let (y0, y1) = (r.saturating_sub(reach), (r + reach).min(img.height - 1));
    for y in y0..=y1 {
        prefetch_span(img.row(y), c.saturating_sub(reach), c + reach);
    }
}

/// How many rows below the one being read the gradient loop asks for.
const AHEAD: usize = 8;

/// Asks for the cache lines of `row[x0..=x1]` (x1 clamped to the row).
#[inline(always)]
fn prefetch_span(row: &[f32], x0: usize, x1: usize) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        let x1 = x1.min(row.len().saturating_sub(1));
        // One prefetch per 64-byte line the span touches.
        let mut x = x0;
        while x <= x1 {
            // SAFETY: a prefetch of an address inside the row never faults.
            unsafe { _mm_prefetch::<_MM_HINT_T0>(row.as_ptr().add(x).cast()) };
            if x == x1 {
                break;
            }
            x = (x + 16).min(x1);
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = (row, x0, x1);
}
