//! The synthetic two-view scenes the VO stages' tests share. `scene`
//! mirrors `lcg_scene` of testdata/gen_goldens.py, so the goldens written
//! there by OpenCV are for exactly these points.

use super::linalg::{mat_mul, skew, Mat3};
use crate::camera::Camera;

/// Rotation from a rotation vector (Rodrigues).
pub fn rodrigues(w: [f64; 3]) -> Mat3 {
    let th = (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]).sqrt();
    let k = [w[0] / th, w[1] / th, w[2] / th];
    let kx = skew(k);
    let kx2 = mat_mul(&kx, &kx);
    std::array::from_fn(|r| {
        std::array::from_fn(|c| (if r == c { 1.0 } else { 0.0 }) + th.sin() * kx[r][c] + (1.0 - th.cos()) * kx2[r][c])
    })
}

/// A synthetic scene: points X1 in camera 1 (depths 5–25, drawn from the
/// 64-bit LCG of `lcg_scene`), X2 = R·X1 + t, normalized image coordinates
/// of both.
pub fn scene(r: &Mat3, t: [f64; 3], n: usize, seed: u64) -> (Vec<[f64; 2]>, Vec<[f64; 2]>) {
    let mut s = seed;
    let mut rnd = || {
        s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((s >> 11) as f64) / ((1u64 << 53) as f64)
    };
    let (mut a, mut b) = (Vec::new(), Vec::new());
    for _ in 0..n {
        let x1 = [rnd() * 8.0 - 4.0, rnd() * 4.0 - 2.0, 5.0 + rnd() * 20.0];
        let x2: [f64; 3] = std::array::from_fn(|i| r[i][0] * x1[0] + r[i][1] * x1[1] + r[i][2] * x1[2] + t[i]);
        a.push([x1[0] / x1[2], x1[1] / x1[2]]);
        b.push([x2[0] / x2[2], x2[1] / x2[2]]);
    }
    (a, b)
}

/// E = [t]x R up to scale and sign: the smallest of ‖E/‖E‖ ∓ E_true/‖E_true‖‖.
pub fn distance_up_to_scale(e: &Mat3, r: &Mat3, t: [f64; 3]) -> f64 {
    let et = mat_mul(&skew(t), r);
    let n: f64 = et.iter().flatten().map(|v| v * v).sum::<f64>().sqrt();
    let ne: f64 = e.iter().flatten().map(|v| v * v).sum::<f64>().sqrt();
    let (mut dp, mut dm) = (0.0f64, 0.0f64);
    for i in 0..3 {
        for j in 0..3 {
            dp = dp.max((e[i][j] / ne - et[i][j] / n).abs());
            dm = dm.max((e[i][j] / ne + et[i][j] / n).abs());
        }
    }
    dp.min(dm)
}

/// Mirrors `lcg_scene` of testdata/gen_goldens.py operation by operation,
/// so both sides hold the same f32 pixels.
pub fn pixel_scene(r: &Mat3, t: [f64; 3], n: usize, seed: u64) -> (Vec<[f32; 2]>, Vec<[f32; 2]>) {
    // The normalized scene, then x·f + c in the same operation order.
    let cam = Camera::default();
    let (a, b) = scene(r, t, n, seed);
    let px = |p: &[f64; 2]| [(p[0] * cam.fx + cam.cx) as f32, (p[1] * cam.fy + cam.cy) as f32];
    (a.iter().map(px).collect(), b.iter().map(px).collect())
}

/// cv2.Rodrigues([0.005, -0.0316, 0.005]) and the translation of the golden scene.
pub const SCENE_R: Mat3 = [
    [0.9994882647177734, -0.005078119343031715, -0.03158197896573382],
    [0.004920133148589171, 0.9999750021844237, -0.005078119343031715],
    [0.03160697678131018, 0.004920133148589171, 0.9994882647177734],
];
pub const SCENE_T: [f64; 3] = [0.05, -0.02, -1.0];

/// 300 correspondences; every 5th point of the first set moved by
/// (15 + i mod 25, −20) px: 60 outliers.
pub fn golden_points() -> (Vec<[f32; 2]>, Vec<[f32; 2]>) {
    let (mut p1, p2) = pixel_scene(&SCENE_R, SCENE_T, 300, 99);
    for i in (0..300).step_by(5) {
        p1[i][0] += 15.0 + (i % 25) as f32;
        p1[i][1] -= 20.0;
    }
    (p1, p2)
}
