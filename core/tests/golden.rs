//! Golden tests: our SIFT against OpenCV 4.8.0.76 on the committed fixture frames.
//!
//! The goldens in `tests/fixtures/{golden-avx2,golden}/{noipp,ipp}/NNNNNN.sift` were
//! written by `tests/references/gen_goldens.py` from `cv2.SIFT_create(nfeatures=1500)`:
//! `golden-avx2` on an AVX2 CPU (OpenCV's SIFT kernels 8 lanes wide) on the bundled
//! KITTI frames `www/demo/MyKITTI` (0–5 and the manual's 119, 120, 149, 150), and
//! `golden` on an AVX-512 CPU (16 lanes; docs/fidelity.md §SIFT-13) on the synthetic frames of
//! `tests/fixtures/synthetic`. Every test below runs on both sets, at each set's width:
//! - `noipp`: `OPENCV_IPP=disabled`; docs/fidelity.md §SIFT-14 says every field, descriptors included,
//!   is then reproducible bit for bit, so we demand exactly that;
//! - `ipp`: the default wheel, whose IPP exp/magnitude differ at ulp level; §SIFT-14
//!   allows angles off by < 1e-4° and descriptor elements off by 1.
//!
//! File format (little endian): b"SIFTGLD1", u32 width, u32 height, u32 N,
//! N x (x, y, size, angle, response: f32, octave: i32), then N x 128 u8.

#![cfg(not(target_arch = "wasm32"))]

mod golden_data;

use golden_data::{golden_sets, kitti, primary_set, set_frames, Golden, GoldenSet};
use siftlab_core::json;

use std::collections::HashMap;
use std::fs;
use std::sync::{Arc, Mutex, OnceLock};

use siftlab_core::internals as par;
use siftlab_core::manual::EXAMPLES;
use siftlab_core::matching::{match_feature, matching_info, Strategy};
use siftlab_core::sift::{detect, detect_and_compute, Features, KeyPoint};
use siftlab_core::GrayImage;

/// Our SIFT of fixture frame `id` at `set`'s SIMD width, computed once per test
/// binary (tests share it).
fn ours(set: &GoldenSet, id: &str) -> Arc<Features> {
    // Keyed by width and frame file: the sets' frames share ids but not data.
    type Cache = Mutex<HashMap<(usize, std::path::PathBuf), Arc<OnceLock<Arc<Features>>>>>;
    static CACHE: OnceLock<Cache> = OnceLock::new();
    let key = (set.lanes, set.frame_path(id));
    let slot = CACHE.get_or_init(Default::default).lock().unwrap().entry(key).or_default().clone();
    slot.get_or_init(|| {
        let fpath = set.frame_path(id);
        let img = GrayImage::decode(&fs::read(&fpath).unwrap()).unwrap_or_else(|e| panic!("{}: {e}", fpath.display()));
        Arc::new(detect_and_compute(&img, &set.params()))
    })
    .clone()
}

fn load(set: &GoldenSet, kind: &str, id: &str) -> (Golden, Arc<Features>) {
    let golden = set.read(kind, id);
    let fpath = set.frame_path(id);
    let (w, h) = image::image_dimensions(&fpath).unwrap();
    assert_eq!((w, h), (golden.width, golden.height), "{id}: frame size differs from the golden's");
    (golden, ours(set, id))
}

fn fmt_kp(k: &KeyPoint) -> String {
    format!(
        "pt=({:?}, {:?}) size={:?} angle={:?} response={:?} octave={:#x}",
        k.x, k.y, k.size, k.angle, k.response, k.octave
    )
}

#[test]
fn sift_is_bit_exact_against_opencv_without_ipp() {
    let mut failures = Vec::new();
    for set in golden_sets() {
        let (total, report) = noipp_differences(&set);
        eprintln!(
            "{} noipp ({} lanes): {total} keypoints; {} keypoints or descriptors differ",
            set.name,
            set.lanes,
            report.len()
        );
        assert!(total > 0, "{}: no keypoints", set.name);
        failures.extend(report.into_iter().map(|r| format!("{} ({} lanes) {r}", set.name, set.lanes)));
    }
    assert!(
        failures.is_empty(),
        "{} keypoints or descriptors differ from OpenCV (IPP off); first ones:\n{}",
        failures.len(),
        failures[..failures.len().min(10)].join("\n")
    );
}

