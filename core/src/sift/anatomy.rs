//! SIFT's anatomy: what each stage of the pipeline kept and dropped, recorded
//! by the pipeline itself (no second SIFT). [`anatomy`] runs the same
//! `find_keypoints` as [`super::detect`] with a [`Recorder`] as its
//! [`Observer`], so its final list is the pipeline's by construction; the
//! plain path passes `()`, whose empty methods compile away.
//!
//! The funnel, in pipeline order: scan extrema (26-neighbour test above the
//! contrast pre-threshold, §SIFT-6) → refined (§SIFT-7, each drop with its
//! [`Rejection`]) → oriented (one keypoint per histogram peak, §SIFT-8) →
//! duplicates removed → the best `nfeatures` by response (§SIFT-10).

use super::image::Plane;
use super::keypoint::{KeyPoint, Refined};
use super::orientation::{self, Histogram};
use super::params::SiftParams;
use super::pipeline::{find_keypoints, Pyramid};
use crate::image::GrayImage;
use std::sync::Mutex;

pub use super::observer::{Observer, Rejection};

/// A scan extremum in the input image's pixels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScanPoint {
    /// The reported octave (−1 for the doubled base).
    pub octave: i32,
    pub layer: u8,
    pub x: f32,
    pub y: f32,
}

/// A refined extremum: the keypoint (angle 0, input-image coordinates) and
/// where its histogram is centred.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RefinedPoint {
    pub kp: KeyPoint,
    pub o: usize,
    pub layer: usize,
    pub r: usize,
    pub c: usize,
}

/// The observer that records the funnel. A mutex, since the scan runs on
/// several threads; a KITTI frame has some ten thousand events.
#[derive(Default)]
pub struct Recorder {
    events: Mutex<Events>,
}

#[derive(Default)]
struct Events {
    extrema: Vec<ScanPoint>,
    rejected: Vec<(ScanPoint, Rejection)>,
    refined: Vec<RefinedPoint>,
    oriented: Vec<KeyPoint>,
    deduplicated: Vec<KeyPoint>,
}

fn scan_point(o: usize, layer: usize, r: usize, c: usize) -> ScanPoint {
    // Octave o's pixels are 2^o doubled-base pixels, half as many input ones.
    let s = (1u32 << o) as f32 * 0.5;
    ScanPoint { octave: o as i32 - 1, layer: layer as u8, x: c as f32 * s, y: r as f32 * s }
}

/// The keypoints in input-image coordinates, as the pipeline's last step
/// rescales them.
fn rescaled(kps: &[KeyPoint]) -> Vec<KeyPoint> {
    let mut v = kps.to_vec();
    super::order::rescale_first_octave(&mut v);
    v
}

impl Recorder {
    fn with(&self, f: impl FnOnce(&mut Events)) {
        // A poisoned lock only means another scan thread panicked, and that
        // panic is propagated by the scan itself.
        if let Ok(mut e) = self.events.lock() {
            f(&mut e)
        }
    }
}

impl Observer for Recorder {
    fn extremum(&self, o: usize, layer: usize, r: usize, c: usize) {
        self.with(|e| e.extrema.push(scan_point(o, layer, r, c)));
    }
    fn rejected(&self, o: usize, layer: usize, r: usize, c: usize, why: Rejection) {
        self.with(|e| e.rejected.push((scan_point(o, layer, r, c), why)));
    }
    fn refined(&self, x: &Refined) {
        let kp = rescaled(&[x.kp])[0];
        self.with(|e| e.refined.push(RefinedPoint { kp, o: x.o, layer: x.layer, r: x.r, c: x.c }));
    }
    fn oriented(&self, kps: &[KeyPoint]) {
        let v = rescaled(kps);
        self.with(|e| e.oriented = v);
    }
    fn deduplicated(&self, kps: &[KeyPoint]) {
        let v = rescaled(kps);
        self.with(|e| e.deduplicated = v);
    }
}

/// One stage of the funnel and how many points leave it.
#[derive(Clone, Debug, PartialEq)]
pub struct Stage {
    pub name: &'static str,
    pub count: usize,
}

