//! Golden tests: our SIFT against OpenCV 4.8.0.76 on the committed fixture frames.
//!
//! The goldens in `tests/fixtures/golden/{noipp,ipp}/NNNNNN.sift` were written by the
//! fixture generator (tests/scripts) from `cv2.SIFT_create(nfeatures=1500)` run on
//! `tests/fixtures/mykitti/gray/00/image_0/NNNNNN.png`:
//! - `noipp`: `OPENCV_IPP=disabled`; spec §14 says every field, descriptors included,
//!   is then reproducible bit for bit, so we demand exactly that;
//! - `ipp`: the default wheel, whose IPP exp/magnitude differ at ulp level; spec §14
//!   allows angles off by < 1e-4° and descriptor elements off by 1.
//!
//! File format (little endian): b"SIFTGLD1", u32 width, u32 height, u32 N,
//! N x (x, y, size, angle, response: f32, octave: i32), then N x 128 u8.

#![cfg(not(target_arch = "wasm32"))]

mod golden_data;
mod json_mini;

use golden_data::{fixtures, golden_frames, golden_params, parse_golden, Golden};

use std::collections::HashMap;
use std::fs;
use std::sync::{Arc, Mutex, OnceLock};

use siftlab_core::matching::{match_feature, matching_info, Strategy};
use siftlab_core::sift::{detect_and_compute, Features, KeyPoint};
use siftlab_core::GrayImage;

/// Our SIFT of fixture frame `id`, computed once per test binary (tests share it).
fn ours(id: &str) -> Arc<Features> {
    static CACHE: OnceLock<Mutex<HashMap<String, Arc<OnceLock<Arc<Features>>>>>> = OnceLock::new();
    let slot = CACHE.get_or_init(Default::default).lock().unwrap().entry(id.to_owned()).or_default().clone();
    slot.get_or_init(|| {
        let fpath = fixtures().join(format!("mykitti/gray/00/image_0/{id}.png"));
        let img = GrayImage::decode(&fs::read(&fpath).unwrap())
            .unwrap_or_else(|e| panic!("{}: {e}", fpath.display()));
        Arc::new(detect_and_compute(&img, &golden_params()))
    })
    .clone()
}

fn load(kind: &str, id: &str) -> (Golden, Arc<Features>) {
    let gpath = fixtures().join("golden").join(kind).join(format!("{id}.sift"));
    let golden = parse_golden(&fs::read(&gpath).unwrap(), &gpath.display().to_string());
    let fpath = fixtures().join(format!("mykitti/gray/00/image_0/{id}.png"));
    let (w, h) = image::image_dimensions(&fpath).unwrap();
    assert_eq!((w, h), (golden.width, golden.height), "{id}: frame size differs from the golden's");
    (golden, ours(id))
}

fn fmt_kp(k: &KeyPoint) -> String {
    format!(
        "pt=({:?}, {:?}) size={:?} angle={:?} response={:?} octave={:#x}",
        k.x, k.y, k.size, k.angle, k.response, k.octave
    )
}

