//! The `siftlab` binary end to end: `get_info` against OpenCV goldens, `sift --json`
//! against the SIFT goldens, and every bad input the issue lists.

#![cfg(not(target_arch = "wasm32"))]

#[path = "../../tests/golden_data/mod.rs"]
mod golden_data;
use siftlab_core::json;

use golden_data::{golden_frames, golden_lanes, golden_params, golden_sets, kitti, primary_set};

use siftlab_core::manual::EXAMPLES;
use siftlab_core::matching::{match_feature, matching_info, Strategy};
use siftlab_core::sift::{detect_and_compute, Features};
use siftlab_core::GrayImage;

use std::fs;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The bundled real KITTI frames the primary goldens were computed on.
fn dataset() -> PathBuf {
    kitti()
}

fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn golden_lanes_args() -> [String; 2] {
    ["--opencv-lanes".into(), golden_lanes().to_string()]
}

fn siftlab_in(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_siftlab"))
        .current_dir(dir)
        .args(args)
        .output()
        .expect("cannot start the siftlab binary")
}

fn siftlab(args: &[&str]) -> Output {
    siftlab_in(&repo_root(), args)
}

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// A fresh scratch directory per test (no tempfile crate in the core).
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("siftlab-cli-{}-{name}", std::process::id()));
    let _ = fs::remove_dir_all(&dir);
    fs::create_dir_all(&dir).unwrap();
    dir
}

/// Asserts a clean failure: non-zero exit, no panic, a message on stderr that
/// contains every one of `words` (case-insensitive), nothing on stdout after the
/// header lines.
fn assert_fails(o: &Output, words: &[&str], what: &str) {
    let err = stderr(o);
    assert!(!o.status.success(), "{what}: exit status {:?} should be a failure\nstderr: {err}", o.status);
    assert_ne!(o.status.code(), Some(101), "{what}: exit code 101 is Rust's panic code\nstderr: {err}");
    assert!(!err.contains("panicked"), "{what}: panicked\nstderr: {err}");
    assert!(!err.contains("RUST_BACKTRACE"), "{what}: panicked\nstderr: {err}");
    let lower = err.to_lowercase();
    for w in words {
        assert!(lower.contains(&w.to_lowercase()), "{what}: stderr does not mention {w:?}\nstderr: {err}");
    }
    assert!(!stdout(o).contains("ret value"), "{what}: printed a result anyway\nstdout: {}", stdout(o));
}

// ---------------------------------------------------------------------------
// get_info against OpenCV

/// Our features of bundled frame `frame` (golden SIFT parameters), once per test binary.
fn library_features(frame: usize) -> std::sync::Arc<Features> {
    use std::sync::{Arc, Mutex, OnceLock};
    static CACHE: OnceLock<Mutex<Vec<Option<Arc<Features>>>>> = OnceLock::new();
    let mut cache = CACHE.get_or_init(Default::default).lock().unwrap();
    if cache.len() <= frame {
        cache.resize(frame + 1, None);
    }
    cache[frame]
        .get_or_insert_with(|| {
            let bytes = fs::read(dataset().join(format!("gray/00/image_0/{frame:06}.png"))).unwrap();
            let img = GrayImage::decode(&bytes).unwrap();
            Arc::new(detect_and_compute(&img, &golden_params()))
        })
        .clone()
}

