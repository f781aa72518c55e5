//! The OpenCV goldens' files read from bytes: a `.sift` golden (format in
//! `golden.rs`) and the SIMD width in `meta.json`. Shared by the native golden
//! tests (through `golden_data`, which reads the files) and the browser test
//! (`wasm_golden/`, which has no file system and includes their bytes).

#![allow(dead_code)] // each test binary uses its own part

use siftlab_core::sift::KeyPoint;

pub struct Golden {
    pub width: u32,
    pub height: u32,
    pub keypoints: Vec<KeyPoint>,
    pub descriptors: Vec<[u8; 128]>,
}

/// A `SIFTGLD1` golden; `name` labels the assertion messages.
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
    let descriptors = bytes[kp_end..].chunks_exact(128).map(|c| <[u8; 128]>::try_from(c).unwrap()).collect();
    Golden { width, height, keypoints, descriptors }
}

/// The SIMD width OpenCV's SIFT kernels ran with where a golden set was
/// written (`opencv_simd_lanes` in its meta.json; docs/fidelity.md §SIFT-13).
pub fn meta_lanes(meta: &str, name: &str) -> usize {
    let meta = siftlab_core::json::parse(meta).expect("meta.json is JSON");
    let lanes = meta.get("opencv_simd_lanes").and_then(|v| v.as_i64()).expect("meta.json: opencv_simd_lanes") as usize;
    assert!(matches!(lanes, 8 | 16), "{name}/meta.json: opencv_simd_lanes {lanes}");
    lanes
}
