//! LK in the browser: the simd128 kernels bit for bit against OpenCV and the
//! portable kernels.

use crate::{performance_now, sift, FRAME0, FRAME1};
use siftlab_core::GrayImage;
use wasm_bindgen_test::*;

include!("../../src/vo/testdata/lk_golden.rs");

/// LK in the browser: the simd128 kernels against OpenCV's calcOpticalFlowPyrLK
/// (the 68-point golden of the native unit test) and against the portable
/// kernels, bit for bit, on the KITTI-sized fixture pair (every frame-0 SIFT
/// keypoint, as the lab tracks them) and on a noisy pair whose large
/// gradients force the replay of OpenCV's f32 order.
#[wasm_bindgen_test]
fn lk_in_the_browser_is_bit_exact() {
    use siftlab_core::internals::calc_optical_flow_pyr_lk_portable;
    use siftlab_core::vo::{calc_optical_flow_pyr_lk, LkParams, LkResult};
    let lk = LkParams::default();
    let bits = |r: &LkResult, i: usize| [r.next_pts[i][0].to_bits(), r.next_pts[i][1].to_bits()];

    let prev = GrayImage::decode(include_bytes!("../../src/vo/testdata/lk_prev.png")).unwrap();
    let next = GrayImage::decode(include_bytes!("../../src/vo/testdata/lk_next.png")).unwrap();
    let pts: Vec<[f32; 2]> = LK_GOLDEN.iter().map(|g| g.0).collect();
    let out = calc_optical_flow_pyr_lk(&prev, &next, &pts, &lk);
    for (i, g) in LK_GOLDEN.iter().enumerate() {
        assert_eq!(out.status[i] as u8, g.2, "status of point {i}");
        assert_eq!(bits(&out, i), g.1, "point {i} {:?}", g.0);
        if g.2 == 1 {
            assert_eq!(out.err[i].to_bits(), g.3, "err of point {i}");
        }
    }

    let (f0, _) = sift(FRAME0);
    let frame0 = GrayImage::decode(FRAME0).unwrap();
    let frame1 = GrayImage::decode(FRAME1).unwrap();
    let pts: Vec<[f32; 2]> = f0.keypoints.iter().map(|k| [k.x, k.y]).collect();
    let t0 = performance_now();
    let simd = calc_optical_flow_pyr_lk(&frame0, &frame1, &pts, &lk);
    let t1 = performance_now();
    let portable = calc_optical_flow_pyr_lk_portable(&frame0, &frame1, &pts, &lk);
    let t2 = performance_now();
    assert_eq!(simd.status, portable.status);
    for i in 0..pts.len() {
        assert_eq!(bits(&simd, i), bits(&portable, i), "fixture point {i}");
        if simd.status[i] {
            assert_eq!(simd.err[i].to_bits(), portable.err[i].to_bits(), "err of fixture point {i}");
        }
    }
    let tracked = simd.status.iter().filter(|&&s| s).count();

    // A noisy pair: xorshift noise of ±90 on smooth texture, shifted by 1.3 px.
    let (w, h) = (320usize, 200usize);
    let noisy = |dx: f64| {
        let mut s = 0x9e37_79b9_7f4a_7c15u64;
        let data = (0..w * h)
            .map(|i| {
                s ^= s << 13;
                s ^= s >> 7;
                s ^= s << 17;
                let (x, y) = ((i % w) as f64 + dx, (i / w) as f64);
                let v = 128.0 + 60.0 * (x * 0.11 + y * 0.07).sin() + 40.0 * (y * 0.13 - x * 0.05).cos();
                (v as i64 + (s % 181) as i64 - 90).clamp(0, 255) as u8
            })
            .collect();
        GrayImage::new(w, h, data).unwrap()
    };
    let (a, b) = (noisy(0.0), noisy(1.3));
    let grid: Vec<[f32; 2]> =
        (0..400).map(|k| [-5.0 + (k % 25) as f32 * 13.7, -5.0 + (k / 25) as f32 * 13.3]).collect();
    let (simd, portable) =
        (calc_optical_flow_pyr_lk(&a, &b, &grid, &lk), calc_optical_flow_pyr_lk_portable(&a, &b, &grid, &lk));
    assert_eq!(simd, portable);
    console_log!(
        "wasm LK: 68/68 OpenCV golden points bit-exact; {tracked}/{} fixture keypoints tracked, simd128 = portable \
         bit for bit; WASM_LK_MS={:.1} (portable {:.1} ms)",
        pts.len(),
        t1 - t0,
        t2 - t1
    );
}
