//! `siftlab view_trajectory` with the student's matcher and the outputs of
//! issue 24: `--metrics`, `--plot`, `--save-poses-tum`, checked against the
//! committed OpenCV and numpy references (no Python needed).

use std::fs;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn siftlab(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_siftlab")).current_dir(repo_root()).args(args).output().unwrap()
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("siftlab-clitraj-{}-{name}", std::process::id()));
    let _ = fs::remove_dir_all(&dir);
    fs::create_dir_all(&dir).unwrap();
    dir
}

/// `"key": value` of the one-line JSON object (or fixture case line) `line`.
fn json_number(line: &str, key: &str) -> Option<f64> {
    let rest = &line[line.find(&format!("\"{key}\": "))? + key.len() + 4..];
    let v = &rest[..rest.find([',', '}']).unwrap_or(rest.len())];
    v.trim().parse().ok()
}

/// nndr 0.8 over frames 0–99: the lab's stdout, positions equal to OpenCV's
/// loop, metrics equal to numpy's, a TUM file and an SVG plot.
#[test]
fn matcher_driven_run_writes_metrics_plot_and_tum_poses() {
    let dir = scratch("nndr");
    let (poses, tum, metrics, plot) = (dir.join("p.txt"), dir.join("t.txt"), dir.join("m.json"), dir.join("plot.svg"));
    let arg = |p: &PathBuf| p.to_str().unwrap().to_string();
    let args = [
        "-d",
        "www/demo/MyKITTI",
        "view_trajectory",
        "-a",
        "nndr",
        "-t",
        "0.8",
        "99",
        "--output",
        &arg(&dir.join("w.png")),
        "--save-poses",
        &arg(&poses),
        "--save-poses-tum",
        &arg(&tum),
        "--metrics",
        &arg(&metrics),
        "--plot",
        &arg(&plot),
    ];
    let o = siftlab(&args);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert_eq!(
        String::from_utf8_lossy(&o.stdout),
        "vo params: ('nndr', 0.8, 'www/demo/MyKITTI')\ndebug run: view_trajectory(99,)\nret value: None\n"
    );
    assert!(err.contains("nndr 0.8 (100 frames): ATE 1.1077 m (aligned 0.1667 m)"), "{err}");

    // Positions: tests/fixtures/vo_matched/nndr_0.8.txt (OpenCV, IPP off).
    let rows = |p: &Path| -> Vec<Vec<f64>> {
        fs::read_to_string(p).unwrap().lines().map(|l| l.split(' ').map(|v| v.parse().unwrap()).collect()).collect()
    };
    let want = rows(&repo_root().join("tests/fixtures/vo_matched/nndr_0.8.txt"));
    let got = rows(&poses);
    assert_eq!(got.len(), 100);
    for (g, w) in got.iter().zip(&want) {
        for k in [3, 7, 11] {
            assert!((g[k] - w[k]).abs() <= 1e-6, "{g:?} vs OpenCV {w:?}");
        }
    }
    // TUM: i/10 s, the same positions, unit quaternions.
    let t = rows(&tum);
    assert_eq!(t.len(), 100);
    for (i, (l, g)) in t.iter().zip(&got).enumerate() {
        assert_eq!(l.len(), 8);
        assert!((l[0] - i as f64 / 10.0).abs() < 1e-12);
        assert_eq!([l[1], l[2], l[3]], [g[3], g[7], g[11]]);
        let q: f64 = l[4..].iter().map(|v| v * v).sum();
        assert!((q - 1.0).abs() < 1e-12 && l[7] >= 0.0);
    }
    // Metrics: tests/fixtures/metrics/reference.json (numpy on the OpenCV poses,
    // which differ from ours by ≤ 3.2e-8 m, hence 1e-6 relative).
    let m = fs::read_to_string(&metrics).unwrap();
    let reference = fs::read_to_string(repo_root().join("tests/fixtures/metrics/reference.json")).unwrap();
    let case = reference.lines().find(|l| l.starts_with("\"nndr_0.8\"")).unwrap();
    for key in ["frames", "ate_rmse", "ate_rmse_aligned", "rpe_trans_rmse", "rpe_rot_rmse_deg"] {
        let (g, w) = (json_number(&m, key).unwrap(), json_number(case, key).unwrap());
        assert!((g - w).abs() <= 1e-6 * w.abs(), "{key}: {g} vs numpy {w}");
    }
    assert!(m.contains("\"kitti_t_err_pct\": null, \"kitti_r_err_deg_per_100m\": null}"), "{m}");
    let svg = fs::read_to_string(&plot).unwrap();
    assert!(svg.starts_with("<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"720\" height=\"990\""), "{svg:.200}");
    for text in [">ground truth</text>", ">nndr 0.8</text>", ">start</text>", ">x (m)</text>", ">frame</text>"] {
        assert!(svg.contains(text), "{text}");
    }
    let _ = fs::remove_dir_all(&dir);
}

/// The LK run's `--plot` as PNG, and what a bad flag says.
#[test]
fn lk_plot_png_and_bad_flags() {
    let dir = scratch("lk");
    let plot = dir.join("plot.png");
    let o = siftlab(&[
        "-d",
        "www/demo/MyKITTI",
        "view_trajectory",
        "4",
        "--output",
        dir.join("w.png").to_str().unwrap(),
        "--plot",
        plot.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(String::from_utf8_lossy(&o.stderr).contains("LK (5 frames): ATE "));
    let img = image::open(&plot).unwrap().to_rgb8();
    assert_eq!(img.dimensions(), (720, 990));
    assert_eq!(img.get_pixel(2, 2).0, [255, 255, 255]);
    // The truth (black) and the LK run (the palette's vermillion) are drawn.
    use siftlab_core::render::palette::{TRACKERS, TRUTH};
    assert!(img.pixels().any(|p| p.0 == TRUTH.color) && img.pixels().any(|p| p.0 == TRACKERS[0].color));

    let o = siftlab(&["-d", "www/demo/MyKITTI", "view_trajectory", "-t", "0.8", "4"]);
    assert!(!o.status.success() && String::from_utf8_lossy(&o.stderr).contains("--algorithm"));
    let o = siftlab(&["-d", "www/demo/MyKITTI", "view_trajectory", "-a", "nndr", "-t", "1.5", "4"]);
    assert!(String::from_utf8_lossy(&o.stderr).contains("nndr threshold 1.5 is outside [0, 1]"));
    let o = siftlab(&["-d", "www/demo/MyKITTI", "view_trajectory", "4", "--plot", "x.gif"]);
    assert!(String::from_utf8_lossy(&o.stderr).contains("must end in .png or .svg"));
    let _ = fs::remove_dir_all(&dir);
}
