//! Whole-frame matching judged by the true geometry, against OpenCV + numpy:
//! `tests/fixtures/match_all.jsonl` was written by
//! `tests/references/match_all_reference.py` (OpenCV 4.8.0 without IPP, so its
//! keypoints are siftlab's bit for bit). Plus the CLI's `match_all` and
//! `anatomy` output, and the sweep against the same golden.

#![cfg(not(target_arch = "wasm32"))]

#[path = "../../tests/golden_data/mod.rs"]
mod golden_data;
use siftlab_core::json;

use golden_data::{kitti, repo_root};
use json::Json;
use siftlab_core::dataset::parse_poses;
use siftlab_core::matching::epipolar::{fundamental, judge, Verdicts};
use siftlab_core::matching::sweep::sweep;
use siftlab_core::matching::{match_all, Strategy};
use siftlab_core::sift::{detect_and_compute, Features, SiftParams};
use siftlab_core::vo::Camera;
use siftlab_core::GrayImage;
use std::process::Command;

fn features(i: usize) -> Features {
    let path = kitti().join(format!("gray/00/image_0/{i:06}.png"));
    detect_and_compute(&GrayImage::decode(&std::fs::read(path).unwrap()).unwrap(), &SiftParams::default())
}

struct Case {
    frame: usize,
    strategy: Strategy,
    matches: usize,
    correct: usize,
}

fn golden() -> Vec<Case> {
    let text = std::fs::read_to_string(repo_root().join("tests/fixtures/match_all.jsonl")).unwrap();
    text.lines()
        .map(|l| {
            let j = json::parse(l).unwrap();
            let n = |k: &str| j.get(k).and_then(Json::as_i64).unwrap() as usize;
            let t = j.get("threshold").and_then(Json::as_f64);
            let strategy = Strategy::parse(j.get("strategy").and_then(Json::as_str).unwrap(), t).unwrap();
            Case { frame: n("frame"), strategy, matches: n("matches"), correct: n("correct") }
        })
        .collect()
}

#[test]
fn counts_equal_opencv_and_numpy_on_bundled_pairs() {
    let poses = parse_poses(&std::fs::read_to_string(kitti().join("poses/00.txt")).unwrap()).unwrap();
    let cases = golden();
    assert_eq!(cases.len(), 24, "4 pairs x 6 settings");
    let mut frames: Vec<usize> = cases.iter().map(|c| c.frame).collect();
    frames.dedup();
    for frame in frames {
        let (prev, cur) = (features(frame - 1), features(frame));
        let f = fundamental(&poses[frame - 1], &poses[frame], &Camera::default()).unwrap();
        let s = sweep(&prev, &cur, Some((&f, 2.0))).unwrap();
        for c in cases.iter().filter(|c| c.frame == frame) {
            let all: Vec<_> = match_all(&c.strategy, &prev, &cur).unwrap().into_iter().flatten().collect();
            let ok = judge(&f, &prev.keypoints, &cur.keypoints, &all, 2.0);
            let got = Verdicts { matches: all.len(), correct: Some(ok.iter().filter(|&&b| b).count()) };
            let want = Verdicts { matches: c.matches, correct: Some(c.correct) };
            assert_eq!(got, want, "frame {frame}, {:?}", c.strategy);
            // The sweep gives the same counts without re-matching.
            let curve = s.curve(c.strategy.kind());
            let swept = match c.strategy.threshold() {
                Some(t) => curve.at(t).unwrap(),
                None => curve.all(),
            };
            assert_eq!(swept, want, "sweep, frame {frame}, {:?}", c.strategy);
        }
    }
}

fn siftlab(dir: &std::path::Path, args: &[&str]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_siftlab")).current_dir(dir).args(args).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    String::from_utf8(out.stdout).unwrap()
}

