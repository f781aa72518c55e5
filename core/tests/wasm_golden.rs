//! The core in the browser: SIFT and the matcher compiled to wasm32 and run in headless
//! Chromium (wasm-bindgen-test), checked against the same OpenCV goldens as natively.
//! WebAssembly has no fused multiply-add, so this is where an FMA emulation that is not
//! exact would show.
//!
//! Run by tests/run:
//! `cargo test --release --target wasm32-unknown-unknown -p siftlab-core --no-default-features`

#![cfg(target_arch = "wasm32")]

mod json_mini;

use siftlab_core::matching::{knn_match, match_feature, matching_info, Strategy};
use siftlab_core::sift::{detect_and_compute, Features, SiftParams};
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

const FRAME0: &[u8] = include_bytes!("../../tests/fixtures/mykitti/gray/00/image_0/000000.png");
const FRAME1: &[u8] = include_bytes!("../../tests/fixtures/mykitti/gray/00/image_0/000001.png");
const GOLDEN0: &[u8] = include_bytes!("../../tests/fixtures/golden/noipp/000000.sift");
const GOLDEN1: &[u8] = include_bytes!("../../tests/fixtures/golden/noipp/000001.sift");
const GET_INFO: &str = include_str!("../../tests/fixtures/golden/get_info.jsonl");
const META: &str = include_str!("../../tests/fixtures/golden/meta.json");

/// The SIMD width OpenCV's SIFT kernels ran with where the goldens were written (spec §13).
fn golden_lanes() -> usize {
    let meta = json_mini::parse(META).expect("meta.json is JSON");
    meta.get("opencv_simd_lanes").and_then(|v| v.i64()).expect("opencv_simd_lanes") as usize
}

fn u32_at(b: &[u8], o: usize) -> u32 {
    u32::from_le_bytes([b[o], b[o + 1], b[o + 2], b[o + 3]])
}

/// Checks `ours` against a golden (format in core/tests/golden.rs) field by field,
/// bit for bit; returns the number of keypoints.
fn assert_bit_exact(name: &str, ours: &Features, golden: &[u8]) -> usize {
    assert_eq!(&golden[..8], b"SIFTGLD1", "{name}: bad magic");
    let n = u32_at(golden, 16) as usize;
    assert_eq!(ours.keypoints.len(), n, "{name}: keypoint count");
    assert_eq!(ours.descriptors.len(), n, "{name}: descriptor count");
    for (i, k) in ours.keypoints.iter().enumerate() {
        let o = 20 + 24 * i;
        let want = [u32_at(golden, o), u32_at(golden, o + 4), u32_at(golden, o + 8), u32_at(golden, o + 12), u32_at(golden, o + 16)];
        let got = [k.x.to_bits(), k.y.to_bits(), k.size.to_bits(), k.angle.to_bits(), k.response.to_bits()];
        assert_eq!(got, want, "{name} keypoint {i}: (x, y, size, angle, response) bits differ: {k:?}");
        assert_eq!(k.octave, u32_at(golden, o + 20) as i32, "{name} keypoint {i}: octave");
    }
    let base = 20 + 24 * n;
    for (i, d) in ours.descriptors.iter().enumerate() {
        assert_eq!(&d[..], &golden[base + 128 * i..base + 128 * (i + 1)], "{name} descriptor {i}");
    }
    n
}

fn sift(bytes: &[u8]) -> (Features, f64) {
    let img = GrayImage::decode(bytes).expect("fixture frame decodes");
    let t0 = performance_now();
    let params = SiftParams { opencv_lanes: golden_lanes(), ..SiftParams::default() };
    let f = detect_and_compute(&img, &params);
    (f, performance_now() - t0)
}

#[wasm_bindgen_test]
fn sift_in_the_browser_is_bit_exact_against_opencv() {
    let (f0, ms0) = sift(FRAME0);
    let n0 = assert_bit_exact("000000", &f0, GOLDEN0);
    let (f1, ms1) = sift(FRAME1);
    let n1 = assert_bit_exact("000001", &f1, GOLDEN1);
    // A third run, warm, is the figure bench_compare.sh reports.
    let (_, ms_warm) = sift(FRAME0);
    console_log!(
        "wasm SIFT 1241x376: {n0} + {n1} keypoints bit-exact; detect+compute {ms0:.1} ms, {ms1:.1} ms; \
         WASM_SIFT_MS={ms_warm:.1}"
    );
}

#[wasm_bindgen_test]
fn matching_in_the_browser_equals_the_lab() {
    let (prev, _) = sift(FRAME0);
    let (cur, _) = sift(FRAME1);

    // knn k=2 against the brute-force definition (spec §16): exact integer sums,
    // ascending, ties to the lower train index.
    let t0 = performance_now();
    let knn = knn_match(&prev.descriptors, &cur.descriptors, 2);
    let knn_ms = performance_now() - t0;
    assert_eq!(knn.len(), prev.descriptors.len());
    for (q, row) in knn.iter().enumerate().step_by(97) {
        let mut all: Vec<(u32, usize)> = cur
            .descriptors
            .iter()
            .enumerate()
            .map(|(t, d)| {
                let s: u32 = prev.descriptors[q].iter().zip(d).map(|(&a, &b)| (a as i32 - b as i32).pow(2) as u32).sum();
                (s, t)
            })
            .collect();
        all.sort();
        assert_eq!(row.len(), 2.min(all.len()));
        for (m, &(s, t)) in row.iter().zip(&all) {
            assert_eq!((m.query_idx, m.train_idx), (q, t), "query {q}");
            assert_eq!(m.distance.to_bits(), (s as f32).sqrt().to_bits(), "query {q} distance");
        }
    }

    // Every get_info golden for this pair (FRAME_ID 1 = frames 0 and 1).
    let mut checked = 0;
    for line in GET_INFO.lines().filter(|l| !l.trim().is_empty()) {
        let rec = json_mini::parse(line).expect("golden line is JSON");
        if rec.get("dataset_frame").and_then(|v| v.i64()) != Some(1) {
            continue;
        }
        let algo = rec.get("algo").and_then(|v| v.str()).expect("algo");
        let threshold = rec.get("threshold").and_then(|v| v.f64());
        let feature = rec.get("feature").and_then(|v| v.i64()).expect("feature") as usize;
        let stdout = rec.get("stdout").and_then(|v| v.str()).expect("stdout");
        let want = stdout
            .lines()
            .find_map(|l| l.strip_prefix("ret value: "))
            .expect("golden has a ret value line");
        let s = Strategy::parse(algo, threshold).expect("golden strategy is valid");
        let m = match_feature(&s, &prev, &cur, feature).expect("golden feature is in range");
        let got = matching_info(&prev.keypoints, &cur.keypoints, &m).to_string();
        assert_eq!(got, want, "get_info -a {algo} -t {threshold:?} 1 {feature}");
        checked += 1;
    }
    assert!(checked > 0, "no get_info goldens for FRAME_ID 1");
    console_log!("wasm matching: {checked} get_info goldens identical; knn k=2 1500x1500 {knn_ms:.1} ms; WASM_KNN2_MS={knn_ms:.1}");
}
