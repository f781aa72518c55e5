//! What the benches share: the frames of `$SIFTLAB_BENCH_DATASET` (default:
//! the bundled KITTI frames); bench_compare.sh points OpenCV at the same
//! dataset.

use std::path::{Path, PathBuf};

use siftlab_core::GrayImage;

/// Frame `id` of the bench dataset, decoded.
pub fn frame(id: usize) -> GrayImage {
    let ds = std::env::var_os("SIFTLAB_BENCH_DATASET")
        .map(PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("../www/demo/MyKITTI"));
    let p = ds.join(format!("gray/00/image_0/{id:06}.png"));
    let bytes = std::fs::read(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
    GrayImage::decode(&bytes).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}