/// A fresh folder for one test's `matches.png`.
fn temp_dir(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("siftlab-match-all-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn cli_match_all_prints_the_golden_counts_and_writes_matches_png() {
    let dir = temp_dir("counts");
    let d = kitti();
    let args = ["--opencv-lanes", "8", "-d", d.to_str().unwrap(), "match_all", "-a", "nndr", "-t", "0.8"];
    let out = siftlab(&dir, &[&args[..], &["--json", "120"]].concat());
    let want = golden().into_iter().find(|c| c.frame == 120 && c.strategy == Strategy::Nndr(0.8)).unwrap();
    let precision = want.correct as f64 / want.matches as f64;
    // Today's keys first, in today's form; the records follow.
    let head = format!(
        "{{\"strategy\": \"nndr\", \"threshold\": 0.8, \"matches\": {}, \"correct\": {}, \"precision\": {precision:?}, \"records\": [",
        want.matches, want.correct,
    );
    assert!(out.starts_with(&head), "{}", &out[..out.len().min(200)]);
    let json = json::parse(&out).unwrap();
    assert_eq!(json.get("records").and_then(Json::as_arr).map(<[Json]>::len), Some(want.matches));
    // The text output is what it was.
    let text = siftlab(&dir, &[&args[..], &["120"]].concat());
    assert_eq!(
        text,
        format!(
            "nndr (threshold 0.8): {} matches, {} correct within 2 px of the true epipolar line, precision {precision:.4}\n",
            want.matches, want.correct
        )
    );
    // The default picture is the flow over the current frame.
    let png = image::open(dir.join("matches.png")).unwrap();
    assert_eq!((png.width(), png.height()), (1241, 376));
    std::fs::remove_dir_all(&dir).ok();
}

/// The records of pair 119 -> 120 against OpenCV + numpy
/// (`tests/fixtures/match_all_records/`, from `match_all_reference.py` at 8
/// lanes, IPP off): the same matches in the same order, each distance as
/// the lab prints it character for character, the same verdict, and the
/// Sampson distance within 1e-9 relative plus 1e-10 px. The floor is for
/// x₂ᵀFx₁'s cancellation: numpy's F and nalgebra's differ in the last bits
/// (two numpy routes to F already differ by 3e-14 relative), which moves
/// every Sampson distance by up to ~4e-11 px whatever its size, so the
/// nearest-to-zero one (6.8e-4 px) differs by 1.5e-9 of itself.
/// Also without poses: the same matches, every Sampson distance and
/// verdict null.
#[test]
fn cli_match_all_records_equal_opencv_and_numpy() {
    let dir = temp_dir("records");
    let d = kitti();
    let no_poses = dir.join("MyKITTI-no-poses");
    let images = no_poses.join("gray/00/image_0");
    std::fs::create_dir_all(&images).unwrap();
    for f in [119, 120] {
        let name = format!("{f:06}.png");
        std::fs::copy(d.join("gray/00/image_0").join(&name), images.join(&name)).unwrap();
    }
    let mut gaps = Vec::new();
    for (algo, t, file) in [("nndr", "0.8", "120-nndr-0.8.jsonl"), ("dt", "300", "120-dt-300.jsonl")] {
        let text = std::fs::read_to_string(repo_root().join("tests/fixtures/match_all_records").join(file)).unwrap();
        let mut lines = text.lines();
        let head = json::parse(lines.next().unwrap()).unwrap();
        let want: Vec<Json> = lines.map(|l| json::parse(l).unwrap()).collect();
        assert_eq!(head.get("matches").and_then(Json::as_i64), Some(want.len() as i64), "{file}");
        let run = |dataset: &std::path::Path| {
            let args = ["--opencv-lanes", "8", "-d", dataset.to_str().unwrap(), "match_all", "-a", algo, "-t", t];
            json::parse(&siftlab(&dir, &[&args[..], &["--json", "120"]].concat())).unwrap()
        };
        let got = run(&d);
        assert_eq!(got.get("correct").and_then(Json::as_i64), head.get("correct").and_then(Json::as_i64), "{file}");
        let records = got.get("records").and_then(Json::as_arr).unwrap();
        assert_eq!(records.len(), want.len(), "{file}");
        let (mut worst, mut worst_px) = ((0.0f64, 0usize), 0.0f64);
        for (i, (g, w)) in records.iter().zip(&want).enumerate() {
            let w = w.as_arr().unwrap();
            let at = format!("{file}, match {i}");
            assert_eq!(g.get("query"), Some(&w[0]), "{at}");
            assert_eq!(g.get("train"), Some(&w[1]), "{at}");
            // Python's repr of the widened f32, the same characters.
            assert_eq!(g.get("distance"), Some(&w[2]), "{at}");
            let (s, r) = (g.get("sampson").and_then(Json::as_f64).unwrap(), w[3].as_f64().unwrap());
            assert!((s - r).abs() <= 1e-9 * r.abs() + 1e-10, "{at}: sampson {s} vs numpy {r}");
            let gap = (s - r).abs() / r.abs();
            if gap > worst.0 {
                worst = (gap, i);
            }
            worst_px = worst_px.max((s - r).abs());
            assert_eq!(g.get("correct"), Some(&w[4]), "{at}");
        }
        gaps.push(format!(
            "{file}: {} matches, largest Sampson gap {worst_px:.2e} px, {:.2e} relative (match {})",
            want.len(),
            worst.0,
            worst.1
        ));
        // Without poses: the same matches, nothing judged.
        let plain = run(&no_poses);
        assert_eq!(plain.get("correct"), Some(&Json::Null));
        let unjudged = plain.get("records").and_then(Json::as_arr).unwrap();
        assert_eq!(unjudged.len(), want.len());
        for (g, w) in unjudged.iter().zip(&want) {
            let w = w.as_arr().unwrap();
            assert_eq!((g.get("query"), g.get("train"), g.get("distance")), (Some(&w[0]), Some(&w[1]), Some(&w[2])));
            assert_eq!((g.get("sampson"), g.get("correct")), (Some(&Json::Null), Some(&Json::Null)));
        }
    }
    eprintln!("{}", gaps.join("\n"));
    std::fs::remove_dir_all(&dir).ok();
}

/// Each layout's matches.png is the library's picture (what the app draws)
/// of the CLI's matches and verdicts: `flow` the current frame,
/// `side` both frames.
#[test]
fn cli_match_all_layouts_draw_the_librarys_pictures() {
    use siftlab_core::render::{flow_frame, whole_frame};
    let dir = temp_dir("layouts");
    let d = kitti();
    let poses = parse_poses(&std::fs::read_to_string(d.join("poses/00.txt")).unwrap()).unwrap();
    let frame =
        |i: usize| GrayImage::decode(&std::fs::read(d.join(format!("gray/00/image_0/{i:06}.png"))).unwrap()).unwrap();
    let (prev_image, cur_image) = (frame(119), frame(120));
    let (prev, cur) = (features(119), features(120));
    let f = fundamental(&poses[119], &poses[120], &Camera::default()).unwrap();
    let all: Vec<_> = match_all(&Strategy::Nndr(0.8), &prev, &cur).unwrap().into_iter().flatten().collect();
    let ok = judge(&f, &prev.keypoints, &cur.keypoints, &all, 2.0);
    let flow = flow_frame(&cur_image, &prev.keypoints, &cur.keypoints, &all, Some(&ok)).unwrap();
    let side = whole_frame(&prev_image, &prev.keypoints, &cur_image, &cur.keypoints, &all, Some(&ok)).unwrap();
    assert_eq!((flow.width(), flow.height()), (1241, 376));
    assert_eq!((side.width(), side.height()), (2 * 1241, 376));
    for (layout, want) in [(Some("flow"), &flow), (Some("side"), &side), (None, &flow)] {
        let mut args = vec!["--opencv-lanes", "8", "-d", d.to_str().unwrap(), "match_all", "-a", "nndr", "-t", "0.8"];
        if let Some(l) = layout {
            args.extend(["--layout", l]);
        }
        args.push("120");
        siftlab(&dir, &args);
        let png = image::open(dir.join("matches.png")).unwrap().to_rgb8();
        assert!(png == *want, "--layout {layout:?}");
    }
    // The flow picture is the frame where no match is drawn, and the
    // palette's two hues where the matches are.
    let gray = siftlab_core::render::gray_to_rgb(&cur_image);
    let changed = flow.pixels().zip(gray.pixels()).filter(|(a, b)| a != b).count();
    assert!(changed > 10_000 && changed < 1241 * 376 / 4, "{changed} pixels drawn over");
    let out = Command::new(env!("CARGO_BIN_EXE_siftlab"))
        .current_dir(&dir)
        .args(["-d", d.to_str().unwrap(), "match_all", "-a", "nn", "--layout", "up", "120"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("--layout") && err.contains("flow") && err.contains("side"), "{err}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn cli_anatomy_ends_at_sifts_keypoint_count() {
    let img = kitti().join("gray/00/image_0/000120.png");
    let root = repo_root();
    let json = json::parse(&siftlab(&root, &["anatomy", img.to_str().unwrap(), "--json"])).unwrap();
    let stages = json.get("stages").and_then(Json::as_arr).unwrap();
    let names: Vec<&str> = stages.iter().map(|s| s.get("stage").and_then(Json::as_str).unwrap()).collect();
    assert_eq!(names, ["extrema", "refined", "oriented", "deduplicated", "kept"]);
    let sift = json::parse(&siftlab(&root, &["sift", img.to_str().unwrap(), "--json"])).unwrap();
    let n = sift.get("keypoints").and_then(Json::as_arr).unwrap().len() as i64;
    assert_eq!(stages[4].get("count").and_then(Json::as_i64), Some(n));
    assert_eq!(json.get("octaves").and_then(Json::as_i64), Some(9));
}

/// The trade-off on the bundled pairs: where the three curves cross, and
/// the precision each strategy reaches at its usual setting (printed for the
/// docs; run with --nocapture). nndr's ratio test is the most precise at
/// every pair, as Lowe found, and nn without a threshold the least.
#[test]
fn tradeoff_on_bundled_pairs() {
    use siftlab_core::matching::StrategyKind;
    let poses = parse_poses(&std::fs::read_to_string(kitti().join("poses/00.txt")).unwrap()).unwrap();
    for frame in [1usize, 50, 120, 150] {
        let (prev, cur) = (features(frame - 1), features(frame));
        let f = fundamental(&poses[frame - 1], &poses[frame], &Camera::default()).unwrap();
        let s = sweep(&prev, &cur, Some((&f, 2.0))).unwrap();
        let p = |v: Verdicts| v.precision().unwrap();
        let (nn, dt, nndr) = (p(s.nn.all()), p(s.dt.at(250.0).unwrap()), p(s.nndr.at(0.8).unwrap()));
        assert!(nndr > nn && nndr > dt, "frame {frame}");
        let k = StrategyKind::ALL;
        let mut text = Vec::new();
        for (i, &a) in k.iter().enumerate() {
            for &b in &k[i + 1..] {
                for (m, pr) in s.curve(a).crossings(s.curve(b), 20) {
                    text.push(format!("{}x{} at {m} ({pr:.3})", a.name(), b.name()));
                }
            }
        }
        eprintln!(
            "pair {}->{frame}: precision nn {nn:.4}, dt 250 {dt:.4}, nndr 0.8 {nndr:.4}; crossings: {}",
            frame - 1,
            text.join(", ")
        );
    }
}