/// Everything the anatomy view shows for one image.
pub struct Anatomy {
    pub params: SiftParams,
    pub octaves: usize,
    /// Gaussian levels per octave (layers + 3); DoG levels are one fewer.
    pub levels_per_octave: usize,
    /// The Gaussian pyramid, octave `o`'s level `i` at `o * levels_per_octave + i`.
    pub gauss: Vec<Plane>,
    pub extrema: Vec<ScanPoint>,
    pub rejected: Vec<(ScanPoint, Rejection)>,
    pub refined: Vec<RefinedPoint>,
    pub oriented: Vec<KeyPoint>,
    pub deduplicated: Vec<KeyPoint>,
    /// The pipeline's output: `detect`'s keypoints, in OpenCV's order.
    pub kept: Vec<KeyPoint>,
}

/// Runs the pipeline on `img` with a recorder. The scan order depends on the
/// threads; every list is sorted (OpenCV's keypoint order for keypoints) so
/// the result does not.
pub fn anatomy(img: &GrayImage, p: &SiftParams) -> Anatomy {
    let rec = Recorder::default();
    let (kept, gauss) = if img.width() == 0 || img.height() == 0 {
        (Vec::new(), Vec::new())
    } else {
        find_keypoints(img, p, Pyramid::Keep, &rec)
    };
    let e = rec.events.into_inner().unwrap_or_else(|poisoned| poisoned.into_inner());
    let per = p.n_octave_layers + 3;
    let key = |s: &ScanPoint| (s.octave, s.layer, s.y.to_bits(), s.x.to_bits());
    let (mut extrema, mut rejected, mut refined, mut oriented) = (e.extrema, e.rejected, e.refined, e.oriented);
    extrema.sort_by_key(key);
    rejected.sort_by_key(|(s, _)| key(s));
    refined.sort_by_key(|r| (r.o, r.layer, r.r, r.c));
    oriented.sort_by(|a, b| a.y.total_cmp(&b.y).then(a.x.total_cmp(&b.x)).then(a.angle.total_cmp(&b.angle)));
    Anatomy {
        params: p.clone(),
        octaves: gauss.len() / per,
        levels_per_octave: per,
        gauss,
        extrema,
        rejected,
        refined,
        oriented,
        deduplicated: e.deduplicated,
        kept,
    }
}

impl Anatomy {
    /// The funnel's stages in pipeline order; the last one's count is the
    /// number of keypoints `detect_and_compute` returns.
    pub fn stages(&self) -> Vec<Stage> {
        [
            ("extrema", self.extrema.len()),
            ("refined", self.refined.len()),
            ("oriented", self.oriented.len()),
            ("deduplicated", self.deduplicated.len()),
            ("kept", self.kept.len()),
        ]
        .into_iter()
        .map(|(name, count)| Stage { name, count })
        .collect()
    }

    /// How many extrema the refinement dropped, per reason (in [`Rejection::ALL`]'s order).
    pub fn drops(&self) -> [(Rejection, usize); 4] {
        Rejection::ALL.map(|r| (r, self.rejected.iter().filter(|(_, w)| *w == r).count()))
    }

    /// The lowest response kept when `retainBest` cut the list, else `None`.
    pub fn response_cutoff(&self) -> Option<f32> {
        (self.deduplicated.len() > self.kept.len())
            .then(|| self.kept.iter().map(|k| k.response).fold(f32::INFINITY, f32::min))
    }

    /// Gaussian level `i` of octave `o`.
    pub fn gaussian(&self, o: usize, i: usize) -> Option<&Plane> {
        (i < self.levels_per_octave).then(|| self.gauss.get(o * self.levels_per_octave + i)).flatten()
    }

    /// DoG level `j` of octave `o`: level j+1 − level j, the same f32
    /// subtraction the scan makes (§SIFT-5).
    pub fn dog(&self, o: usize, j: usize) -> Option<Plane> {
        let (lo, hi) = (self.gaussian(o, j)?, self.gaussian(o, j + 1)?);
        let mut d = Plane::for_overwrite(lo.width, lo.height);
        for ((d, &a), &b) in d.data.iter_mut().zip(&hi.data).zip(&lo.data) {
            *d = a - b;
        }
        Some(d)
    }

