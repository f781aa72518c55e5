//! The public calls: against OpenCV's own output, against known motion,
//! and the vector kernels against the portable ones on whole frames.

use super::*;
use crate::image::GrayImage;

/// A smooth textured image: sums of sines, so sub-pixel shifts are
/// well defined, sampled at (x + dx, y + dy).
fn textured(w: usize, h: usize, dx: f64, dy: f64) -> GrayImage {
    let mut data = vec![0u8; w * h];
    for y in 0..h {
        for x in 0..w {
            let (u, v) = (x as f64 + dx, y as f64 + dy);
            let val = 128.0
                + 35.0 * (u * 0.27 + v * 0.13).sin()
                + 35.0 * (v * 0.21 - u * 0.17).sin()
                + 30.0 * (u * 0.07 + v * 0.05).sin()
                + 25.0 * (u * 0.04 - v * 0.08).cos();
            data[y * w + x] = val.round().clamp(0.0, 255.0) as u8;
        }
    }
    GrayImage::new(w, h, data).unwrap()
}

#[test]
fn recovers_a_known_subpixel_shift() {
    let (w, h) = (320, 240);
    let (sx, sy) = (2.37, -1.61);
    let prev = textured(w, h, 0.0, 0.0);
    // next(x, y) = prev(x + sx, y + sy) → features move by (−sx, −sy).
    let next = textured(w, h, sx, sy);
    let mut pts = Vec::new();
    for gy in 0..6 {
        for gx in 0..8 {
            pts.push([40.0 + 32.0 * gx as f32 + 0.25, 40.0 + 30.0 * gy as f32 + 0.5]);
        }
    }
    let out = calc_optical_flow_pyr_lk(&prev, &next, &pts, &LkParams::default());
    let (mut worst, mut sum) = (0f64, 0f64);
    for (i, p) in pts.iter().enumerate() {
        assert!(out.status[i], "point {i} lost");
        let ex = (out.next_pts[i][0] - p[0]) as f64 + sx;
        let ey = (out.next_pts[i][1] - p[1]) as f64 + sy;
        worst = worst.max(ex.abs()).max(ey.abs());
        sum += ex.abs() + ey.abs();
        assert!(out.err[i] < 2.0, "err {}", out.err[i]);
    }
    // Measured: worst 0.0088 px, mean 0.0030 px (8-bit quantization).
    assert!(worst < 0.01, "worst shift error {worst}");
    let mean = sum / (2 * pts.len()) as f64;
    assert!(mean < 0.005, "mean error {mean}");
}

#[test]
fn results_follow_the_callers_order_not_the_visiting_order() {
    // The tracker visits points in bands of rows; each result must land
    // at its own point's index, bit for bit what tracking it alone gives.
    let prev = textured(320, 240, 0.0, 0.0);
    let next = textured(320, 240, 1.3, -0.7);
    let mut pts = Vec::new();
    for k in 0..70u32 {
        // Scattered, bottom-right first, with one point outside the image.
        let x = 300.0 - ((k * 37) % 280) as f32 - 0.25 * (k % 4) as f32;
        let y = 220.0 - ((k * 53) % 200) as f32 - 0.5 * (k % 3) as f32;
        pts.push([x, y]);
    }
    pts[17] = [-30.0, 50.0];
    let together = calc_optical_flow_pyr_lk(&prev, &next, &pts, &LkParams::default());
    assert!(!together.status[17]);
    assert!(together.status.iter().filter(|&&s| s).count() > 60);
    for (i, p) in pts.iter().enumerate() {
        let alone = calc_optical_flow_pyr_lk(&prev, &next, &[*p], &LkParams::default());
        assert_eq!(together.next_pts[i].map(f32::to_bits), alone.next_pts[0].map(f32::to_bits), "point {i}");
        assert_eq!(together.status[i], alone.status[0], "point {i}");
        assert_eq!(together.err[i].to_bits(), alone.err[0].to_bits(), "point {i}");
    }
}