/// Each line of the primary set's `get_info.jsonl` (tests/references/gen_goldens.py)
/// holds one `get_info` call on the bundled frames, `{"dataset_frame", "feature",
/// "algo", "threshold"}`, and the exact stdout the lab's Python + OpenCV printed for
/// `-d www/demo/MyKITTI`, so the CLI runs from the repository root with that path.
///
/// The binary must print the lab's `vo params`, `debug run` and `ret count` lines
/// exactly, and as `ret value` exactly what the library gives (golden.rs compares the
/// library with OpenCV on every draw; the default wheel's IPP can move a distance in
/// rare draws, docs/fidelity.md §SIFT-14). Every process runs SIFT twice, so this runs the binary on
/// every 12th draw plus every `nn` draw without a threshold.
#[test]
fn get_info_prints_exactly_what_the_lab_prints() {
    let set = primary_set();
    let path = set.dir().join("get_info.jsonl");
    let text = fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let (mut n, mut identical) = (0, 0);
    let mut failures = Vec::new();
    for (lineno, line) in text.lines().enumerate().filter(|(_, l)| !l.trim().is_empty()) {
        let rec = json::parse(line).unwrap_or_else(|e| panic!("line {}: {e}", lineno + 1));
        let no_threshold = rec.get("threshold") == Some(&json::Json::Null);
        if lineno % 12 != 0 && !no_threshold {
            continue;
        }
        let field = |k: &str| rec.get(k).unwrap_or_else(|| panic!("line {}: no {k:?}", lineno + 1));
        let algo = field("algo").as_str().expect("algo is a string").to_owned();
        let mut argv: Vec<String> = vec!["-d".into(), set.dataset.clone(), "get_info".into()];
        argv.extend(golden_lanes_args());
        argv.extend(["-a".into(), algo.clone()]);
        let threshold = match field("threshold") {
            json::Json::Null => None,
            // The number's JSON text is Python's repr of the float the lab
            // parsed; `py_float` writes the same text back.
            t @ (json::Json::Float(_) | json::Json::Int(_)) => {
                let t = t.as_f64().unwrap();
                argv.extend(["-t".into(), siftlab_core::pyfmt::py_float(t)]);
                Some(t)
            }
            other => panic!("line {}: bad threshold {other:?}", lineno + 1),
        };
        let frame = field("dataset_frame").as_i64().expect("dataset_frame") as usize;
        let feature = field("feature").as_i64().expect("feature") as usize;
        argv.extend([frame.to_string(), feature.to_string()]);
        let golden = field("stdout").as_str().expect("stdout is a string");

        let (prev, cur) = (library_features(frame - 1), library_features(frame));
        let s = Strategy::parse(&algo, threshold).unwrap();
        let m = match_feature(&s, &prev, &cur, feature).unwrap();
        let library = matching_info(&prev.keypoints, &cur.keypoints, &m).to_string();
        let expected: String = golden
            .lines()
            .map(|l| if l.starts_with("ret value: ") { format!("ret value: {library}\n") } else { format!("{l}\n") })
            .collect();

        let argv_ref: Vec<&str> = argv.iter().map(String::as_str).collect();
        let o = siftlab_in(&repo_root(), &argv_ref);
        assert!(o.status.success(), "siftlab {argv:?} failed: {}", stderr(&o));
        assert!(!stderr(&o).contains("panicked"));
        let got = stdout(&o);
        if got != expected {
            failures.push(format!("siftlab {}\n--- expected\n{expected}--- siftlab\n{got}", argv.join(" ")));
        }
        identical += (got == golden) as usize;
        n += 1;
    }
    eprintln!("get_info CLI: {n} runs; {identical} byte-identical to the lab's stdout");
    assert!(n >= 30, "only {n} get_info goldens run");
    assert!(failures.is_empty(), "{} of {n} get_info outputs differ:\n{}", failures.len(), failures.join("\n"));
}

// ---------------------------------------------------------------------------
// sift --json against the OpenCV (IPP disabled) goldens

fn first_golden_frame() -> String {
    golden_frames("noipp").remove(0)
}

/// A frame every golden set has; each set is checked on its own dataset at
/// its own width (golden.rs shows that the other width misses each set).
const WIDTH_FRAME: &str = "000002";

