//! The OpenCV goldens (`tests/fixtures/golden-avx2` on the bundled KITTI
//! frames, `tests/fixtures/golden` on synthetic frames), shared by the golden
//! test binaries. Format: see `golden.rs`.

#![allow(dead_code)] // each test binary uses its own part

use std::fs;
use std::path::{Path, PathBuf};

use siftlab_core::sift::{KeyPoint, SiftParams};

use super::json_mini;

/// One committed set of OpenCV goldens, written by
/// `tests/scripts/gen_goldens.py` on one CPU: `noipp/`, `ipp/`,
/// `get_info.jsonl` and `meta.json`, which records the dataset the goldens
/// were computed on and the SIMD width OpenCV's dispatched SIFT kernels ran
/// with (docs/fidelity.md §SIFT-13: 16 on AVX-512, 8 on AVX2). The width is taken from there,
/// not from the host, so a test means the same on any CPU.
pub struct GoldenSet {
    /// The folder below `tests/fixtures` (`golden`, `golden-avx2`).
    pub name: &'static str,
    pub lanes: usize,
    /// The dataset the goldens were computed on, as the repository-relative
    /// path `get_info.jsonl` prints (`www/demo/MyKITTI`).
    pub dataset: String,
}

impl GoldenSet {
    fn new(name: &'static str) -> GoldenSet {
        let path = fixtures().join(name).join("meta.json");
        let meta = fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let meta = json_mini::parse(&meta).expect("meta.json is JSON");
        let lanes = meta.get("opencv_simd_lanes").and_then(|v| v.i64()).expect("meta.json: opencv_simd_lanes") as usize;
        assert!(matches!(lanes, 8 | 16), "{name}/meta.json: opencv_simd_lanes {lanes}");
        let dataset = meta.get("dataset").and_then(|v| v.str()).expect("meta.json: dataset").to_owned();
        GoldenSet { name, lanes, dataset }
    }

    /// The golden dataset's folder.
    pub fn dataset_dir(&self) -> PathBuf {
        repo_root().join(&self.dataset)
    }

    /// The frame a golden was computed from (`id` as `000150`).
    pub fn frame_path(&self, id: &str) -> PathBuf {
        self.dataset_dir().join(format!("gray/00/image_0/{id}.png"))
    }

    pub fn dir(&self) -> PathBuf {
        fixtures().join(self.name)
    }

    /// The lab's SIFT parameters at this set's SIMD width.
    pub fn params(&self) -> SiftParams {
        SiftParams { opencv_lanes: self.lanes, ..SiftParams::default() }
    }

    /// The golden of frame `id` of `kind` (`noipp` or `ipp`).
    pub fn read(&self, kind: &str, id: &str) -> Golden {
        let path = self.dir().join(kind).join(format!("{id}.sift"));
        let bytes = fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        parse_golden(&bytes, &path.display().to_string())
    }
}

/// The primary set (`golden-avx2/`: the bundled real KITTI frames, written on
/// an AVX2 CPU, 8 lanes: the width of most students' laptops, the app's
/// default and OpenCV's validated configuration).
pub fn primary_set() -> GoldenSet {
    GoldenSet::new("golden-avx2")
}

/// Every committed set: the primary one and `golden/` (an AVX-512 CPU, 16
/// lanes; on the synthetic frames of `tests/fixtures/synthetic` until it is
/// regenerated on an AVX-512 CPU).
pub fn golden_sets() -> Vec<GoldenSet> {
    let sets = vec![primary_set(), GoldenSet::new("golden")];
    assert_ne!(sets[0].lanes, sets[1].lanes, "the golden sets should cover both SIMD widths");
    sets
}

/// The primary set's SIMD width.
pub fn golden_lanes() -> usize {
    primary_set().lanes
}

pub fn golden_params() -> SiftParams {
    primary_set().params()
}

pub struct Golden {
    pub width: u32,
    pub height: u32,
    pub keypoints: Vec<KeyPoint>,
    pub descriptors: Vec<[u8; 128]>,
}

pub fn fixtures() -> PathBuf {
    repo_root().join("tests/fixtures")
}

pub fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// The bundled real KITTI data (`www/demo/MyKITTI`).
pub fn kitti() -> PathBuf {
    repo_root().join("www/demo/MyKITTI")
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
    let descriptors = bytes[kp_end..].chunks_exact(128).map(|c| <[u8; 128]>::try_from(c).unwrap()).collect();
    Golden { width, height, keypoints, descriptors }
}

/// Frame ids that have a golden of `kind` in the primary set, sorted.
pub fn golden_frames(kind: &str) -> Vec<String> {
    set_frames(&primary_set(), kind)
}

/// Frame ids that have a golden of `kind` in `set`, sorted.
pub fn set_frames(set: &GoldenSet, kind: &str) -> Vec<String> {
    let dir = set.dir().join(kind);
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
