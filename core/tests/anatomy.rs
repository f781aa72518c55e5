//! The anatomy's funnel against the plain pipeline on every bundled frame:
//! its final list must be `detect_and_compute`'s keypoints bit for bit, and
//! its stage counts must add up.

#![cfg(not(target_arch = "wasm32"))]

mod golden_data;

use golden_data::kitti;
use siftlab_core::sift::anatomy::{anatomy, Rejection};
use siftlab_core::sift::{detect_and_compute, KeyPoint, SiftParams};
use siftlab_core::GrayImage;

fn bits(k: &[KeyPoint]) -> Vec<[u32; 6]> {
    k.iter()
        .map(|k| [k.x, k.y, k.size, k.angle, k.response].map(f32::to_bits))
        .zip(k.iter().map(|k| k.octave as u32))
        .map(|(f, o)| [f[0], f[1], f[2], f[3], f[4], o])
        .collect()
}

#[test]
fn funnel_ends_in_the_pipelines_keypoints_on_every_bundled_frame() {
    let dir = kitti().join("gray/00/image_0");
    let mut frames: Vec<_> = std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().path()).collect();
    frames.sort();
    assert_eq!(frames.len(), 151, "the bundled MyKITTI frames 0–150");
    let p = SiftParams::default();
    for path in &frames {
        let img = GrayImage::decode(&std::fs::read(path).unwrap()).unwrap();
        let a = anatomy(&img, &p);
        let plain = detect_and_compute(&img, &p);
        let name = path.display();
        assert_eq!(bits(&a.kept), bits(&plain.keypoints), "{name}");
        // Every scan extremum is refined or dropped for one reason.
        let dropped: usize = a.drops().iter().map(|(_, n)| n).sum();
        assert_eq!(a.extrema.len(), a.refined.len() + dropped, "{name}");
        // Orientation only adds keypoints; dedup and retainBest only remove.
        let c: Vec<usize> = a.stages().iter().map(|s| s.count).collect();
        assert!(c[2] >= c[1] && c[3] <= c[2] && c[4] <= c[3] && c[4] >= 1500.min(c[3]), "{name}: {c:?}");
        assert_eq!(a.octaves, 9, "{name}: cvRound(log2(752) - 2) + 1 octaves on the doubled 2482x752 base");
        if let Some(cut) = a.response_cutoff() {
            assert!(a.kept.iter().all(|k| k.response >= cut), "{name}");
            assert!(a.deduplicated.iter().filter(|k| k.response > cut).count() <= 1500, "{name}");
        }
    }
}

/// On one frame, in detail: each kept keypoint's histogram (recomputed by
/// the orientation stage's code) has a peak at the keypoint's angle, and the
/// drop reasons all occur on a real frame.
#[test]
fn histograms_give_each_kept_keypoint_its_angle() {
    let img = GrayImage::decode(&std::fs::read(kitti().join("gray/00/image_0/000000.png")).unwrap()).unwrap();
    let a = anatomy(&img, &SiftParams::default());
    let hists = a.histograms();
    assert_eq!(hists.len(), a.kept.len());
    for (k, h) in a.kept.iter().zip(&hists) {
        let h = h.as_ref().expect("every kept keypoint comes from a recorded refined extremum");
        assert!(h.peaks.iter().any(|&(_, angle)| angle.to_bits() == k.angle.to_bits()), "{k:?}: {:?}", h.peaks);
        let top = h.smoothed.iter().copied().fold(0f32, f32::max);
        assert_eq!(h.threshold, top * 0.8);
        assert!(h.raw.iter().all(|v| *v >= 0.0));
    }
    for (why, n) in a.drops() {
        assert!(n > 0, "{why:?} never happens on frame 0");
    }
    assert_eq!(a.drops().map(|(r, _)| r), Rejection::ALL);
    // Secondary peaks: more oriented keypoints than refined extrema.
    assert!(a.oriented.len() > a.refined.len());
    // The DoG level is the difference of two Gaussian levels, bit for bit.
    let d = a.dog(1, 2).unwrap();
    let (lo, hi) = (a.gaussian(1, 2).unwrap(), a.gaussian(1, 3).unwrap());
    assert_eq!(d.data[1000].to_bits(), (hi.data[1000] - lo.data[1000]).to_bits());
}
