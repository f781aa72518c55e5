//! Bad input: one clear message, non-zero exit, no panic.

use crate::{assert_fails, dataset, scratch, siftlab, siftlab_in, stderr, stdout};
use siftlab_core::json;
use std::fs;
use std::path::PathBuf;

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