/// Position, size, response and octave bit-equal (everything but the angle,
/// which IPP's exp moves in the last bits: docs/fidelity.md §SIFT-14).
fn same_geometry(a: &KeyPoint, b: &KeyPoint) -> bool {
    a.x.to_bits() == b.x.to_bits()
        && a.y.to_bits() == b.y.to_bits()
        && a.size.to_bits() == b.size.to_bits()
        && a.response.to_bits() == b.response.to_bits()
        && a.octave == b.octave
}

/// Every keypoint and descriptor of `set`'s `noipp` goldens against ours,
/// bit for bit: (keypoints compared, one line per difference).
fn noipp_differences(set: &GoldenSet) -> (usize, Vec<String>) {
    let mut total = 0usize;
    let mut report = Vec::new();
    for id in set_frames(set, "noipp") {
        let (golden, ours) = load(set, "noipp", &id);
        assert_eq!(ours.keypoints.len(), ours.descriptors.len(), "{id}: one descriptor per keypoint");
        assert_eq!(ours.keypoints.len(), golden.keypoints.len(), "{} {id}: keypoint count", set.name);
        for (i, (a, b)) in ours.keypoints.iter().zip(&golden.keypoints).enumerate() {
            total += 1;
            if !(same_geometry(a, b) && a.angle.to_bits() == b.angle.to_bits()) {
                report.push(format!("{id} keypoint {i}:\n ours   {}\n opencv {}", fmt_kp(a), fmt_kp(b)));
            }
            let (da, db) = (&ours.descriptors[i], &golden.descriptors[i]);
            if da != db {
                let diff: Vec<String> = da
                    .iter()
                    .zip(db)
                    .enumerate()
                    .filter(|(_, (p, q))| p != q)
                    .map(|(j, (p, q))| format!("[{j}] {p} vs {q}"))
                    .collect();
                report.push(format!("{id} descriptor {i} (ours vs opencv): {}", diff.join(", ")));
            }
        }
    }
    (total, report)
}

/// `detect` (what the odometry calls: keypoints only) gives OpenCV's
/// keypoints bit for bit both ways it runs: on one thread, where each octave
/// is scanned as soon as it is blurred and then dropped, and on all threads,
/// where the whole pyramid is built first.
#[test]
fn detect_alone_is_bit_exact_on_one_thread_and_on_all() {
    let bits = |k: &KeyPoint| {
        (k.x.to_bits(), k.y.to_bits(), k.size.to_bits(), k.angle.to_bits(), k.response.to_bits(), k.octave)
    };
    let mut compared = 0;
    for set in golden_sets() {
        for id in set_frames(&set, "noipp") {
            let golden = set.read("noipp", &id);
            let img = GrayImage::decode(&fs::read(set.frame_path(&id)).unwrap()).unwrap();
            let want: Vec<_> = golden.keypoints.iter().map(bits).collect();
            let serial: Vec<_> = par::serial(|| detect(&img, &set.params())).iter().map(bits).collect();
            let parallel: Vec<_> = par::with_threads(4, || detect(&img, &set.params())).iter().map(bits).collect();
            assert_eq!(serial, want, "{} {id}: detect on one thread", set.name);
            assert_eq!(parallel, want, "{} {id}: detect on several threads", set.name);
            compared += want.len();
        }
    }
    assert!(compared > 0, "no golden keypoints compared");
}

/// Angular difference in degrees, across the 0/360 wrap.
fn angle_diff(a: f32, b: f32) -> f64 {
    let d = (a as f64 - b as f64).rem_euclid(360.0);
    d.min(360.0 - d)
}

#[test]
fn sift_matches_the_default_opencv_wheel_within_spec_tolerances() {
    for set in golden_sets() {
        within_ipp_tolerances(&set);
    }
}

