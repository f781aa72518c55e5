//! The `sift` target: decode (or take raw pixels), then SIFT, and check that
//! the features are well formed.

use super::check_message;
use siftlab_core::sift::{detect_and_compute, Features, SiftParams};
use siftlab_core::GrayImage;

/// The largest image the SIFT target runs on: SIFT doubles it first, so
/// 4096 pixels keep one execution around a millisecond or two; the thin
/// shapes (up to 512 x 8) still reach the border and octave-count cases.
pub const SIFT_MAX_PIXELS: usize = 4096;
pub const SIFT_MAX_SIDE: usize = 512;

/// Image bytes (or raw pixels) → decode → SIFT, checking the output is
/// well formed.
pub fn sift(data: &[u8]) {
    let Some((&mode, rest)) = data.split_first() else { return };
    let img = if mode & 1 == 0 {
        match GrayImage::decode(rest) {
            Ok(img) => img,
            Err(e) => return check_message(&e),
        }
    } else {
        if rest.len() < 2 {
            return;
        }
        let w = 1 + (rest[0] as usize | ((mode as usize >> 4) << 8)) % SIFT_MAX_SIDE;
        let h = 1 + rest[1] as usize % SIFT_MAX_SIDE;
        if w * h > SIFT_MAX_PIXELS {
            return;
        }
        let px = &rest[2..];
        let data = (0..w * h).map(|i| if px.is_empty() { 0 } else { px[i % px.len()] }).collect();
        GrayImage::new(w, h, data).unwrap()
    };
    let (w, h) = (img.width(), img.height());
    if w * h > SIFT_MAX_PIXELS || w.max(h) > SIFT_MAX_SIDE {
        return;
    }
    let params = SiftParams { opencv_lanes: if mode & 2 == 0 { 8 } else { 16 }, ..SiftParams::default() };
    // On the calling thread: thread start-up would dominate at this size,
    // and LeakSanitizer reports glibc's per-thread TLS destructor record
    // (32 bytes from __cxa_thread_atexit_impl) as a leak in every spawned
    // thread. The threaded stages compute the same bits (golden tests).
    let f = siftlab_core::internals::serial(|| detect_and_compute(&img, &params));
    check_features(&f, w, h, &params);
}

fn check_features(f: &Features, w: usize, h: usize, p: &SiftParams) {
    assert_eq!(f.keypoints.len(), f.descriptors.len());
    // No cap on the count: retainBest keeps every keypoint tied with the
    // nfeatures-th response (a repeated texture gives thousands).
    let _ = p;
    for k in &f.keypoints {
        assert!(k.x.is_finite() && k.y.is_finite(), "{k:?}");
        assert!(k.x >= -1.0 && k.y >= -1.0 && k.x <= w as f32 && k.y <= h as f32, "{k:?} outside {w}x{h}");
        assert!(k.size.is_finite() && k.size > 0.0, "{k:?}");
        assert!(k.angle.is_finite() && (0.0..=360.0).contains(&k.angle), "{k:?}");
        assert!(k.response.is_finite(), "{k:?}");
    }
}