#[test]
fn sift_json_round_trips_opencv_values_bit_exactly() {
    for set in golden_sets() {
        let frame = set.frame_path(WIDTH_FRAME);
        let lanes = set.lanes.to_string();
        let o = siftlab(&["--opencv-lanes", &lanes, "sift", frame.to_str().unwrap(), "--json"]);
        assert!(o.status.success(), "sift --json failed: {}", stderr(&o));
        let doc = json::parse(stdout(&o).trim()).expect("sift --json is not valid JSON");
        let golden = set.read("noipp", WIDTH_FRAME);
        let id = format!("{} {WIDTH_FRAME}", set.name);
        assert_eq!(doc.get("width").and_then(|v| v.as_i64()), Some(golden.width as i64));
        assert_eq!(doc.get("height").and_then(|v| v.as_i64()), Some(golden.height as i64));
        let kps = doc.get("keypoints").and_then(|v| v.as_arr()).expect("keypoints array");
        let descs = doc.get("descriptors").and_then(|v| v.as_arr()).expect("descriptors array");
        let n = golden.keypoints.len();
        assert_eq!((kps.len(), descs.len()), (n, n), "{id}: keypoint/descriptor counts");
        for (i, (kp, want)) in kps.iter().zip(&golden.keypoints).enumerate() {
            let fields =
                [("x", want.x), ("y", want.y), ("size", want.size), ("angle", want.angle), ("response", want.response)];
            for (key, want) in fields {
                let got = kp.get(key).and_then(|v| v.as_f32()).unwrap_or_else(|| panic!("kp {i} {key}"));
                assert_eq!(got.to_bits(), want.to_bits(), "{id} kp {i} {key}: {got:?} vs OpenCV {want:?}");
            }
            assert_eq!(kp.get("octave").and_then(|v| v.as_i64()), Some(want.octave as i64), "{id} kp {i} octave");
        }
        for (i, (d, want)) in descs.iter().zip(&golden.descriptors).enumerate() {
            let got: Vec<i64> = d.as_arr().expect("descriptor row").iter().map(|v| v.as_i64().unwrap()).collect();
            let want: Vec<i64> = want.iter().map(|&b| b as i64).collect();
            assert_eq!(got, want, "{id} descriptor {i} at {lanes} lanes");
        }
    }
}