fn within_ipp_tolerances(set: &GoldenSet) {
    let (mut total, mut geo_exact, mut angle_ok, mut angle_exact) = (0usize, 0usize, 0usize, 0usize);
    let (mut desc_exact, mut desc_within1) = (0usize, 0usize);
    let mut max_angle = 0f64;
    let mut max_desc = 0i32;
    for id in set_frames(set, "ipp") {
        let (golden, ours) = load(set, "ipp", &id);
        // docs/fidelity.md §SIFT-14: IPP never changed the count or order; a peak crossing the 0.8
        // orientation threshold could, so a count change is a failure worth seeing.
        assert_eq!(ours.keypoints.len(), golden.keypoints.len(), "{id}: keypoint count");
        for (i, (a, b)) in ours.keypoints.iter().zip(&golden.keypoints).enumerate() {
            total += 1;
            if !same_geometry(a, b) {
                eprintln!("{id} keypoint {i} differs:\n ours   {}\n opencv {}", fmt_kp(a), fmt_kp(b));
                continue;
            }
            geo_exact += 1;
            let d = angle_diff(a.angle, b.angle);
            max_angle = max_angle.max(d);
            angle_exact += (a.angle.to_bits() == b.angle.to_bits()) as usize;
            if d <= 1e-4 {
                angle_ok += 1;
            } else {
                eprintln!("{id} keypoint {i}: angle off by {d:e} deg");
            }
            let (da, db) = (&ours.descriptors[i], &golden.descriptors[i]);
            let worst = da.iter().zip(db).map(|(&p, &q)| (p as i32 - q as i32).abs()).max().unwrap_or(0);
            max_desc = max_desc.max(worst);
            desc_exact += (worst == 0) as usize;
            desc_within1 += (worst <= 1) as usize;
        }
    }
    let pct = |n: usize| 100.0 * n as f64 / total.max(1) as f64;
    eprintln!(
        "{} ipp ({} lanes): {total} keypoints; pt/size/response/octave bit-equal {:.3}%; angle within 1e-4 deg {:.3}% \
         (bit-exact {:.3}%, max {max_angle:e} deg); descriptors exact {:.3}%, within +-1 {:.3}% (max diff {max_desc})",
        set.name,
        set.lanes,
        pct(geo_exact),
        pct(angle_ok),
        pct(angle_exact),
        pct(desc_exact),
        pct(desc_within1),
    );
    assert!(total > 0, "{}: no keypoints", set.name);
    // Issue [1] acceptance: >= 99.9% index-exact against the default wheel, and
    // descriptors within +-1 of it.
    let name = set.name;
    assert!(pct(geo_exact) >= 99.9, "{name}: pt/size/response/octave bit-equal only {:.3}%", pct(geo_exact));
    assert!(pct(angle_ok) >= 99.9, "{name}: angles within 1e-4 deg only {:.3}%", pct(angle_ok));
    assert_eq!(desc_within1, geo_exact, "{name}: some descriptor differs by more than 1 (max {max_desc})");
}

/// Where two long strings first differ, with some context, so a failure stays readable
/// when the tuple holds hundreds of matches.
pub fn first_difference(want: &str, got: &str) -> String {
    let at = want.bytes().zip(got.bytes()).position(|(a, b)| a != b).unwrap_or(want.len().min(got.len()));
    let from = at.saturating_sub(60);
    let clip = |s: &str| s.get(from..(at + 60).min(s.len())).unwrap_or("").to_owned();
    format!("at byte {at}:\n   opencv ...{}...\n   ours   ...{}...", clip(want), clip(got))
}

struct Draw {
    frame: usize,
    feature: usize,
    algo: String,
    threshold: Option<f64>,
    want: String,
}

/// The golden `get_info` draws (tests/references/gen_goldens.py): frame, feature,
/// strategy, threshold and the `ret value:` the lab's Python printed on the default wheel.
fn get_info_draws(set: &GoldenSet) -> Vec<Draw> {
    let path = set.dir().join("get_info.jsonl");
    let text = fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    text.lines()
        .filter(|l| !l.trim().is_empty())
        .enumerate()
        .map(|(i, line)| {
            let rec = json::parse(line).unwrap_or_else(|e| panic!("line {}: {e}", i + 1));
            let stdout = rec.get("stdout").and_then(|v| v.as_str()).expect("stdout");
            Draw {
                frame: rec.get("dataset_frame").and_then(|v| v.as_i64()).expect("dataset_frame") as usize,
                feature: rec.get("feature").and_then(|v| v.as_i64()).expect("feature") as usize,
                algo: rec.get("algo").and_then(|v| v.as_str()).expect("algo").to_owned(),
                threshold: rec.get("threshold").and_then(|v| v.as_f64()),
                want: stdout.lines().find_map(|l| l.strip_prefix("ret value: ")).expect("ret value line").to_owned(),
            }
        })
        .collect()
}

