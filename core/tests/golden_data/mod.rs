//! The OpenCV goldens (`tests/fixtures/golden-avx2` on the bundled KITTI
//! frames, `tests/fixtures/golden` on synthetic frames), shared by the golden
//! test binaries. Format: see `golden.rs`.

#![allow(dead_code)] // each test binary uses its own part

use std::fs;
use std::path::{Path, PathBuf};

use siftlab_core::sift::SiftParams;

use siftlab_core::json;

mod format;
pub use format::{meta_lanes, parse_golden, Golden};

/// One committed set of OpenCV goldens, written by
/// `tests/references/gen_goldens.py` on one CPU: `noipp/`, `ipp/`,
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
        let lanes = meta_lanes(&meta, name);
        let meta = json::parse(&meta).expect("meta.json is JSON");
        let dataset = meta.get("dataset").and_then(|v| v.as_str()).expect("meta.json: dataset").to_owned();
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

pub fn fixtures() -> PathBuf {
    repo_root().join("tests/fixtures")
}

pub fn repo_root() -> PathBuf {
    // The workspace root (core/ for the library's tests, core/cli/ for the CLI's).
    let here = Path::new(env!("CARGO_MANIFEST_DIR"));
    here.ancestors().find(|p| p.join("Cargo.lock").exists()).unwrap_or(here).to_path_buf()
}

/// The bundled real KITTI data (`www/demo/MyKITTI`).
pub fn kitti() -> PathBuf {
    repo_root().join("www/demo/MyKITTI")
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
