//! `sift` against the OpenCV (IPP disabled) goldens: `--json` bit for bit, the
//! plain and `--repeat` lines, and `SIFTLAB_SIMD`.

use crate::golden_data::{golden_frames, golden_lanes, golden_sets, primary_set};
use crate::{dataset, siftlab, stderr, stdout};
use siftlab_core::json;
use std::fs;
use std::process::Command;

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
