//! SIFT detect+compute on a 1241x376 fixture frame (KITTI size), single thread, as
//! compared with OpenCV's `detectAndCompute` under `cv2.setNumThreads(1)` by
//! tests/benchmarks/bench_compare.sh; and the stage that costs most, the five blurs
//! of the first octave (a 2482x752 plane), on their own.

// criterion is a native dev-dependency: on wasm32 (`cargo clippy --all-targets
// --target wasm32-unknown-unknown`) this bench is an empty program.
#![cfg_attr(target_arch = "wasm32", no_main)]
#![cfg(not(target_arch = "wasm32"))]

use std::path::Path;

use criterion::{black_box, criterion_group, criterion_main, Criterion};
use siftlab_core::internals::gaussian_blur;
use siftlab_core::internals::initial_image;
use siftlab_core::internals::level_sigmas;
use siftlab_core::sift::{detect_and_compute, SiftParams};
use siftlab_core::GrayImage;

/// Frame 0 of `$SIFTLAB_BENCH_DATASET` (default: the bundled KITTI frames); bench_compare.sh
/// points OpenCV at the same dataset.
fn load() -> GrayImage {
    let ds = std::env::var_os("SIFTLAB_BENCH_DATASET")
        .map(std::path::PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("../www/demo/MyKITTI"));
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

/// Gaussian levels 1..=5 of octave 0 from the frame's doubled base, each blurred
/// from the one before (docs/fidelity.md §SIFT-4): about two fifths of a VO frame's CPU time.
fn bench_octave0_blurs(c: &mut Criterion) {
    let img = load();
    let params = SiftParams::for_host();
    let base = initial_image(&img, params.sigma);
    let sigmas = level_sigmas(params.sigma, params.n_octave_layers);
    let mut g = c.benchmark_group("sift");
    g.sample_size(20);
    g.bench_function("octave0_blurs_2482x752", |b| {
        b.iter(|| {
            let mut level = gaussian_blur(black_box(&base), sigmas[1]);
            for &s in &sigmas[2..] {
                level = gaussian_blur(&level, s);
            }
            level
        })
    });
    // The same on the calling thread alone: how the odometry runs it, one
    // frame per core (`par::serial`).
    g.bench_function("octave0_blurs_2482x752_1t", |b| {
        b.iter(|| {
            siftlab_core::internals::serial(|| {
                let mut level = gaussian_blur(black_box(&base), sigmas[1]);
                for &s in &sigmas[2..] {
                    level = gaussian_blur(&level, s);
                }
                level
            })
        })
    });
    g.finish();
}

criterion_group!(benches, bench_sift, bench_octave0_blurs);
criterion_main!(benches);