#[test]
fn sift_plain_prints_count_and_time() {
    let id = first_golden_frame();
    let frame = dataset().join(format!("gray/00/image_0/{id}.png"));
    let o = siftlab(&["sift", frame.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = stdout(&o);
    let golden = fs::read(primary_set().dir().join(format!("noipp/{id}.sift"))).unwrap();
    let n = u32::from_le_bytes(golden[16..20].try_into().unwrap());
    let line = out.trim_end();
    let rest = line
        .strip_prefix(&format!("{n} keypoints in "))
        .unwrap_or_else(|| panic!("unexpected output {line:?}, want \"{n} keypoints in T ms\""));
    let t = rest.strip_suffix(" ms").unwrap_or_else(|| panic!("no ' ms' in {line:?}"));
    assert!(t.parse::<f64>().map(|v| v >= 0.0).unwrap_or(false), "bad time {t:?}");
}

#[test]
fn sift_repeat_reports_best_and_mean() {
    let id = first_golden_frame();
    let frame = dataset().join(format!("gray/00/image_0/{id}.png"));
    let o = siftlab(&["sift", frame.to_str().unwrap(), "--repeat", "3"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let golden = fs::read(primary_set().dir().join(format!("noipp/{id}.sift"))).unwrap();
    let n = u32::from_le_bytes(golden[16..20].try_into().unwrap());
    let line = stdout(&o).trim_end().to_owned();
    let rest = line.strip_prefix(&format!("{n} keypoints in ")).unwrap_or_else(|| panic!("unexpected {line:?}"));
    let (best, rest) = rest.split_once(" ms (best of 3; mean ").unwrap_or_else(|| panic!("unexpected {line:?}"));
    let mean = rest.strip_suffix(" ms)").unwrap_or_else(|| panic!("unexpected {line:?}"));
    let (best, mean): (f64, f64) = (best.parse().unwrap(), mean.parse().unwrap());
    assert!(best > 0.0 && best <= mean, "best {best} mean {mean}");

    let o = siftlab(&["sift", frame.to_str().unwrap(), "--repeat", "0"]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("0 is not in 1..=1000"), "{}", stderr(&o));
}

// ---------------------------------------------------------------------------
// bad input: one clear message, non-zero exit, no panic

fn ds_arg() -> String {
    dataset().to_str().unwrap().to_owned()
}

#[test]
fn missing_dataset_is_reported() {
    let o = siftlab(&["-d", "/nonexistent/MyKITTI", "get_info", "-a", "nn", "1", "0"]);
    assert_fails(&o, &["/nonexistent/MyKITTI"], "missing dataset");
}

#[test]
fn frame_id_zero_is_rejected() {
    let o = siftlab(&["-d", &ds_arg(), "get_info", "-a", "nn", "0", "0"]);
    assert_fails(&o, &["frame"], "FRAME_ID 0");
}

#[test]
fn frame_beyond_the_dataset_is_reported() {
    let o = siftlab(&["-d", &ds_arg(), "get_info", "-a", "nn", "99999", "0"]);
    // The previous frame (99998) is read first; either name is a clear message.
    assert_fails(&o, &["9999", ".png"], "missing frame file");
}

#[test]
fn feature_out_of_range_is_rejected() {
    let o = siftlab(&["-d", &ds_arg(), "get_info", "-a", "nn", "1", "1500"]);
    assert_fails(&o, &["feature", "1500"], "FEATURE_ID 1500");
}

#[test]
fn nndr_threshold_above_one_is_rejected() {
    let o = siftlab(&["-d", &ds_arg(), "get_info", "-a", "nndr", "-t", "1.5", "1", "0"]);
    assert_fails(&o, &["threshold", "1.5"], "nndr -t 1.5");
}

#[test]
fn negative_threshold_is_rejected() {
    for algo in ["dt", "nn", "nndr"] {
        let o = siftlab(&["-d", &ds_arg(), "get_info", "-a", algo, "-t", "-5", "1", "0"]);
        assert_fails(&o, &["threshold"], &format!("{algo} -t -5"));
    }
}

#[test]
fn nan_threshold_is_rejected() {
    for algo in ["dt", "nn", "nndr"] {
        let o = siftlab(&["-d", &ds_arg(), "get_info", "-a", algo, "-t", "nan", "1", "0"]);
        assert_fails(&o, &["threshold"], &format!("{algo} -t nan"));
    }
}

#[test]
fn dt_and_nndr_need_a_threshold() {
    for algo in ["dt", "nndr"] {
        let o = siftlab(&["-d", &ds_arg(), "get_info", "-a", algo, "1", "0"]);
        assert_fails(&o, &["threshold"], &format!("{algo} without -t"));
    }
}

#[test]
fn unknown_strategy_is_rejected() {
    let o = siftlab(&["-d", &ds_arg(), "get_info", "-a", "knn", "-t", "1", "1", "0"]);
    assert_fails(&o, &["knn"], "-a knn");
}

/// A dataset whose frames 0 and 1 are the given byte strings.
fn dataset_with(name: &str, f0: &[u8], f1: &[u8]) -> PathBuf {
    let root = scratch(name);
    let frames = root.join("gray/00/image_0");
    fs::create_dir_all(&frames).unwrap();
    fs::create_dir_all(root.join("poses")).unwrap();
    fs::write(frames.join("000000.png"), f0).unwrap();
    fs::write(frames.join("000001.png"), f1).unwrap();
    fs::copy(dataset().join("poses/00.txt"), root.join("poses/00.txt")).unwrap();
    root
}

fn fixture_frame(id: u32) -> Vec<u8> {
    fs::read(dataset().join(format!("gray/00/image_0/{id:06}.png"))).unwrap()
}

fn png(w: u32, h: u32, f: impl Fn(u32, u32) -> u8) -> Vec<u8> {
    let buf: Vec<u8> = (0..h).flat_map(|y| (0..w).map(move |x| (x, y))).map(|(x, y)| f(x, y)).collect();
    let mut out = std::io::Cursor::new(Vec::new());
    image::write_buffer_with_format(&mut out, &buf, w, h, image::ExtendedColorType::L8, image::ImageFormat::Png)
        .unwrap();
    out.into_inner()
}

#[test]
fn non_image_frame_is_reported() {
    let root = dataset_with("nonimage", b"this is not a PNG file\n", &fixture_frame(1));
    let o = siftlab(&["-d", root.to_str().unwrap(), "get_info", "-a", "nn", "1", "0"]);
    assert_fails(&o, &["000000.png"], "non-image frame");
    let _ = fs::remove_dir_all(&root);
}

#[test]
fn truncated_frame_is_reported() {
    let good = fixture_frame(0);
    let root = dataset_with("truncated", &fixture_frame(0), &good[..good.len() / 2]);
    let o = siftlab(&["-d", root.to_str().unwrap(), "get_info", "-a", "nn", "1", "0"]);
    assert_fails(&o, &["000001.png"], "truncated frame");
    let _ = fs::remove_dir_all(&root);
}

#[test]
fn non_image_file_for_sift_is_reported() {
    let dir = scratch("sift-nonimage");
    let p = dir.join("notes.png");
    fs::write(&p, b"hello").unwrap();
    let o = siftlab(&["sift", p.to_str().unwrap()]);
    assert_fails(&o, &["image"], "sift on a non-image");
    let o = siftlab(&["sift", dir.join("absent.png").to_str().unwrap()]);
    assert_fails(&o, &["absent.png"], "sift on a missing file");
    let _ = fs::remove_dir_all(&dir);
}

#[test]
fn tiny_images_give_zero_keypoints_not_a_crash() {
    let dir = scratch("tiny");
    for (w, h) in [(1, 1), (2, 3), (8, 8)] {
        let p = dir.join(format!("tiny{w}x{h}.png"));
        fs::write(&p, png(w, h, |x, y| ((x * 37 + y * 91) % 256) as u8)).unwrap();
        let o = siftlab(&["sift", p.to_str().unwrap()]);
        assert!(o.status.success(), "sift {w}x{h}: {}", stderr(&o));
        assert!(!stderr(&o).contains("panicked"));
        assert!(stdout(&o).starts_with("0 keypoints in "), "sift {w}x{h}: {}", stdout(&o));
        let o = siftlab(&["sift", p.to_str().unwrap(), "--json"]);
        assert!(o.status.success(), "sift --json {w}x{h}: {}", stderr(&o));
        let doc = json::parse(stdout(&o).trim()).expect("valid JSON");
        assert_eq!(doc.get("keypoints").and_then(|v| v.as_arr()).map(|a| a.len()), Some(0));
    }
    // get_info on tiny frames: SIFT finds nothing, so feature 0 does not exist.
    let tiny = png(8, 8, |x, y| ((x * 37 + y * 91) % 256) as u8);
    let root = dataset_with("tiny-ds", &tiny, &tiny);
    let o = siftlab(&["-d", root.to_str().unwrap(), "get_info", "-a", "nn", "1", "0"]);
    assert_fails(&o, &["feature"], "get_info on tiny frames");
    let _ = fs::remove_dir_all(&root);
    let _ = fs::remove_dir_all(&dir);
}

#[test]
fn a_broken_frame_stops_view_trajectory_with_the_error_on_its_own_line() {
    let ds = scratch("broken-frame");
    let frames = ds.join("gray/00/image_0");
    fs::create_dir_all(&frames).unwrap();
    fs::create_dir_all(ds.join("poses")).unwrap();
    fs::copy(dataset().join("poses/00.txt"), ds.join("poses/00.txt")).unwrap();
    for i in 0..5 {
        let name = format!("{i:06}.png");
        fs::copy(dataset().join("gray/00/image_0").join(&name), frames.join(&name)).unwrap();
    }
    fs::write(frames.join("000005.png"), b"not a png").unwrap();
    // FRAME_ID 5: frames 0 to 5, as the lab counts.
    let o = siftlab_in(&ds, &["-d", ds.to_str().unwrap(), "view_trajectory", "5"]);
    assert_fails(&o, &["frame 5", "000005.png", "not an image"], "broken frame 5");
    let err = stderr(&o);
    // Five frames of SIFT take well over the bar's 100 ms refresh: it was drawn.
    assert!(err.contains("/6 frames"), "no progress bar before the error\nstderr: {err:?}");
    assert!(
        err.lines().any(|l| l.starts_with("siftlab: error: frame 5")),
        "the error must start its own line, not follow the progress bar\nstderr: {err:?}"
    );
    assert!(!ds.join("trajectory.png").exists(), "no trajectory.png from a failed run");
    let _ = fs::remove_dir_all(&ds);
}

#[test]
fn siftlab_simd_caps_the_kernels_without_changing_the_result() {
    let frame = dataset().join(format!("gray/00/image_0/{}.png", first_golden_frame()));
    let lanes = golden_lanes().to_string();
    let sift = |level: Option<&str>| {
        let mut cmd = Command::new(env!("CARGO_BIN_EXE_siftlab"));
        cmd.args(["--opencv-lanes", &lanes, "sift", frame.to_str().unwrap(), "--json"]);
        match level {
            Some(l) => cmd.env("SIFTLAB_SIMD", l),
            None => cmd.env_remove("SIFTLAB_SIMD"),
        };
        cmd.output().expect("cannot start the siftlab binary")
    };
    let uncapped = sift(None);
    assert!(uncapped.status.success(), "{}", stderr(&uncapped));
    assert!(stdout(&uncapped).contains("\"keypoints\""));
    for level in ["avx2", "scalar", "AVX512"] {
        let o = sift(Some(level));
        assert!(o.status.success(), "SIFTLAB_SIMD={level}: {}", stderr(&o));
        assert!(stdout(&o) == stdout(&uncapped), "SIFTLAB_SIMD={level} changed the keypoints or descriptors");
    }
    let o = sift(Some("sse4"));
    assert_eq!(o.status.code(), Some(2), "an unknown level is a usage error");
    assert!(stderr(&o).contains("SIFTLAB_SIMD=sse4 is not a SIMD level: use scalar, avx2 or avx512"), "{}", stderr(&o));
    assert!(stdout(&o).is_empty());
}

/// The lab manual's eight examples, through the binary on the bundled frames:
/// stdout is the lab's four lines with the manual's printed value; for the
/// introduction's example, OpenCV 4.8.0.76's value, and the manual's at the
/// index OpenCV 4.8.0.76 gives that keypoint.
#[test]
fn the_manuals_examples_print_the_manuals_values() {
    let cases = EXAMPLES.iter().map(|e| (e, e.feature, e.siftlab_value()));
    let moved = EXAMPLES.iter().filter_map(|e| e.differs.map(|d| (e, d.feature, e.expected)));
    for (e, feature, value) in cases.chain(moved) {
        let mut argv = vec!["-d".to_string(), "www/demo/MyKITTI".into(), "get_info".into(), "-a".into(), e.algo.into()];
        if let Some(t) = e.threshold {
            argv.extend(["-t".into(), t.to_string()]);
        }
        argv.extend([e.frame.to_string(), feature.to_string()]);
        let argv_ref: Vec<&str> = argv.iter().map(String::as_str).collect();
        let o = siftlab(&argv_ref);
        assert!(o.status.success(), "siftlab {argv:?}: {}", stderr(&o));
        let t = e.threshold.map_or("None".to_string(), siftlab_core::pyfmt::py_float);
        let want = format!(
            "vo params: ('{}', {t}, 'www/demo/MyKITTI')\ndebug run: get_info({}, {feature})\nret value: {value}\nret count: 3\n",
            e.algo, e.frame
        );
        assert_eq!(stdout(&o), want, "{}: {}", e.task, e.command_for(feature));
    }
}

/// `view_trajectory FRAME_ID` runs frames 0..=FRAME_ID as the lab counts:
/// `--save-poses` writes FRAME_ID+1 lines, stdout is the lab's three lines and
/// the summary goes to stderr.
#[test]
fn view_trajectory_counts_frames_as_the_lab_does() {
    let dir = scratch("vo-count");
    let poses = dir.join("p.txt");
    let png = dir.join("t.png");
    let ds = dataset();
    let o = siftlab(&[
        "-d",
        ds.to_str().unwrap(),
        "view_trajectory",
        "4",
        "--save-poses",
        poses.to_str().unwrap(),
        "--output",
        png.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let want = format!(
        "vo params: (None, None, '{}')\ndebug run: view_trajectory(4,)\nret value: None\n",
        ds.to_str().unwrap()
    );
    assert_eq!(stdout(&o), want);
    assert_eq!(fs::read_to_string(&poses).unwrap().lines().count(), 5, "frames 0..=4");
    assert!(stderr(&o).contains("trajectory error (ATE RMSE, 5 frames)"), "{}", stderr(&o));
    assert!(png.exists());

    // Beyond the bundled run of frames: which frames exist, and what to ask for.
    let o = siftlab(&["-d", ds.to_str().unwrap(), "view_trajectory", "151", "--output", png.to_str().unwrap()]);
    assert_fails(
        &o,
        &["frames 0 to 151", "frames 0 to 150 only", "000151.png", "FRAME_ID 150 or less"],
        "view_trajectory 151",
    );
    let _ = fs::remove_dir_all(&dir);
}
