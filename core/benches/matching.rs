//! The matcher on a fixture pair's full descriptor sets (1500 x 1500): knn k=2 as
//! OpenCV's `BFMatcher().knnMatch(des1, des2, k=2)`, and each lab strategy applied to
//! every query feature, as compared by tests/benchmarks/bench_compare.sh.

// criterion is a native dev-dependency: on wasm32 (`cargo clippy --all-targets
// --target wasm32-unknown-unknown`) this bench is an empty program.
#![cfg_attr(target_arch = "wasm32", no_main)]
#![cfg(not(target_arch = "wasm32"))]

mod common;

use criterion::{black_box, criterion_group, criterion_main, Criterion};
use siftlab_core::matching::{knn_match, match_all, match_feature, Strategy};
use siftlab_core::sift::{detect_and_compute, Features, SiftParams};

/// SIFT of frame `id` of the bench dataset.
fn features(id: usize) -> Features {
    detect_and_compute(&common::frame(id), &SiftParams::for_host())
}

/// Every query feature through `strategy` on this thread only, for the comparison with
/// OpenCV under `cv2.setNumThreads(1)`.
fn all_features_one_thread(s: &Strategy, prev: &Features, cur: &Features) -> usize {
    (0..prev.keypoints.len()).map(|i| match_feature(s, prev, cur, i).map(|m| m.len()).unwrap_or(0)).sum()
}

fn bench_matching(c: &mut Criterion) {
    let (prev, cur) = (features(0), features(1));
    eprintln!("matching bench: {} x {} descriptors", prev.descriptors.len(), cur.descriptors.len());
    let mut g = c.benchmark_group("matching");
    g.sample_size(20);
    g.bench_function("knn2", |b| b.iter(|| knn_match(black_box(&prev.descriptors), black_box(&cur.descriptors), 2)));
    let strategies = [
        ("dt", Strategy::parse("dt", Some(250.0))),
        ("nn", Strategy::parse("nn", Some(250.0))),
        ("nndr", Strategy::parse("nndr", Some(0.8))),
    ];
    for (name, s) in strategies {
        let s = s.expect("valid strategy");
        // `match_all` is what the CLI and app use (all cores natively); `_1t` is one thread.
        g.bench_function(name, |b| b.iter(|| match_all(black_box(&s), black_box(&prev), black_box(&cur))));
        g.bench_function(format!("{name}_1t"), |b| {
            b.iter(|| all_features_one_thread(black_box(&s), black_box(&prev), black_box(&cur)))
        });
    }
    g.finish();
}

criterion_group!(benches, bench_matching);
criterion_main!(benches);
