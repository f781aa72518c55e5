//! The `poses` target: the poses parser, the ground-truth scale, the frame
//! checks, the calibration parser, and now and then a dataset folder opened.

use super::check_message;
use siftlab_core::dataset::{self, Dataset};

/// `math.dist` of two points, scaled like CPython's `vector_norm` so that
/// neither huge nor tiny coordinates overflow: within 1 ulp of the truth.
fn naive_dist(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    let d: Vec<f64> = (0..3).map(|k| (a[k] - b[k]).abs()).collect();
    let m = d.iter().copied().fold(0.0, f64::max);
    if m == 0.0 || !m.is_finite() {
        return m;
    }
    d.iter().map(|x| (x / m) * (x / m)).sum::<f64>().sqrt() * m
}

/// The poses parser, the ground-truth scale and the frame checks; one input
/// in 16 also lays out a dataset folder for `Dataset::open`.
pub fn poses(data: &[u8]) {
    let Some((&mode, rest)) = data.split_first() else { return };
    let text = String::from_utf8_lossy(rest);
    let parsed = dataset::parse_poses(&text);
    let lines: Vec<&str> = text.lines().filter(|l| !l.trim().is_empty()).collect();
    let poses = match parsed {
        Ok(p) => {
            assert_eq!(p.len(), lines.len());
            for (row, line) in p.iter().zip(&lines) {
                let want: Vec<f64> = line.split_whitespace().map(|f| f.parse().unwrap()).collect();
                assert_eq!(row.as_slice(), want.as_slice());
                assert!(row.iter().all(|v| v.is_finite()));
            }
            for i in 0..=p.len() {
                match dataset::gt_scale(&p, i) {
                    Ok(s) => {
                        assert!(i >= 1 && i < p.len());
                        let (a, b) = (dataset::position(&p[i - 1]), dataset::position(&p[i]));
                        let want = naive_dist(&a, &b);
                        // A finite scale for finite positions, as math.dist gives.
                        assert!(s.is_finite() || !want.is_finite(), "scale {s} for {a:?} -> {b:?}");
                        if want.is_finite() && want > 0.0 {
                            assert!((s - want).abs() <= want * 1e-15, "scale {s} vs {want} for {a:?} -> {b:?}");
                        }
                    }
                    Err(e) => {
                        check_message(&e);
                        assert!(i == 0 || i >= p.len());
                    }
                }
            }
            p
        }
        Err(e) => {
            check_message(&e);
            assert!(e.to_string().contains("poses/00.txt"), "{e}");
            Vec::new()
        }
    };
    // A dataset as the app assembles one from a picked folder.
    let frame_count = (mode >> 4) as usize;
    let ds = Dataset::from_parts("picked".into(), frame_count, Some(poses.clone()));
    // The same bytes as a calib.txt: a camera that validates, or a message.
    match dataset::parse_calib(&text, "calib.txt") {
        Ok(cam) => assert!(cam.validate().is_ok() && text.contains("P0:")),
        Err(e) => check_message(&e),
    }
    for n in 0..=18 {
        match ds.check_frames(n) {
            Ok(()) => assert!(n <= frame_count && n <= poses.len()),
            Err(e) => {
                check_message(&e);
                assert!(n > frame_count || n > poses.len());
            }
        }
    }
    // The file-system part is slow (a folder per run): one mode value in 16.
    if mode & 15 == 15 {
        open_layout(mode, rest);
    }
}

/// A dataset folder laid out from fuzz bits (the lab's layout or KITTI's,
/// frames folder, poses file, calib.txt, frames that are images or not),
/// opened and read.
fn open_layout(mode: u8, rest: &[u8]) {
    let bits = rest.first().copied().unwrap_or(0) ^ mode;
    let dir = std::env::temp_dir().join(format!("siftlab-fuzz-ds-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let layout = if bits & 8 != 0 { dataset::Layout::Kitti } else { dataset::Layout::Lab };
    let seq = dataset::SequenceLayout::new(layout, "00").unwrap();
    if bits & 1 != 0 {
        std::fs::create_dir_all(dir.join(seq.frame_dir())).unwrap();
        for i in 0..(bits >> 5) as usize {
            let bytes: &[u8] = if bits & 2 != 0 { TINY_PNG } else { &rest[..rest.len().min(64)] };
            std::fs::write(dir.join(seq.frame_path(i)), bytes).unwrap();
        }
        if bits & 16 != 0 {
            std::fs::write(dir.join(seq.calib_file()), rest).unwrap();
        }
    }
    if bits & 4 != 0 {
        std::fs::create_dir_all(dir.join("poses")).unwrap();
        std::fs::write(dir.join(dataset::POSES_FILE), rest).unwrap();
    }
    match Dataset::open(&dir) {
        Ok(ds) => {
            assert_eq!(ds.sequence(), &seq);
            for i in 0..ds.frame_count() {
                if let Err(e) = ds.load_frame(i) {
                    check_message(&e);
                }
            }
            let _ = ds.check_frames(ds.frame_count() + 1).unwrap_err();
        }
        Err(e) => check_message(&e),
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// A 2x2 8-bit gray PNG.
const TINY_PNG: &[u8] = &[
    0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a, 0x00, 0x00, 0x00, 0x0d, 0x49, 0x48, 0x44, 0x52, 0x00, 0x00, 0x00,
    0x02, 0x00, 0x00, 0x00, 0x02, 0x08, 0x00, 0x00, 0x00, 0x00, 0x57, 0xdd, 0x52, 0xf8, 0x00, 0x00, 0x00, 0x0c, 0x49,
    0x44, 0x41, 0x54, 0x78, 0x9c, 0x63, 0x60, 0x00, 0x02, 0x16, 0x00, 0x00, 0x0a, 0x00, 0x05, 0xe2, 0xa9, 0xcd, 0xb7,
    0x00, 0x00, 0x00, 0x00, 0x49, 0x45, 0x4e, 0x44, 0xae, 0x42, 0x60, 0x82,
];