#[test]
fn sift_is_bit_exact_against_opencv_without_ipp() {
    let (mut total, mut kp_bad, mut desc_bad) = (0usize, 0usize, 0usize);
    let mut report = Vec::new();
    for id in golden_frames("noipp") {
        let (golden, ours) = load("noipp", &id);
        assert_eq!(ours.keypoints.len(), ours.descriptors.len(), "{id}: one descriptor per keypoint");
        assert_eq!(ours.keypoints.len(), golden.keypoints.len(), "{id}: keypoint count");
        for (i, (a, b)) in ours.keypoints.iter().zip(&golden.keypoints).enumerate() {
            total += 1;
            let same = a.x.to_bits() == b.x.to_bits()
                && a.y.to_bits() == b.y.to_bits()
                && a.size.to_bits() == b.size.to_bits()
                && a.angle.to_bits() == b.angle.to_bits()
                && a.response.to_bits() == b.response.to_bits()
                && a.octave == b.octave;
            if !same {
                kp_bad += 1;
                if report.len() < 10 {
                    report.push(format!("{id} keypoint {i}:\n ours   {}\n opencv {}", fmt_kp(a), fmt_kp(b)));
                }
            }
            let (da, db) = (&ours.descriptors[i], &golden.descriptors[i]);
            if da != db {
                desc_bad += 1;
                if report.len() < 10 {
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
    }
    eprintln!(
        "noipp: {total} keypoints; keypoints bit-exact {}/{total}, descriptors bit-exact {}/{total}",
        total - kp_bad,
        total - desc_bad
    );
    assert!(total > 0);
    assert!(
        kp_bad == 0 && desc_bad == 0,
        "{kp_bad} keypoints and {desc_bad} descriptors differ from OpenCV (IPP off); first ones:\n{}",
        report.join("\n")
    );
}

/// Angular difference in degrees, across the 0/360 wrap.
fn angle_diff(a: f32, b: f32) -> f64 {
    let d = (a as f64 - b as f64).rem_euclid(360.0);
    d.min(360.0 - d)
}

#[test]
fn sift_matches_the_default_opencv_wheel_within_spec_tolerances() {
    let (mut total, mut geo_exact, mut angle_ok, mut angle_exact) = (0usize, 0usize, 0usize, 0usize);
    let (mut desc_exact, mut desc_within1) = (0usize, 0usize);
    let mut max_angle = 0f64;
    let mut max_desc = 0i32;
    for id in golden_frames("ipp") {
        let (golden, ours) = load("ipp", &id);
        // Spec §14: IPP never changed the count or order; a peak crossing the 0.8
        // orientation threshold could, so a count change is a failure worth seeing.
        assert_eq!(ours.keypoints.len(), golden.keypoints.len(), "{id}: keypoint count");
        for (i, (a, b)) in ours.keypoints.iter().zip(&golden.keypoints).enumerate() {
            total += 1;
            let geo = a.x.to_bits() == b.x.to_bits()
                && a.y.to_bits() == b.y.to_bits()
                && a.size.to_bits() == b.size.to_bits()
                && a.response.to_bits() == b.response.to_bits()
                && a.octave == b.octave;
            if !geo {
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
        "ipp: {total} keypoints; pt/size/response/octave bit-equal {:.3}%; angle within 1e-4 deg {:.3}% \
         (bit-exact {:.3}%, max {max_angle:e} deg); descriptors exact {:.3}%, within +-1 {:.3}% (max diff {max_desc})",
        pct(geo_exact),
        pct(angle_ok),
        pct(angle_exact),
        pct(desc_exact),
        pct(desc_within1),
    );
    assert!(total > 0);
    // Issue [1] acceptance: >= 99.9% index-exact against the default wheel, and
    // descriptors within +-1 of it.
    assert!(pct(geo_exact) >= 99.9, "pt/size/response/octave bit-equal only {:.3}%", pct(geo_exact));
    assert!(pct(angle_ok) >= 99.9, "angles within 1e-4 deg only {:.3}%", pct(angle_ok));
    assert_eq!(desc_within1, geo_exact, "some descriptor differs by more than 1 (max {max_desc})");
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

/// The golden `get_info` draws (tests/scripts/gen_goldens.py): frame, feature,
/// strategy, threshold and the `ret value:` the lab's Python printed on the default wheel.
fn get_info_draws() -> Vec<Draw> {
    let path = fixtures().join("golden/get_info.jsonl");
    let text = fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    text.lines()
        .filter(|l| !l.trim().is_empty())
        .enumerate()
        .map(|(i, line)| {
            let rec = json_mini::parse(line).unwrap_or_else(|e| panic!("line {}: {e}", i + 1));
            let stdout = rec.get("stdout").and_then(|v| v.str()).expect("stdout");
            Draw {
                frame: rec.get("dataset_frame").and_then(|v| v.i64()).expect("dataset_frame") as usize,
                feature: rec.get("feature").and_then(|v| v.i64()).expect("feature") as usize,
                algo: rec.get("algo").and_then(|v| v.str()).expect("algo").to_owned(),
                threshold: rec.get("threshold").and_then(|v| v.f64()),
                want: stdout.lines().find_map(|l| l.strip_prefix("ret value: ")).expect("ret value line").to_owned(),
            }
        })
        .collect()
}

/// Runs every draw through the library path the CLI and the app share
/// (Strategy::parse -> match_feature -> matching_info -> Display) on the features
/// `features(frame)` gives; returns (draws, failure reports).
fn run_draws(features: impl Fn(usize) -> Arc<Features>) -> (usize, Vec<String>) {
    let draws = get_info_draws();
    let mut failures = Vec::new();
    for d in &draws {
        let (prev, cur) = (features(d.frame - 1), features(d.frame));
        let s = Strategy::parse(&d.algo, d.threshold).unwrap_or_else(|e| panic!("{}: {e}", d.algo));
        let m = match_feature(&s, &prev, &cur, d.feature).unwrap_or_else(|e| panic!("feature {}: {e}", d.feature));
        let got = matching_info(&prev.keypoints, &cur.keypoints, &m).to_string();
        if got != d.want {
            failures.push(format!(
                "get_info -a {} -t {:?} {} {}: {}",
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

/// The matcher, the strategies, matching_info and the Python float repr alone: fed
/// OpenCV's own keypoints and descriptors (the default-wheel goldens), every draw must
/// give exactly the tuple the lab's Python printed.
#[test]
fn matching_on_opencvs_features_equals_the_labs_python() {
    let opencv = |frame: usize| {
        let id = format!("{frame:06}");
        let path = fixtures().join(format!("golden/ipp/{id}.sift"));
        let g = parse_golden(&fs::read(&path).unwrap(), &id);
        Arc::new(Features { keypoints: g.keypoints, descriptors: g.descriptors })
    };
    let (n, failures) = run_draws(opencv);
    eprintln!("get_info on OpenCV's features: {}/{n} identical to the lab's Python", n - failures.len());
    assert!(n >= 200, "only {n} get_info goldens");
    assert!(failures.is_empty(), "{} of {n} differ; first ones:\n{}", failures.len(), failures[..failures.len().min(10)].join("\n"));
}

/// End to end on our SIFT: the acceptance (get_info identical to OpenCV's on
/// random draws). The goldens come from the default (IPP) wheel, whose descriptors may
/// differ from any open implementation by 1 in rare rows (spec §14), which can move one
/// distance; so at most 1% of draws may differ, and each difference is printed.
#[test]
fn get_info_end_to_end_equals_the_labs_python() {
    let (n, failures) = run_draws(|frame| ours(&format!("{frame:06}")));
    eprintln!("get_info end to end: {}/{n} identical to the lab's Python + OpenCV", n - failures.len());
    for f in &failures {
        eprintln!("  {f}");
    }
    assert!(n >= 200, "only {n} get_info goldens");
    assert!(
        failures.len() * 100 <= n,
        "{} of {n} differ; first ones:\n{}",
        failures.len(),
        failures[..failures.len().min(10)].join("\n")
    );
}
