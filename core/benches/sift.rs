//! SIFT detect+compute on a 1241x376 fixture frame (KITTI size), single thread, as
//! compared with OpenCV's `detectAndCompute` under `cv2.setNumThreads(1)` by
//! tests/scripts/bench_compare.sh.

use std::path::Path;

use criterion::{black_box, criterion_group, criterion_main, Criterion};
use siftlab_core::sift::{detect_and_compute, SiftParams};
use siftlab_core::GrayImage;

/// Frame 0 of `$SIFTLAB_BENCH_DATASET` (default: the committed fixtures); bench_compare.sh
/// points OpenCV at the same dataset.
fn load() -> GrayImage {
    let ds = std::env::var_os("SIFTLAB_BENCH_DATASET")
        .map(std::path::PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/fixtures/mykitti"));
    let p = ds.join("gray/00/image_0/000000.png");
    let bytes = std::fs::read(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
    GrayImage::decode(&bytes).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

fn bench_sift(c: &mut Criterion) {
    let img = load();
    assert_eq!((img.width(), img.height()), (1241, 376), "bench frame must be KITTI-sized");
    let params = SiftParams::for_host();
    let n = detect_and_compute(&img, &params).keypoints.len();
    eprintln!("sift bench: frame 0, {n} keypoints");
    let mut g = c.benchmark_group("sift");
    g.sample_size(20);
    g.bench_function("detect_and_compute_1241x376", |b| {
        b.iter(|| detect_and_compute(black_box(&img), black_box(&params)))
    });
    g.finish();
}

criterion_group!(benches, bench_sift);
criterion_main!(benches);