#[test]
fn status_flags_points_outside_the_image() {
    let prev = textured(200, 120, 0.0, 0.0);
    let next = textured(200, 120, 1.0, 0.0);
    let pts = [[100.0, 60.0], [-40.0, 60.0], [100.0, 500.0], [250.0, 10.0]];
    let out = calc_optical_flow_pyr_lk(&prev, &next, &pts, &LkParams::default());
    assert_eq!(out.status, vec![true, false, false, false]);
    // A previous point out of bounds at level 0 gets err 0 explicitly.
    assert_eq!(out.err[1], 0.0);
    // A flat image has no gradient: the eigenvalue test fails.
    let flat = GrayImage::new(200, 120, vec![90; 24000]).unwrap();
    let out = calc_optical_flow_pyr_lk(&flat, &flat, &[[100.0, 60.0]], &LkParams::default());
    assert_eq!(out.status, vec![false]);
}

include!("../testdata/lk_golden.rs");

/// The AVX2 tracker against the portable one on a KITTI-sized pair (the
/// bundled KITTI frames 0 → 1), on a grid of 640 points covering
/// borders, flat sky and texture: same positions, status and err, bit for
/// bit (the kernel-level test covers the replay path on purpose).
#[test]
fn avx2_equals_portable_on_a_kitti_sized_pair() {
    let prev = GrayImage::decode(include_bytes!("../../../../www/demo/MyKITTI/gray/00/image_0/000000.png")).unwrap();
    let next = GrayImage::decode(include_bytes!("../../../../www/demo/MyKITTI/gray/00/image_0/000001.png")).unwrap();
    let mut pts = Vec::new();
    for gy in 0..16 {
        for gx in 0..40 {
            pts.push([-8.0 + 32.0 * gx as f32 + 0.37 * gy as f32, -6.0 + 24.5 * gy as f32 + 0.11 * gx as f32]);
        }
    }
    let fast = calc_optical_flow_pyr_lk(&prev, &next, &pts, &LkParams::default());
    let portable = calc_optical_flow_pyr_lk_portable(&prev, &next, &pts, &LkParams::default());
    let tracked = fast.status.iter().filter(|&&s| s).count();
    assert!(tracked > 400, "only {tracked} of {} tracked", pts.len());
    assert_eq!(fast.status, portable.status);
    for (i, p) in pts.iter().enumerate() {
        let bits = |r: &LkResult| [r.next_pts[i][0].to_bits(), r.next_pts[i][1].to_bits()];
        assert_eq!(bits(&fast), bits(&portable), "point {i} {p:?}");
        if fast.status[i] {
            assert_eq!(fast.err[i].to_bits(), portable.err[i].to_bits(), "err of point {i}");
        }
    }
}

#[test]
fn bit_exact_against_opencv_on_a_synthetic_pair() {
    let prev = GrayImage::decode(include_bytes!("../testdata/lk_prev.png")).unwrap();
    let next = GrayImage::decode(include_bytes!("../testdata/lk_next.png")).unwrap();
    let pts: Vec<[f32; 2]> = LK_GOLDEN.iter().map(|g| g.0).collect();
    let out = calc_optical_flow_pyr_lk(&prev, &next, &pts, &LkParams::default());
    // The portable kernels (CPUs without AVX2, wasm without SIMD) give the same bits.
    assert_eq!(calc_optical_flow_pyr_lk_portable(&prev, &next, &pts, &LkParams::default()), out);
    let mut exact = 0;
    for (i, g) in LK_GOLDEN.iter().enumerate() {
        let got = [out.next_pts[i][0].to_bits(), out.next_pts[i][1].to_bits()];
        assert_eq!(out.status[i] as u8, g.2, "status of point {i}");
        assert_eq!(
            got,
            g.1,
            "point {i} {:?}: got {:?}, OpenCV {:?}",
            g.0,
            out.next_pts[i],
            [f32::from_bits(g.1[0]), f32::from_bits(g.1[1])]
        );
        if g.2 == 1 {
            assert_eq!(out.err[i].to_bits(), g.3, "err of point {i}");
        }
        exact += 1;
    }
    assert_eq!(exact, 68);
}
