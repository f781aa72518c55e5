//! `siftlab view_feature` / `view_info` end to end: the binary runs in a
//! scratch directory on the lab manual's example frames (the bundled KITTI
//! 119/120 and 149/150) and its PNGs are compared with the lab's OpenCV 4.8
//! images (drawMatchesKnn flags=2, circles radius 10 thickness 2), drawn by
//! `core/src/render/testdata/compare_visual.py --lab-one` (with SIFTLAB_HASH=1
//! it prints these hashes) on OpenCV's own keypoints. The lab images are too
//! big to commit, so the tests hold their FNV-1a 64 hash (RGB bytes,
//! row-major) plus pixels we can name: circle rims at the `get_info`
//! coordinates and the frames themselves.

#![cfg(not(target_arch = "wasm32"))]

use std::fs;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn dataset() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../www/demo/MyKITTI")
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("siftlab-cli-visual-{}-{name}", std::process::id()));
    let _ = fs::remove_dir_all(&dir);
    fs::create_dir_all(&dir).unwrap();
    dir
}

/// Runs the binary in `dir`. `--opencv-lanes 8`: the hashes were made with
/// the wheel on an AVX2 CPU (as the bundled goldens), so the keypoints must be
/// that machine's whatever CPU runs the test.
fn run(dir: &Path, args: &[&str]) -> Output {
    let ds = dataset();
    let mut all = vec!["--opencv-lanes", "8", "-d", ds.to_str().unwrap()];
    all.extend_from_slice(args);
    let o = Command::new(env!("CARGO_BIN_EXE_siftlab")).current_dir(dir).args(&all).output().expect("run siftlab");
    assert!(o.status.success(), "{args:?} failed: {}", String::from_utf8_lossy(&o.stderr));
    o
}

fn load(path: &Path) -> image::RgbImage {
    image::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display())).to_rgb8()
}

fn fnv1a64(img: &image::RgbImage) -> u64 {
    img.as_raw().iter().fold(0xcbf2_9ce4_8422_2325u64, |h, &b| (h ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3))
}

fn frame(id: usize) -> image::RgbImage {
    load(&dataset().join(format!("gray/00/image_0/{id:06}.png")))
}

const GREEN: [u8; 3] = [0, 255, 0];

#[test]
fn view_info_dt_many_matches_equals_opencv() {
    // The manual's Task 1: get_info(150, 209) with dt 300 ->
    // ((226, 119), [(208, 115), (394, 52), (519, 213), (872, 160), (402, 48)], ...).
    let dir = scratch("dt300");
    let o = run(&dir, &["view_info", "-a", "dt", "-t", "300", "150", "209"]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.ends_with("debug run: view_info(150, 209)\nret value: None\n"), "{out}");
    assert!(!dir.join("opencv_visual.png").exists(), "view_info writes only custom_visual.png");
    let img = load(&dir.join("custom_visual.png"));
    assert_eq!(img.dimensions(), (2 * 1241, 2 * 376));
    assert_eq!(fnv1a64(&img), 0xc677_75c8_2972_cc92, "custom_visual.png differs from OpenCV's");
    // Query circle on the previous frame (lower half starts at y=376):
    // left rim (216, 119+376) and top rim (226, 109+376) are green.
    assert_eq!(img.get_pixel(216, 495).0, GREEN);
    assert_eq!(img.get_pixel(226, 485).0, GREEN);
    // First matched point (208, 115) on the current frame (x + 1241): left rim.
    assert_eq!(img.get_pixel(1241 + 198, 376 + 115).0, GREEN);
    // Far from every circle the lower half is the frame itself.
    let f = frame(149);
    assert_eq!(img.get_pixel(5, 376 + 370).0, f.get_pixel(5, 370).0);
}

#[test]
fn view_feature_nn_single_match_equals_opencv() {
    // The manual's Task 2: get_info(150, 209) with nn -> ((226, 119), [(208, 115)], [72.02...]).
    let dir = scratch("nn");
    run(&dir, &["view_feature", "-a", "nn", "150", "209"]);
    assert!(!dir.join("custom_visual.png").exists());
    let img = load(&dir.join("opencv_visual.png"));
    assert_eq!(img.dimensions(), (2482, 376));
    assert_eq!(fnv1a64(&img), 0x8f02_9a9e_7804_1345, "opencv_visual.png differs from OpenCV's");
    // One random theRNG colour for the only match: the line from the query
    // keypoint (~226, ~119) to (~208+1241, ~115) passes its midpoint
    // (~837, ~117) in a colour the gray frames do not have.
    let mid = img.get_pixel(837, 117).0;
    assert!(mid[0] != mid[1] || mid[1] != mid[2], "midpoint {mid:?} is still gray");
    // Away from the line the frames are copied unchanged, side by side.
    let (f0, f1) = (frame(149), frame(150));
    assert_eq!(img.get_pixel(100, 300).0, f0.get_pixel(100, 300).0);
    assert_eq!(img.get_pixel(1241 + 600, 300).0, f1.get_pixel(600, 300).0);
}

#[test]
fn no_match_gives_the_plain_frames() {
    // The manual's Task 3: get_info(120, 45) with nndr 0.93 -> ((0, 0), [], []): nothing drawn.
    let dir = scratch("nndr");
    run(&dir, &["view_info", "-a", "nndr", "-t", "0.93", "120", "45"]);
    let img = load(&dir.join("custom_visual.png"));
    assert_eq!(fnv1a64(&img), 0x62a8_8bc7_1e1f_82fd);
    let (f1, f2) = (frame(119), frame(120));
    for (x, y) in [(0, 0), (1240, 375), (617, 200)] {
        assert_eq!(img.get_pixel(x, y).0, f1.get_pixel(x, y).0);
        assert_eq!(img.get_pixel(x, y + 376).0, f1.get_pixel(x, y).0);
        assert_eq!(img.get_pixel(1241 + x, y + 376).0, f2.get_pixel(x, y).0);
    }
}

#[test]
fn visual_commands_check_arguments_like_get_info() {
    let dir = scratch("bad");
    let ds = dataset();
    for args in [
        vec!["view_feature", "-a", "nndr", "-t", "1.5", "2", "7"],
        vec!["view_info", "-a", "dt", "2", "7"],
        vec!["view_info", "-a", "dt", "-t", "100", "0", "7"],
        vec!["view_feature", "-a", "nn", "2", "999999"],
    ] {
        let mut all = vec!["-d", ds.to_str().unwrap()];
        all.extend_from_slice(&args);
        let o = Command::new(env!("CARGO_BIN_EXE_siftlab")).current_dir(&dir).args(&all).output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{args:?} should fail");
        assert_ne!(o.status.code(), Some(101), "{args:?} panicked: {err}");
        assert!(err.contains("siftlab: error:"), "{args:?}: {err}");
        assert!(
            !dir.join("opencv_visual.png").exists() && !dir.join("custom_visual.png").exists(),
            "{args:?} wrote a PNG"
        );
    }
}
