//! The OpenCV goldens of the fixture frames (`tests/fixtures/golden`), shared
//! by the golden test binaries. Format: see `golden.rs`.

#![allow(dead_code)] // each test binary uses its own part

use std::fs;
use std::path::{Path, PathBuf};

use siftlab_core::sift::{KeyPoint, SiftParams};

use super::json_mini;

/// The SIMD width OpenCV's dispatched SIFT kernels ran with where the goldens were
/// written (spec §13: 16 on AVX-512, 8 on AVX2), from `golden/meta.json`; taken from
/// there, not from the host, so the tests mean the same on any CPU.
pub fn golden_lanes() -> usize {
    let meta = fs::read_to_string(fixtures().join("golden/meta.json")).expect("golden/meta.json");
    let meta = json_mini::parse(&meta).expect("meta.json is JSON");
    meta.get("opencv_simd_lanes").and_then(|v| v.i64()).expect("meta.json: opencv_simd_lanes") as usize
}

pub fn golden_params() -> SiftParams {
    SiftParams { opencv_lanes: golden_lanes(), ..SiftParams::default() }
}

pub struct Golden {
    pub width: u32,
    pub height: u32,
    pub keypoints: Vec<KeyPoint>,
    pub descriptors: Vec<[u8; 128]>,
}

pub fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/fixtures")
}

pub fn parse_golden(bytes: &[u8], name: &str) -> Golden {
    assert!(bytes.len() >= 20, "{name}: too short for a header");
    assert_eq!(&bytes[..8], b"SIFTGLD1", "{name}: bad magic");
    let u32_at = |o: usize| u32::from_le_bytes(bytes[o..o + 4].try_into().unwrap());
    let f32_at = |o: usize| f32::from_le_bytes(bytes[o..o + 4].try_into().unwrap());
    let (width, height, n) = (u32_at(8), u32_at(12), u32_at(16) as usize);
    let kp_end = 20 + n * 24;
    assert_eq!(bytes.len(), kp_end + n * 128, "{name}: size does not match N={n}");
    let keypoints = (0..n)
        .map(|i| {
            let o = 20 + i * 24;
            KeyPoint {
                x: f32_at(o),
                y: f32_at(o + 4),
                size: f32_at(o + 8),
                angle: f32_at(o + 12),
                response: f32_at(o + 16),
                octave: u32_at(o + 20) as i32,
            }
        })
        .collect();
    let descriptors = bytes[kp_end..]
        .chunks_exact(128)
        .map(|c| <[u8; 128]>::try_from(c).unwrap())
        .collect();
    Golden { width, height, keypoints, descriptors }
}

/// Frame ids that have a golden of `kind`, sorted.
pub fn golden_frames(kind: &str) -> Vec<String> {
    let dir = fixtures().join("golden").join(kind);
    let mut ids: Vec<String> = fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("cannot list {}: {e}", dir.display()))
        .filter_map(|e| {
            let p = e.ok()?.path();
            (p.extension()? == "sift").then(|| p.file_stem()?.to_str().map(str::to_owned))?
        })
        .collect();
    ids.sort();
    assert!(!ids.is_empty(), "no goldens in {}", dir.display());
    ids
}

