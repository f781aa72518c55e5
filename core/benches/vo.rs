//! The stages of one visual-odometry frame on KITTI-sized frames 0 → 1
//! (`$SIFTLAB_BENCH_DATASET`, default the committed fixtures), with the lab's
//! parameters: SIFT keypoint detection (nfeatures 1500, no descriptors), LK
//! tracking of those points (AVX2 kernels where the CPU has them, and the
//! portable kernels wasm runs, for the ratio between the two), the essential
//! matrix by RANSAC and recoverPose. `tests/references/compare_vo.py` times the
//! whole loop against OpenCV's.

// criterion is a native dev-dependency: on wasm32 (`cargo clippy --all-targets
// --target wasm32-unknown-unknown`) this bench is an empty program.
#![cfg_attr(target_arch = "wasm32", no_main)]
#![cfg(not(target_arch = "wasm32"))]

mod common;

use criterion::{black_box, criterion_group, criterion_main, Criterion};
use siftlab_core::internals::calc_optical_flow_pyr_lk_portable;
use siftlab_core::sift::{detect, SiftParams};
use siftlab_core::vo::{calc_optical_flow_pyr_lk, find_essential_mat, recover_pose, Camera, LkParams, RansacParams};

fn bench_vo(c: &mut Criterion) {
    let (prev, next) = (common::frame(0), common::frame(1));
    let params = SiftParams::for_host();
    let pts: Vec<[f32; 2]> = detect(&prev, &params).iter().map(|k| [k.x, k.y]).collect();
    let lk = LkParams::default();
    let flow = calc_optical_flow_pyr_lk(&prev, &next, &pts, &lk);
    let (mut refs, mut cur) = (Vec::new(), Vec::new());
    for ((r, c), &ok) in pts.iter().zip(&flow.next_pts).zip(&flow.status) {
        if ok {
            refs.push(*r);
            cur.push(*c);
        }
    }
    let cam = Camera::default();
    let ransac = RansacParams::default();
    let ess = find_essential_mat(&cur, &refs, &cam, &ransac).expect("essential matrix");
    eprintln!("vo bench: {} points, {} tracked, {} RANSAC iterations", pts.len(), cur.len(), ess.iterations);

    let mut g = c.benchmark_group("vo");
    g.sample_size(20);
    g.bench_function("sift_detect_1241x376", |b| b.iter(|| detect(black_box(&prev), black_box(&params))));
    g.bench_function("lk_1500", |b| b.iter(|| calc_optical_flow_pyr_lk(black_box(&prev), black_box(&next), &pts, &lk)));
    g.bench_function("lk_1500_portable", |b| {
        b.iter(|| calc_optical_flow_pyr_lk_portable(black_box(&prev), black_box(&next), &pts, &lk))
    });
    g.bench_function("find_essential_mat", |b| b.iter(|| find_essential_mat(black_box(&cur), &refs, &cam, &ransac)));
    let e = *ess.essential().expect("E");
    g.bench_function("recover_pose", |b| b.iter(|| recover_pose(black_box(&e), &cur, &refs, &cam)));
    g.finish();
}

criterion_group!(benches, bench_vo);
criterion_main!(benches);