/// Runs every draw through the library path the CLI and the app share
/// (Strategy::parse -> match_feature -> matching_info -> Display) on the features
/// `features(frame)` gives against `set`'s draws; returns (draws, failure reports).
fn run_draws(set: &GoldenSet, features: impl Fn(usize) -> Arc<Features>) -> (usize, Vec<String>) {
    let draws = get_info_draws(set);
    let mut failures = Vec::new();
    for d in &draws {
        let (prev, cur) = (features(d.frame - 1), features(d.frame));
        let s = Strategy::parse(&d.algo, d.threshold).unwrap_or_else(|e| panic!("{}: {e}", d.algo));
        let m = match_feature(&s, &prev, &cur, d.feature).unwrap_or_else(|e| panic!("feature {}: {e}", d.feature));
        let got = matching_info(&prev.keypoints, &cur.keypoints, &m).to_string();
        if got != d.want {
            failures.push(format!(
                "{}: get_info -a {} -t {:?} {} {}: {}",
                set.name,
                d.algo,
                d.threshold,
                d.frame,
                d.feature,
                first_difference(&d.want, &got)
            ));
        }
    }
    (draws.len(), failures)
}

/// Runs `set`'s draws on `features` and asserts that at most `allowed_pct` %
/// of them differ from the lab's output (printing each difference).
fn assert_draws(set: &GoldenSet, what: &str, features: impl Fn(usize) -> Arc<Features>, allowed_pct: usize) {
    let (n, failures) = run_draws(set, features);
    eprintln!("{}: get_info {what}: {}/{n} identical to the lab's Python + OpenCV", set.name, n - failures.len());
    for f in &failures {
        eprintln!("  {f}");
    }
    assert!(n >= 200, "{}: only {n} get_info goldens", set.name);
    assert!(
        failures.len() * 100 <= n * allowed_pct,
        "{} of {n} differ; first ones:\n{}",
        failures.len(),
        failures[..failures.len().min(10)].join("\n")
    );
}

/// The matcher, the strategies, matching_info and the Python float repr alone: fed
/// OpenCV's own keypoints and descriptors (the default-wheel goldens), every draw must
/// give exactly the tuple the lab's Python printed.
#[test]
fn matching_on_opencvs_features_equals_the_labs_python() {
    for set in golden_sets() {
        let opencv = |frame: usize| {
            let g = set.read("ipp", &format!("{frame:06}"));
            Arc::new(Features { keypoints: g.keypoints, descriptors: g.descriptors })
        };
        assert_draws(&set, "on OpenCV's features", opencv, 0);
    }
}

/// End to end on our SIFT: the acceptance (get_info identical to OpenCV's on
/// random draws). The goldens come from the default (IPP) wheel, whose descriptors may
/// differ from any open implementation by 1 in rare rows (§SIFT-14), which can move one
/// distance; so at most 1% of draws may differ, and each difference is printed.
#[test]
fn get_info_end_to_end_equals_the_labs_python() {
    for set in golden_sets() {
        assert_draws(&set, "end to end", |frame| ours(&set, &format!("{frame:06}")), 1);
    }
}

/// The SIMD width matters (docs/fidelity.md §SIFT-13) and the tests above see it: OpenCV's two
/// widths disagree somewhere on the fixture frames, and each set is missed
/// when our SIFT runs at the other set's width.
#[test]
fn each_golden_set_needs_its_own_simd_width() {
    for set in golden_sets() {
        let other = if set.lanes == 8 { 16 } else { 8 };
        let (total, report) = noipp_differences(&GoldenSet { lanes: other, ..set });
        eprintln!(
            "{} noipp at the other width ({other} lanes): {} of {total} keypoints or descriptors differ",
            set.name,
            report.len()
        );
        assert!(!report.is_empty(), "{}: {other} lanes gave the {}-lane goldens too", set.name, set.lanes);
    }
}

/// The lab manual's worked examples (the introduction's on frames 100/101,
/// Tasks 1–3 on 119/120 and 149/150 of the bundled KITTI data) print exactly
/// the manual's values on our SIFT at the bundled goldens' width; the
/// introduction's at feature 132, where OpenCV 4.8.0.76 has that keypoint.
#[test]
fn the_manuals_examples_reproduce_exactly() {
    let set = primary_set();
    assert_eq!(set.dataset_dir().canonicalize().unwrap(), kitti().canonicalize().unwrap());
    let features = |frame: usize| ours(&set, &format!("{frame:06}"));
    for e in &EXAMPLES {
        let (prev, cur) = (features(e.frame - 1), features(e.frame));
        let info = |feature| {
            let m = match_feature(&e.strategy(), &prev, &cur, feature).unwrap();
            matching_info(&prev.keypoints, &cur.keypoints, &m).to_string()
        };
        assert_eq!(info(e.feature), e.siftlab_value(), "{}: {}", e.task, e.command());
        if let Some(d) = e.differs {
            assert_eq!(info(d.feature), e.expected, "{}", e.command_for(d.feature));
        }
    }
}
