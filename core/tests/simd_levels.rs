//! The kernels of every x86 SIMD level against OpenCV's goldens.
//!
//! A machine with AVX-512 only runs its AVX-512 kernels, but most students'
//! laptops run the AVX2 ones, and a CPU without AVX2 the plain Rust ones.
//! `siftlab_core::internals::set_cap` makes this machine run those instead; each
//! level must give OpenCV's keypoints and descriptors bit for bit (the `noipp`
//! goldens, as `golden.rs` demands of the uncapped run): the AVX2 kernels on
//! both golden sets (OpenCV at 16 and at 8 lanes), the plain ones on the
//! primary set.
//!
//! One test in its own binary: the cap is process-wide.

#![cfg(all(not(target_arch = "wasm32"), target_arch = "x86_64"))]

mod golden_data;

use std::fs;

use golden_data::{golden_sets, primary_set, set_frames, GoldenSet};
use siftlab_core::sift::detect_and_compute;
use siftlab_core::simd::{set_cap, SimdLevel};
use siftlab_core::GrayImage;

/// Keypoints and descriptors of frame `id` equal to the golden's, bit for bit;
/// returns how many keypoints were compared.
fn check_frame(level: SimdLevel, set: &GoldenSet, id: &str) -> usize {
    let golden = set.read("noipp", id);
    let frame = set.frame_path(id);
    let img = GrayImage::decode(&fs::read(&frame).unwrap()).unwrap();
    let ours = detect_and_compute(&img, &set.params());
    let name = set.name;
    assert_eq!(ours.keypoints.len(), golden.keypoints.len(), "{level:?} {name} {id}: keypoint count");
    for (i, (a, b)) in ours.keypoints.iter().zip(&golden.keypoints).enumerate() {
        let bits = |k: &siftlab_core::sift::KeyPoint| {
            [k.x.to_bits(), k.y.to_bits(), k.size.to_bits(), k.angle.to_bits(), k.response.to_bits(), k.octave as u32]
        };
        assert_eq!(bits(a), bits(b), "{level:?} {name} {id} keypoint {i}: ours {a:?}, OpenCV {b:?}");
        assert_eq!(ours.descriptors[i], golden.descriptors[i], "{level:?} {name} {id} descriptor {i}");
    }
    ours.keypoints.len()
}

#[test]
fn every_simd_level_is_bit_exact_against_opencv() {
    // The plain-Rust level calls the library's fmaf for every FMA of the
    // blur (about 1.3 s a frame, against 0.1 s with AVX2): one set only.
    let runs = golden_sets().into_iter().map(|set| (SimdLevel::Avx2, set)).chain([(SimdLevel::Scalar, primary_set())]);
    for (level, set) in runs {
        let frames = set_frames(&set, "noipp");
        set_cap(level);
        let total: usize = frames.iter().map(|id| check_frame(level, &set, id)).sum();
        eprintln!(
            "{level:?}, {} ({} lanes): {total} keypoints on {} frames, keypoints and descriptors bit-exact",
            set.name,
            set.lanes,
            frames.len()
        );
        assert!(total > 0);
    }
    set_cap(SimdLevel::Avx512);
}
