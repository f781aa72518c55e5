//! The core in the browser: SIFT and the matcher compiled to wasm32 and run in headless
//! Chromium (wasm-bindgen-test), checked against the same OpenCV goldens as natively.
//! WebAssembly has no fused multiply-add, so this is where an FMA emulation that is not
//! exact would show.
//!
//! Run by tests/run, twice: the portable build and the relaxed-SIMD one (the worker
//! www/worker.js loads where relaxed SIMD validates), which adds the test that its
//! fused path is the one these tests ran:
//! `cargo test --release --target wasm32-unknown-unknown -p siftlab-core --no-default-features [--features relaxed-simd]`

#![cfg(target_arch = "wasm32")]

#[path = "golden_data/format.rs"]
mod golden_format;

use siftlab_core::json;
use siftlab_core::matching::{knn_match, match_feature, matching_info, Strategy};
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
const FRAME0: &[u8] = include_bytes!("../../www/demo/MyKITTI/gray/00/image_0/000000.png");
const FRAME1: &[u8] = include_bytes!("../../www/demo/MyKITTI/gray/00/image_0/000001.png");
const GOLDEN0: &[u8] = include_bytes!("../../tests/fixtures/golden-avx2/noipp/000000.sift");
const GOLDEN1: &[u8] = include_bytes!("../../tests/fixtures/golden-avx2/noipp/000001.sift");
const IPP0: &[u8] = include_bytes!("../../tests/fixtures/golden-avx2/ipp/000000.sift");
const IPP1: &[u8] = include_bytes!("../../tests/fixtures/golden-avx2/ipp/000001.sift");
const GET_INFO: &str = include_str!("../../tests/fixtures/golden-avx2/get_info.jsonl");
const META: &str = include_str!("../../tests/fixtures/golden-avx2/meta.json");
/// The 16-lane set (`golden`, an AVX-512 CPU) on its synthetic frame 2, so
/// both of OpenCV's widths are checked in the browser.
const FRAME2_16: &[u8] = include_bytes!("../../tests/fixtures/synthetic/gray/00/image_0/000002.png");
const GOLDEN2_16: &[u8] = include_bytes!("../../tests/fixtures/golden/noipp/000002.sift");
const META_16: &str = include_str!("../../tests/fixtures/golden/meta.json");
/// The lab manual's example pairs (frames 119/120 and 149/150).
const MANUAL_FRAMES: [(usize, &[u8]); 6] = [
    (100, include_bytes!("../../www/demo/MyKITTI/gray/00/image_0/000100.png")),
    (101, include_bytes!("../../www/demo/MyKITTI/gray/00/image_0/000101.png")),
    (119, include_bytes!("../../www/demo/MyKITTI/gray/00/image_0/000119.png")),
    (120, include_bytes!("../../www/demo/MyKITTI/gray/00/image_0/000120.png")),
    (149, include_bytes!("../../www/demo/MyKITTI/gray/00/image_0/000149.png")),
    (150, include_bytes!("../../www/demo/MyKITTI/gray/00/image_0/000150.png")),
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

#[wasm_bindgen_test]
fn sift_in_the_browser_is_bit_exact_against_opencv() {
    let (f0, ms0) = sift(FRAME0);
    let (f1, ms1) = sift(FRAME1);
    // A third run, warm, is the figure bench_compare.sh reports.
    let (_, ms_warm) = sift(FRAME0);
    let (mut n, mut kp_ok, mut desc_ok) = (0, 0, 0);
    for (name, f, g) in [("000000", &f0, GOLDEN0), ("000001", &f1, GOLDEN1)] {
        let (a, b, c) = compare(name, f, g);
        (n, kp_ok, desc_ok) = (n + a, kp_ok + b, desc_ok + c);
    }
    console_log!(
        "wasm SIFT 1241x376 vs OpenCV (IPP off): keypoints bit-exact {kp_ok}/{n}, descriptors bit-exact {desc_ok}/{n}; \
         detect+compute {ms0:.1} ms, {ms1:.1} ms; WASM_SIFT_MS={ms_warm:.1}"
    );
    assert_eq!((kp_ok, desc_ok), (n, n), "wasm SIFT differs from OpenCV (IPP off)");
}

/// Both SIMD widths in the browser: the 16-lane goldens bit for bit at 16
/// lanes (the 8-lane ones are checked above), and missed at 8, so the width
/// is seen.
#[wasm_bindgen_test]
fn sift_in_the_browser_follows_opencvs_simd_width() {
    let lanes_16 = golden_format::meta_lanes(META_16, "golden");
    assert_ne!(lanes_16, golden_lanes(), "the two golden sets should have different widths");
    let (f, ms) = sift_at(FRAME2_16, lanes_16);
    let (n, kp_ok, desc_ok) = compare(&format!("synthetic 000002 at {lanes_16} lanes"), &f, GOLDEN2_16);
    console_log!("wasm SIFT synthetic frame 2 at {lanes_16} lanes vs OpenCV (IPP off): keypoints {kp_ok}/{n}, descriptors {desc_ok}/{n} bit-exact; {ms:.1} ms");
    assert_eq!((kp_ok, desc_ok), (n, n), "wasm SIFT at {lanes_16} lanes differs from OpenCV's");
    let (f, _) = sift_at(FRAME2_16, golden_lanes());
    let (n, kp_ok, desc_ok) = compare("synthetic 000002 at the other width", &f, GOLDEN2_16);
    assert!((kp_ok, desc_ok) != (n, n), "{} lanes gave the {lanes_16}-lane goldens too", golden_lanes());
}

/// The lab manual's `get_info` examples on our SIFT in the browser: exactly
/// the manual's printed values (the introduction's at feature 132).
#[wasm_bindgen_test]
fn the_manuals_examples_reproduce_in_the_browser() {
    use siftlab_core::manual::EXAMPLES;
    let features: Vec<(usize, Features)> = MANUAL_FRAMES.iter().map(|&(id, bytes)| (id, sift(bytes).0)).collect();
    let get = |id: usize| &features.iter().find(|(i, _)| *i == id).expect("a manual frame").1;
    for e in &EXAMPLES {
        let (prev, cur) = (get(e.frame - 1), get(e.frame));
        let info = |feature| {
            let m = match_feature(&e.strategy(), prev, cur, feature).expect("the manual's feature exists");
            matching_info(&prev.keypoints, &cur.keypoints, &m).to_string()
        };
        assert_eq!(info(e.feature), e.siftlab_value(), "{}: {}", e.task, e.command());
        if let Some(d) = e.differs {
            assert_eq!(info(d.feature), e.expected, "{}", e.command_for(d.feature));
        }
    }
    console_log!("wasm: the manual's {} get_info examples reproduce exactly", EXAMPLES.len());
}

/// OpenCV's own features (default-wheel golden) as `Features`.
fn golden_features(golden: &[u8]) -> Features {
    let g = golden_format::parse_golden(golden, "ipp golden");
    Features { keypoints: g.keypoints, descriptors: g.descriptors }
}

#[wasm_bindgen_test]
fn matching_in_the_browser_equals_the_lab() {
    // The matcher alone, in wasm: OpenCV's own features of frames 0 and 1 (default
    // wheel, which the get_info goldens used); our SIFT is checked above.
    let (prev, cur) = (golden_features(IPP0), golden_features(IPP1));

    // knn k=2 against the brute-force definition (docs/fidelity.md §SIFT-16): exact integer sums,
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
                let s: u32 =
                    prev.descriptors[q].iter().zip(d).map(|(&a, &b)| (a as i32 - b as i32).pow(2) as u32).sum();
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
    let (mut checked, mut failures) = (0, Vec::new());
    for line in GET_INFO.lines().filter(|l| !l.trim().is_empty()) {
        let rec = json::parse(line).expect("golden line is JSON");
        if rec.get("dataset_frame").and_then(|v| v.as_i64()) != Some(1) {
            continue;
        }
        let algo = rec.get("algo").and_then(|v| v.as_str()).expect("algo");
        let threshold = rec.get("threshold").and_then(|v| v.as_f64());
        let feature = rec.get("feature").and_then(|v| v.as_i64()).expect("feature") as usize;
        let stdout = rec.get("stdout").and_then(|v| v.as_str()).expect("stdout");
        let want = stdout.lines().find_map(|l| l.strip_prefix("ret value: ")).expect("golden has a ret value line");
        let s = Strategy::parse(algo, threshold).expect("golden strategy is valid");
        let m = match_feature(&s, &prev, &cur, feature).expect("golden feature is in range");
        let got = matching_info(&prev.keypoints, &cur.keypoints, &m).to_string();
        if got != want {
            let at = want.bytes().zip(got.bytes()).position(|(a, b)| a != b).unwrap_or(want.len().min(got.len()));
            let clip = |t: &str| t.get(at.saturating_sub(40)..(at + 40).min(t.len())).unwrap_or("").to_owned();
            failures.push(format!(
                "get_info -a {algo} -t {threshold:?} 1 {feature}: opencv ...{}... ours ...{}...",
                clip(want),
                clip(&got)
            ));
        }
        checked += 1;
    }
    console_log!(
        "wasm matching: {}/{checked} get_info goldens (FRAME_ID 1) identical; knn k=2 {}x{} {knn_ms:.1} ms; WASM_KNN2_MS={knn_ms:.1}",
        checked - failures.len(),
        prev.descriptors.len(),
        cur.descriptors.len()
    );
    assert!(checked > 0, "no get_info goldens for FRAME_ID 1");
    assert!(failures.is_empty(), "{} of {checked} differ:\n{}", failures.len(), failures.join("\n"));
}

/// Multiply-adds where an FMA is easy to get wrong.
const FMA_SPECIAL: [(f32, f32, f32); 6] = [
    (1.0 + f32::EPSILON, 1.0 + f32::EPSILON, -1.0), // exact result 2^-22 + 2^-46: halfway in f64
    (1.0 + 1.0 / 4096.0, 1.0 + 1.0 / 4096.0, 0.0),  // 1 + 2^-11 + 2^-24: an f32 halfway point
    (1.0 + 1.0 / 4096.0, 1.0 + 1.0 / 4096.0, -(1.0 + 1.0 / 2048.0)), // 2^-24 fused, 0 unfused
    (3.0, 5.0, -15.0),                              // exact zero
    (1e-20, 1e-20, 0.0),                            // f32-subnormal product
    (1e-20, -1e-20, 1e-39),                         // subnormal sum
];

/// Random f32s: `random(lo)` takes the sign and mantissa bits of an xorshift draw
/// and `lo` as its exponent bits.
fn random_f32(seed: u64) -> impl FnMut(u32) -> f32 {
    let mut state = seed;
    move |lo| {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        f32::from_bits((state as u32 & 0x807F_FFFF) | lo)
    }
}

/// The lane-wise FMA emulation the wasm blur and gradient kernels use equals the scalar one (itself tested
/// against hardware FMA natively) on random triples and on sums that land exactly on an
/// f32 halfway point, zero or an f32-subnormal magnitude (the lanes that take the fallback).
#[wasm_bindgen_test]
fn simd_fma_emulation_equals_the_scalar_one() {
    use core::arch::wasm32::*;
    use siftlab_core::internals::num::{fma_emulated, fma_emulated_x4};
    let mut random = random_f32(0x9E37_79B9_7F4A_7C15);
    let mut checked = 0;
    for round in 0..250_000 {
        let (a, b, c) = match FMA_SPECIAL.get(round) {
            // The special case in lane 2, random values around it.
            Some(&(x, y, z)) => (
                [random(0x3F00_0000), random(0x4000_0000), x, random(0x3E00_0000)],
                [random(0x3F00_0000), random(0x3E00_0000), y, random(0x3F00_0000)],
                [random(0x3300_0000), random(0x4300_0000), z, random(0x3F00_0000)],
            ),
            // Half the rounds with one weight in every lane, as the blur calls it.
            None => {
                let w = random(0x3F00_0000);
                (
                    [random(0x3F00_0000), random(0x4000_0000), random(0x3E00_0000), random(0x4300_0000)],
                    if round % 2 == 0 {
                        [w; 4]
                    } else {
                        [w, random(0x3E00_0000), random(0x4000_0000), random(0x3F00_0000)]
                    },
                    [random(0x3300_0000), random(0x4300_0000), random(0x3F00_0000), -random(0x4000_0000)],
                )
            }
        };
        let v = |x: [f32; 4]| f32x4(x[0], x[1], x[2], x[3]);
        let got = fma_emulated_x4(v(a), v(b), v(c));
        let got = [
            f32x4_extract_lane::<0>(got),
            f32x4_extract_lane::<1>(got),
            f32x4_extract_lane::<2>(got),
            f32x4_extract_lane::<3>(got),
        ];
        for l in 0..4 {
            assert_eq!(
                got[l].to_bits(),
                fma_emulated(a[l], b[l], c[l]).to_bits(),
                "lane {l}: {} * {} + {}",
                a[l],
                b[l],
                c[l]
            );
            checked += 1;
        }
    }
    assert_eq!(checked, 1_000_000);
}

/// The four-lane gradient kernels of orientation and descriptors (`num::x4`, behind
/// `gradient_directions` and `gradient_samples`) equal the scalar `fast_atan2_deg`,
/// `magnitude` and `exp32f` on every element: random differences of 8-bit-scale pixels,
/// the axes and diagonals where fastAtan2's branches switch (±0 included), and exponents
/// from 0 to beyond exp32f's clamp. Lengths not a multiple of 4 check the scalar tail.
#[wasm_bindgen_test]
fn gradient_kernels_equal_the_scalar_ones() {
    use siftlab_core::internals::num::{exp32f, fast_atan2_deg, gradient_directions, gradient_samples, magnitude};
    let mut random = random_f32(0x243F_6A88_85A3_08D3);
    let edges = [0.0f32, -0.0, 1.0, -1.0, 0.5, -0.5, 255.0, -255.0, 1e-30, -1e-30];
    let (mut dxs, mut dys) = (Vec::new(), Vec::new());
    for &x in &edges {
        for &y in &edges {
            dxs.push(x);
            dys.push(y);
        }
    }
    for _ in 0..100_003 {
        // |v| in [0.5, 256): the range of a difference of two pixels.
        dxs.push(random(0x3F00_0000) * 2f32.powi((random(0x3F80_0000) * 8.0) as i32));
        dys.push(random(0x3F00_0000) * 2f32.powi((random(0x3F80_0000) * 8.0) as i32));
    }
    let args: Vec<f32> = (0..dxs.len())
        .map(|i| if i % 97 == 0 { -3000.0 + i as f32 * 1e-3 } else { -random(0x3F80_0000).abs() * 40.0 })
        .collect();
    let (oris, mags) = gradient_directions(&dxs, &dys);
    let (oris2, mags2, wts) = gradient_samples(&dxs, &dys, &args);
    for i in 0..dxs.len() {
        let (x, y) = (dxs[i], dys[i]);
        assert_eq!(oris[i].to_bits(), fast_atan2_deg(y, x).to_bits(), "atan2({y}, {x}) at {i}");
        assert_eq!(mags[i].to_bits(), magnitude(x, y).to_bits(), "magnitude({x}, {y}) at {i}");
        assert_eq!((oris2[i].to_bits(), mags2[i].to_bits()), (oris[i].to_bits(), mags[i].to_bits()));
        assert_eq!(wts[i].to_bits(), exp32f(args[i]).to_bits(), "exp32f({}) at {i}", args[i]);
    }
    assert_eq!(dxs.len(), 100_103);
}

/// The relaxed-SIMD build (`--features relaxed-simd`; www/worker.js loads it wherever
/// relaxed SIMD validates): Chromium's `f32x4.relaxed_madd` is fused, so every other test
/// of this run (SIFT against OpenCV, the blur against the scalar filter) went through the
/// engine's FMA and not the emulation; and that FMA, as `num::fma` uses it, equals the
/// exact emulation on random triples and on halfway, zero and subnormal cases.
#[cfg(feature = "relaxed-simd")]
#[wasm_bindgen_test]
fn relaxed_madd_is_fused_here_and_equals_the_exact_fma() {
    use siftlab_core::internals::num::{fma, fma_emulated, fma_engine, relaxed_madd_is_fused};
    assert!(
        relaxed_madd_is_fused(),
        "this engine's relaxed_madd is not fused: the relaxed build falls back to the emulation, \
         and this run did not test its fused path"
    );
    assert!(fma_engine().starts_with("relaxed SIMD"), "{}", fma_engine());
    let mut random = random_f32(0xD1B5_4A32_D192_ED03);
    for &(a, b, c) in &FMA_SPECIAL {
        assert_eq!(fma(a, b, c).to_bits(), fma_emulated(a, b, c).to_bits(), "{a} * {b} + {c}");
    }
    for _ in 0..1_000_000 {
        let (a, b, c) = (random(0x3F00_0000), random(0x4000_0000), random(0x3F80_0000));
        assert_eq!(fma(a, b, c).to_bits(), fma_emulated(a, b, c).to_bits(), "{a} * {b} + {c}");
    }
}

include!("../src/vo/testdata/lk_golden.rs");

/// LK in the browser: the simd128 kernels against OpenCV's calcOpticalFlowPyrLK
/// (the 68-point golden of the native unit test) and against the portable
/// kernels, bit for bit, on the KITTI-sized fixture pair (every frame-0 SIFT
/// keypoint, as the lab tracks them) and on a noisy pair whose large
/// gradients force the replay of OpenCV's f32 order.
#[wasm_bindgen_test]
fn lk_in_the_browser_is_bit_exact() {
    use siftlab_core::internals::calc_optical_flow_pyr_lk_portable;
    use siftlab_core::vo::{calc_optical_flow_pyr_lk, LkParams, LkResult};
    let lk = LkParams::default();
    let bits = |r: &LkResult, i: usize| [r.next_pts[i][0].to_bits(), r.next_pts[i][1].to_bits()];

    let prev = GrayImage::decode(include_bytes!("../src/vo/testdata/lk_prev.png")).unwrap();
    let next = GrayImage::decode(include_bytes!("../src/vo/testdata/lk_next.png")).unwrap();
    let pts: Vec<[f32; 2]> = LK_GOLDEN.iter().map(|g| g.0).collect();
    let out = calc_optical_flow_pyr_lk(&prev, &next, &pts, &lk);
    for (i, g) in LK_GOLDEN.iter().enumerate() {
        assert_eq!(out.status[i] as u8, g.2, "status of point {i}");
        assert_eq!(bits(&out, i), g.1, "point {i} {:?}", g.0);
        if g.2 == 1 {
            assert_eq!(out.err[i].to_bits(), g.3, "err of point {i}");
        }
    }

    let (f0, _) = sift(FRAME0);
    let frame0 = GrayImage::decode(FRAME0).unwrap();
    let frame1 = GrayImage::decode(FRAME1).unwrap();
    let pts: Vec<[f32; 2]> = f0.keypoints.iter().map(|k| [k.x, k.y]).collect();
    let t0 = performance_now();
    let simd = calc_optical_flow_pyr_lk(&frame0, &frame1, &pts, &lk);
    let t1 = performance_now();
    let portable = calc_optical_flow_pyr_lk_portable(&frame0, &frame1, &pts, &lk);
    let t2 = performance_now();
    assert_eq!(simd.status, portable.status);
    for i in 0..pts.len() {
        assert_eq!(bits(&simd, i), bits(&portable, i), "fixture point {i}");
        if simd.status[i] {
            assert_eq!(simd.err[i].to_bits(), portable.err[i].to_bits(), "err of fixture point {i}");
        }
    }
    let tracked = simd.status.iter().filter(|&&s| s).count();

    // A noisy pair: xorshift noise of ±90 on smooth texture, shifted by 1.3 px.
    let (w, h) = (320usize, 200usize);
    let noisy = |dx: f64| {
        let mut s = 0x9e37_79b9_7f4a_7c15u64;
        let data = (0..w * h)
            .map(|i| {
                s ^= s << 13;
                s ^= s >> 7;
                s ^= s << 17;
                let (x, y) = ((i % w) as f64 + dx, (i / w) as f64);
                let v = 128.0 + 60.0 * (x * 0.11 + y * 0.07).sin() + 40.0 * (y * 0.13 - x * 0.05).cos();
                (v as i64 + (s % 181) as i64 - 90).clamp(0, 255) as u8
            })
            .collect();
        GrayImage::new(w, h, data).unwrap()
    };
    let (a, b) = (noisy(0.0), noisy(1.3));
    let grid: Vec<[f32; 2]> =
        (0..400).map(|k| [-5.0 + (k % 25) as f32 * 13.7, -5.0 + (k / 25) as f32 * 13.3]).collect();
    let (simd, portable) =
        (calc_optical_flow_pyr_lk(&a, &b, &grid, &lk), calc_optical_flow_pyr_lk_portable(&a, &b, &grid, &lk));
    assert_eq!(simd, portable);
    console_log!(
        "wasm LK: 68/68 OpenCV golden points bit-exact; {tracked}/{} fixture keypoints tracked, simd128 = portable \
         bit for bit; WASM_LK_MS={:.1} (portable {:.1} ms)",
        pts.len(),
        t1 - t0,
        t2 - t1
    );
}

/// A plain separable Gaussian filter on the exact scalar FMA, as docs/fidelity.md §SIFT-3 states it: row
/// pass (first tap a product, then one FMA per tap, BORDER_REFLECT_101), then the
/// symmetric column pass (centre product, then one FMA per pair of rows).
fn reference_blur(src: &siftlab_core::internals::Plane, sigma: f64) -> Vec<f32> {
    use siftlab_core::internals::gaussian_kernel;
    use siftlab_core::internals::num::fma_emulated;
    let (w, h) = (src.width, src.height);
    let k = gaussian_kernel(sigma);
    let r = k.len() / 2;
    let reflect = |mut p: isize, len: usize| {
        let len = len as isize;
        while p < 0 || p >= len {
            p = if p < 0 { -p } else { 2 * (len - 1) - p };
        }
        p as usize
    };
    let mut tmp = vec![0f32; w * h];
    for y in 0..h {
        for x in 0..w {
            let at = |t: usize| src.data[y * w + reflect(x as isize + t as isize - r as isize, w)];
            let mut a = at(0) * k[0];
            for (t, &kt) in k.iter().enumerate().skip(1) {
                a = fma_emulated(at(t), kt, a);
            }
            tmp[y * w + x] = a;
        }
    }
    let mut out = vec![0f32; w * h];
    for y in 0..h {
        for x in 0..w {
            let at = |dy: isize| tmp[reflect(y as isize + dy, h) * w + x];
            let mut a = at(0) * k[r];
            for t in 1..=r {
                a = fma_emulated(at(t as isize) + at(-(t as isize)), k[r + t], a);
            }
            out[y * w + x] = a;
        }
    }
    out
}

/// The wasm Gaussian blur equals [`reference_blur`] bit for bit, on both of its paths:
/// tame data (every value 0 or in [2^-100, 2^100]), where the FMA check is ORed over a
/// 16-pixel block and a flagged block is redone with the scalar FMA, and other data
/// (negative values, values near 2^-110), where every FMA is checked as it is made.
/// Each image is blurred three times in a row at the pyramid's sigmas, as SIFT chains
/// its levels.
#[wasm_bindgen_test]
fn blur_in_the_browser_equals_the_scalar_filter() {
    use siftlab_core::internals::gaussian_blur;
    use siftlab_core::internals::Plane;
    let mut state = 0x2545_F491_4F6C_DD1Du64;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    /// (name, width, height, pixel from a random draw)
    type Case = (&'static str, usize, usize, fn(u64) -> f32);
    let cases: [Case; 4] = [
        ("8-bit image", 203, 61, |r| (r % 256) as f32),
        ("8-bit image with black areas", 97, 40, |r| if r % 3 == 0 { 0.0 } else { (r % 256) as f32 }),
        ("negative values", 131, 37, |r| (r % 512) as f32 - 255.5),
        ("values near 2^-110", 77, 29, |r| if r % 2 == 0 { 0.0 } else { (r % 1000) as f32 * 7.7e-34 }),
    ];
    let mut checked = 0;
    for (name, w, h, value) in cases {
        let mut img = Plane::new(w, h);
        for v in img.data.iter_mut() {
            *v = value(next() >> 11);
        }
        for sigma in [1.2262734984654078, 1.9465878414647133, 3.090015587289591] {
            let want = reference_blur(&img, sigma);
            let got = gaussian_blur(&img, sigma);
            for (i, (g, e)) in got.data.iter().zip(&want).enumerate() {
                assert_eq!(g.to_bits(), e.to_bits(), "{name}, sigma {sigma}: pixel ({}, {}): {g} vs {e}", i % w, i / w);
            }
            checked += want.len();
            img = got;
        }
    }
    assert_eq!(checked, 3 * (203 * 61 + 97 * 40 + 131 * 37 + 77 * 29));
}

/// SIFT's anatomy in the browser: the funnel's final list is the plain
/// pipeline's keypoints bit for bit (frames 0, 1 and the manual's 120), and
/// its time against plain SIFT's (the app's budget: at most 2x).
#[wasm_bindgen_test]
fn anatomy_in_the_browser_ends_in_the_pipelines_keypoints() {
    use siftlab_core::sift::anatomy::anatomy;
    let params = SiftParams::default();
    let bits = |k: &[KeyPoint]| -> Vec<[u32; 6]> {
        k.iter()
            .map(|k| {
                [
                    k.x.to_bits(),
                    k.y.to_bits(),
                    k.size.to_bits(),
                    k.angle.to_bits(),
                    k.response.to_bits(),
                    k.octave as u32,
                ]
            })
            .collect()
    };
    for (name, bytes) in [("000000", FRAME0), ("000001", FRAME1), ("000120", MANUAL_FRAMES[3].1)] {
        let img = GrayImage::decode(bytes).unwrap();
        let t0 = performance_now();
        let plain = detect_and_compute(&img, &params);
        let t1 = performance_now();
        let a = anatomy(&img, &params);
        let t2 = performance_now();
        let _ = a.histograms();
        let t3 = performance_now();
        let counts: Vec<usize> = a.stages().iter().map(|s| s.count).collect();
        console_log!(
            "anatomy {name}: stages {counts:?}; detect_and_compute {:.1} ms, anatomy {:.1} ms (+ histograms {:.1} ms)",
            t1 - t0,
            t2 - t1,
            t3 - t2
        );
        assert_eq!(bits(&a.kept), bits(&plain.keypoints), "{name}");
    }
}