    /// The orientation histogram of every kept keypoint, by the pipeline's
    /// own code (§SIFT-8), from the refined extremum it came from (same
    /// position, size, response and octave: orientation only sets the
    /// angle). The app sends them all, so a click needs no worker round trip.
    pub fn histograms(&self) -> Vec<Option<Histogram>> {
        let per = self.levels_per_octave;
        let key = |k: &KeyPoint| (k.x.to_bits(), k.y.to_bits(), k.size.to_bits(), k.response.to_bits(), k.octave);
        let mut by_key = std::collections::HashMap::new();
        for r in &self.refined {
            by_key.entry(key(&r.kp)).or_insert(r);
        }
        self.kept
            .iter()
            .map(|kp| {
                let src = by_key.get(&key(kp))?;
                let levels = self.gauss.get(src.o * per..(src.o + 1) * per)?;
                Some(orientation::histogram(levels, &unscaled(src), &self.params))
            })
            .collect()
    }
}

/// A recorded refined point as the scan handed it to the orientation stage
/// (doubled-base coordinates, before the rescale the recorder applied).
fn unscaled(src: &RefinedPoint) -> Refined {
    let k = src.kp;
    // Exact inverse of `rescale_first_octave`: ×0.5 and ×2 are exact in f32.
    let kp = KeyPoint {
        x: k.x * 2.0,
        y: k.y * 2.0,
        size: k.size * 2.0,
        octave: (k.octave & !255) | ((k.octave + 1) & 255),
        ..k
    };
    Refined { kp, o: src.o, layer: src.layer, r: src.r, c: src.c }
}

/// A pyramid level as 8-bit gray for display: Gaussian levels are already
/// 0..255 (rounded and clamped); a DoG level is centred on 128 and scaled by
/// its largest |value|, so its sign stays visible.
pub fn level_to_gray(plane: &Plane, dog: bool) -> Vec<u8> {
    values_to_gray(&plane.data, dog)
}

/// [`level_to_gray`] of a level's values (or a thumbnail's: a DoG is then
/// scaled by the thumbnail's own peak), the one rule the CLI's PNGs and the
/// app's canvases share.
pub fn values_to_gray(values: &[f32], dog: bool) -> Vec<u8> {
    if !dog {
        return values.iter().map(|&v| v.round().clamp(0.0, 255.0) as u8).collect();
    }
    let peak = values.iter().fold(0f32, |m, v| m.max(v.abs()));
    let k = if peak > 0.0 { 127.0 / peak } else { 0.0 };
    values.iter().map(|&v| (128.0 + v * k).round().clamp(0.0, 255.0) as u8).collect()
}

/// Every `step`-th pixel of every `step`-th row: a thumbnail whose values
/// are the level's own (so the value under the cursor is exact there).
pub fn subsample(plane: &Plane, step: usize) -> Plane {
    let step = step.max(1);
    let (w, h) = (plane.width.div_ceil(step), plane.height.div_ceil(step));
    let mut out = Plane::for_overwrite(w, h);
    for y in 0..h {
        let src = plane.row(y * step);
        for (x, d) in out.row_mut(y).iter_mut().enumerate() {
            *d = src[x * step];
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plane(w: usize, h: usize, f: impl Fn(usize, usize) -> f32) -> Plane {
        let mut p = Plane::for_overwrite(w, h);
        for y in 0..h {
            for (x, v) in p.row_mut(y).iter_mut().enumerate() {
                *v = f(x, y);
            }
        }
        p
    }

    #[test]
    fn gray_levels_round_and_dog_levels_keep_their_sign() {
        let g = plane(3, 1, |x, _| [-3.0, 127.5, 300.0][x]);
        assert_eq!(level_to_gray(&g, false), vec![0, 128, 255]);
        let d = plane(3, 1, |x, _| [-2.0, 0.0, 1.0][x]);
        assert_eq!(level_to_gray(&d, true), vec![1, 128, 192]);
        assert_eq!(level_to_gray(&plane(2, 1, |_, _| 0.0), true), vec![128, 128]);
    }

    #[test]
    fn subsample_keeps_exact_values() {
        let p = plane(5, 3, |x, y| (10 * y + x) as f32);
        let s = subsample(&p, 2);
        assert_eq!((s.width, s.height), (3, 2));
        assert_eq!(s.data, vec![0.0, 2.0, 4.0, 20.0, 22.0, 24.0]);
    }

    #[test]
    fn empty_image_has_an_empty_funnel() {
        let a = anatomy(&GrayImage::new(0, 0, Vec::new()).unwrap(), &SiftParams::default());
        assert!(a.stages().iter().all(|s| s.count == 0));
        assert_eq!((a.octaves, a.response_cutoff()), (0, None));
    }
}
