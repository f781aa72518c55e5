//! The worker side of "see inside": SIFT's anatomy of a frame and the
//! whole-frame sweep of a pair, by the core, packed for the page.

use crate::platform::now_ms;
use crate::protocol::inside::{AnatomyData, InsideReply, InsideRequest, LevelThumb, SweepData};
use siftlab_core::matching::epipolar::fundamental;
use siftlab_core::matching::sweep::sweep;
use siftlab_core::sift::anatomy::{anatomy, subsample, Anatomy, Rejection};
use siftlab_core::sift::SiftParams;
use siftlab_core::GrayImage;

/// Thumbnails are at most this wide (the first octave, 2482 px on KITTI, is
/// sent every 4th pixel; octaves from the third on at full size).
pub const THUMB_MAX_WIDTH: usize = 640;

/// The subsampling step that brings `width` under [`THUMB_MAX_WIDTH`].
pub fn thumb_step(width: usize) -> usize {
    width.div_ceil(THUMB_MAX_WIDTH).max(1)
}

/// Packs an anatomy for the page.
pub fn pack_anatomy(a: &Anatomy, ms: f64) -> AnatomyData {
    let xy = |pts: &mut dyn Iterator<Item = (f32, f32)>| pts.flat_map(|(x, y)| [x, y]).collect::<Vec<f32>>();
    let mut levels = Vec::new();
    for o in 0..a.octaves {
        for i in 0..a.levels_per_octave {
            let dog = a.dog(o, i);
            let planes = [(false, a.gaussian(o, i)), (true, dog.as_ref())];
            for (is_dog, plane) in planes {
                let Some(p) = plane else { continue };
                let step = thumb_step(p.width);
                let mut t = subsample(p, step);
                levels.push(LevelThumb {
                    octave: o as u32,
                    index: i as u32,
                    dog: is_dog,
                    step: step as u32,
                    width: t.width as u32,
                    height: t.height as u32,
                    values: std::mem::take(&mut t.data),
                });
            }
        }
    }
    let kps = |k: &[siftlab_core::sift::KeyPoint]| xy(&mut k.iter().map(|k| (k.x, k.y)));
    let points = vec![
        xy(&mut a.extrema.iter().map(|s| (s.x, s.y))),
        xy(&mut a.refined.iter().map(|r| (r.kp.x, r.kp.y))),
        kps(&a.oriented),
        kps(&a.deduplicated),
        kps(&a.kept),
    ];
    let (mut hist, mut hist_thr, mut peak_counts, mut peaks) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for h in a.histograms() {
        match h {
            Some(h) => {
                hist.extend_from_slice(&h.raw);
                hist.extend_from_slice(&h.smoothed);
                hist_thr.push(h.threshold);
                peak_counts.push(h.peaks.len() as u8);
                peaks.extend(h.peaks.iter().flat_map(|&(b, a)| [b, a]));
            }
            None => {
                hist.extend([f32::NAN; 72]);
                hist_thr.push(f32::NAN);
                peak_counts.push(0);
            }
        }
    }
    let why = |r: Rejection| Rejection::ALL.iter().position(|&x| x == r).unwrap_or(0) as u8;
    AnatomyData {
        octaves: a.octaves as u32,
        levels_per_octave: a.levels_per_octave as u32,
        stages: a.stages().iter().map(|s| (s.name.to_string(), s.count as u32)).collect(),
        drops: a.drops().iter().map(|(r, n)| (r.name().to_string(), *n as u32)).collect(),
        cutoff: a.response_cutoff(),
        levels,
        points,
        rejected: xy(&mut a.rejected.iter().map(|(s, _)| (s.x, s.y))),
        rejected_why: a.rejected.iter().map(|(_, r)| why(*r)).collect(),
        hist,
        hist_thr,
        peak_counts,
        peaks,
        ms,
    }
}

/// Handles one "see inside" request, posting progress and the outcome.
pub fn handle(req: InsideRequest, post: &dyn Fn(InsideReply)) {
    match req {
        InsideRequest::Anatomy { id, bytes, lanes } => {
            post(InsideReply::Progress { id, stage: "decoding the image".into() });
            let img = match GrayImage::decode(&bytes) {
                Ok(img) => img,
                Err(e) => return post(InsideReply::Failed { id, message: e.to_string() }),
            };
            post(InsideReply::Progress { id, stage: "SIFT with every stage recorded".into() });
            let t0 = now_ms();
            let params = SiftParams { opencv_lanes: lanes as usize, ..SiftParams::default() };
            let a = anatomy(&img, &params);
            let data = pack_anatomy(&a, now_ms() - t0);
            post(InsideReply::Anatomy { id, data: Box::new(data) });
        }
        InsideRequest::WholeFrame { id, prev, cur, poses, camera, px } => {
            post(InsideReply::Progress { id, stage: "every distance of the pair, sorted once".into() });
            let t0 = now_ms();
            let f = match poses.map(|ab| fundamental(&ab[0], &ab[1], &camera)).transpose() {
                Ok(f) => f,
                Err(e) => return post(InsideReply::Failed { id, message: e.to_string() }),
            };
            match sweep(&prev, &cur, f.as_ref().map(|f| (f, px))) {
                Ok(s) => {
                    let data = SweepData { sweep: s, judged: f.is_some(), px, ms: now_ms() - t0 };
                    post(InsideReply::WholeFrame { id, data: Box::new(data) });
                }
                Err(e) => post(InsideReply::Failed { id, message: e.to_string() }),
            }
        }
    }
}
