//! The core in the browser: SIFT and the matcher compiled to wasm32 and run in headless
//! Chromium (wasm-bindgen-test), checked against the same OpenCV goldens as natively.
//! WebAssembly has no fused multiply-add, so this is where an FMA emulation that is not
//! exact would show.
//!
//! Run by tests/run, twice: the portable build and the relaxed-SIMD one (the worker
//! www/worker.js loads where relaxed SIMD validates), which adds the test that its
//! fused path is the one these tests ran:
//! `cargo test --release --target wasm32-unknown-unknown -p siftlab-core --no-default-features [--features relaxed-simd]`
//!
//! This file holds the frames, the goldens and the helpers every module uses; the tests
//! are grouped by what they check: `sift_goldens` (SIFT, the manual, the anatomy),
//! `matching`, `num_kernels` (the FMA and gradient kernels), `blur` and `lk`.

#![cfg(target_arch = "wasm32")]

#[path = "../golden_data/format.rs"]
mod golden_format;

mod blur;
mod lk;
mod matching;
mod num_kernels;
mod sift_goldens;

use siftlab_core::sift::{detect_and_compute, Features, KeyPoint, SiftParams};
use siftlab_core::GrayImage;
use wasm_bindgen::prelude::*;
use wasm_bindgen_test::*;

wasm_bindgen_test_configure!(run_in_browser);

#[wasm_bindgen]
extern "C" {
    /// `performance.now()`: the page's high-resolution clock, in ms.
    #[wasm_bindgen(js_namespace = performance, js_name = now)]
    fn performance_now() -> f64;
}

/// The bundled KITTI frames and their 8-lane goldens (`golden-avx2`, the app's
/// default width).
const FRAME0: &[u8] = include_bytes!("../../../www/demo/MyKITTI/gray/00/image_0/000000.png");
const FRAME1: &[u8] = include_bytes!("../../../www/demo/MyKITTI/gray/00/image_0/000001.png");
const GOLDEN0: &[u8] = include_bytes!("../../../tests/fixtures/golden-avx2/noipp/000000.sift");
const GOLDEN1: &[u8] = include_bytes!("../../../tests/fixtures/golden-avx2/noipp/000001.sift");
const IPP0: &[u8] = include_bytes!("../../../tests/fixtures/golden-avx2/ipp/000000.sift");
const IPP1: &[u8] = include_bytes!("../../../tests/fixtures/golden-avx2/ipp/000001.sift");
const GET_INFO: &str = include_str!("../../../tests/fixtures/golden-avx2/get_info.jsonl");
const META: &str = include_str!("../../../tests/fixtures/golden-avx2/meta.json");
/// The 16-lane set (`golden`, an AVX-512 CPU) on its synthetic frame 2, so
/// both of OpenCV's widths are checked in the browser.
const FRAME2_16: &[u8] = include_bytes!("../../../tests/fixtures/synthetic/gray/00/image_0/000002.png");
const GOLDEN2_16: &[u8] = include_bytes!("../../../tests/fixtures/golden/noipp/000002.sift");
const META_16: &str = include_str!("../../../tests/fixtures/golden/meta.json");
/// The lab manual's example pairs (frames 119/120 and 149/150).
const MANUAL_FRAMES: [(usize, &[u8]); 6] = [
    (100, include_bytes!("../../../www/demo/MyKITTI/gray/00/image_0/000100.png")),
    (101, include_bytes!("../../../www/demo/MyKITTI/gray/00/image_0/000101.png")),
    (119, include_bytes!("../../../www/demo/MyKITTI/gray/00/image_0/000119.png")),
    (120, include_bytes!("../../../www/demo/MyKITTI/gray/00/image_0/000120.png")),
    (149, include_bytes!("../../../www/demo/MyKITTI/gray/00/image_0/000149.png")),
    (150, include_bytes!("../../../www/demo/MyKITTI/gray/00/image_0/000150.png")),
];

/// The SIMD width OpenCV's SIFT kernels ran with where the goldens were written (docs/fidelity.md §SIFT-13).
fn golden_lanes() -> usize {
    golden_format::meta_lanes(META, "golden-avx2")
}

/// Compares `ours` with a golden field by field, bit for bit; returns (keypoints,
/// keypoints bit-exact, descriptors bit-exact) and logs the first differences.
fn compare(name: &str, ours: &Features, golden: &[u8]) -> (usize, usize, usize) {
    let golden = golden_format::parse_golden(golden, name);
    let n = golden.keypoints.len();
    assert_eq!(ours.keypoints.len(), n, "{name}: keypoint count");
    assert_eq!(ours.descriptors.len(), n, "{name}: descriptor count");
    let (mut kp_ok, mut desc_ok, mut shown) = (0, 0, 0);
    let bits = |k: &KeyPoint| [k.x.to_bits(), k.y.to_bits(), k.size.to_bits(), k.angle.to_bits(), k.response.to_bits()];
    for (i, (k, g)) in ours.keypoints.iter().zip(&golden.keypoints).enumerate() {
        let (got, want) = (bits(k), bits(g));
        if got == want && k.octave == g.octave {
            kp_ok += 1;
        } else if shown < 5 {
            shown += 1;
            console_log!("{name} keypoint {i}: (x, y, size, angle, response) bits ours {got:?} opencv {want:?}; {k:?}");
        }
        if ours.descriptors[i] == golden.descriptors[i] {
            desc_ok += 1;
        } else if shown < 5 {
            shown += 1;
            console_log!("{name} descriptor {i} differs");
        }
    }
    (n, kp_ok, desc_ok)
}

fn sift(bytes: &[u8]) -> (Features, f64) {
    sift_at(bytes, golden_lanes())
}

fn sift_at(bytes: &[u8], lanes: usize) -> (Features, f64) {
    let img = GrayImage::decode(bytes).expect("fixture frame decodes");
    let t0 = performance_now();
    let params = SiftParams { opencv_lanes: lanes, ..SiftParams::default() };
    let f = detect_and_compute(&img, &params);
    (f, performance_now() - t0)
}
