//! `cv2.findEssentialMat(points1, points2, focal, pp, cv2.RANSAC, 0.999, 1.0)`
//! in OpenCV 4.8 (docs/fidelity.md §VO-3.1 to §VO-3.3): the old
//! `RANSACPointSetRegistrator` with `cv::RNG` seeded to 2^64−1 on every call,
//! 5-distinct-index sampling by rejection, Sampson error rounded to f32,
//! strict-greater model replacement and `RANSACUpdateNumIters`. No refinement:
//! the result is the best minimal-sample model.

use super::five_point::five_point;
use super::linalg::{CvRng, Mat3};
use crate::camera::Camera;
use crate::{Error, Result};

/// RANSAC settings of the lab's call.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RansacParams {
    pub prob: f64,
    /// Inlier threshold in pixels.
    pub threshold: f64,
    pub max_iters: usize,
}

impl Default for RansacParams {
    fn default() -> Self {
        RansacParams { prob: 0.999, threshold: 1.0, max_iters: 1000 }
    }
}

/// What findEssentialMat returns.
#[derive(Clone, Debug, PartialEq)]
pub struct EssentialResult {
    /// The model(s): exactly one after RANSAC; with exactly 5 points OpenCV
    /// returns every five-point solution (stacked (3k)×3), in solver order.
    pub models: Vec<Mat3>,
    /// Inlier mask of the chosen model (all true with 5 points).
    pub mask: Vec<bool>,
    pub inliers: usize,
    /// RANSAC iterations run (samples drawn).
    pub iterations: usize,
}

impl EssentialResult {
    /// The single E the lab passes on to recoverPose.
    pub fn essential(&self) -> Result<&Mat3> {
        match self.models.as_slice() {
            [e] => Ok(e),
            _ => Err(Error::Odometry(format!(
                "findEssentialMat returned {} candidate matrices (only 5 tracked points); \
                 recoverPose needs exactly one",
                self.models.len()
            ))),
        }
    }
}

/// `RANSACUpdateNumIters(p, ep, modelPoints, maxIters)`; `pow`/`log` are the
/// C library's (glibc natively), as in the wheel.
pub fn update_num_iters(p: f64, ep: f64, model_points: i32, max_iters: usize) -> usize {
    let p = p.clamp(0.0, 1.0);
    let ep = ep.clamp(0.0, 1.0);
    let num = (1.0 - p).max(f64::MIN_POSITIVE);
    let denom = 1.0 - (1.0 - ep).powf(model_points as f64);
    if denom < f64::MIN_POSITIVE {
        return 0;
    }
    let num = num.ln();
    let denom = denom.ln();
    if denom >= 0.0 || -num >= max_iters as f64 * (-denom) {
        max_iters
    } else {
        (num / denom).round_ties_even() as usize
    }
}

/// The correspondences as four coordinate columns, so that the Sampson
/// error of a model runs over them in vectors: every lane does OpenCV's
/// scalar operations in its order (Rust never fuses a multiply and an add).
struct Columns {
    x1: Vec<f64>,
    y1: Vec<f64>,
    x2: Vec<f64>,
    y2: Vec<f64>,
}

impl Columns {
    fn new(p1: &[[f64; 2]], p2: &[[f64; 2]]) -> Self {
        Columns {
            x1: p1.iter().map(|p| p[0]).collect(),
            y1: p1.iter().map(|p| p[1]).collect(),
            x2: p2.iter().map(|p| p[0]).collect(),
            y2: p2.iter().map(|p| p[1]).collect(),
        }
    }
}

/// Squared Sampson distance of every correspondence, f64 rounded to f32
/// (`EMEstimatorCallback::computeError`, baseline code: no FMA), into `err`;
/// returns how many are at most `t` (`findInliers`).
fn sampson_errors(e: &Mat3, pts: &Columns, t: f32, err: &mut Vec<f32>) -> usize {
    #[inline(always)]
    fn body(e: &Mat3, pts: &Columns, t: f32, err: &mut [f32]) -> usize {
        let n = err.len();
        let (x1, y1, x2, y2) = (&pts.x1[..n], &pts.y1[..n], &pts.x2[..n], &pts.y2[..n]);
        let mut good = 0;
        for i in 0..n {
            let ex1: [f64; 3] = std::array::from_fn(|r| (e[r][0] * x1[i] + e[r][1] * y1[i]) + e[r][2]);
            let etx2: [f64; 3] = std::array::from_fn(|c| (e[0][c] * x2[i] + e[1][c] * y2[i]) + e[2][c]);
            let r = (x2[i] * ex1[0] + y2[i] * ex1[1]) + ex1[2];
            let den = ((ex1[0] * ex1[0] + ex1[1] * ex1[1]) + etx2[0] * etx2[0]) + etx2[1] * etx2[1];
            let v = (r * r / den) as f32;
            err[i] = v;
            good += (v <= t) as usize;
        }
        good
    }
    err.clear();
    err.resize(pts.x1.len(), 0.0);
    #[cfg(target_arch = "x86_64")]
    {
        // The same loop compiled for wider vectors: each lane still does
        // OpenCV's unfused scalar operations, so only the speed changes.
        #[target_feature(enable = "avx512f")]
        fn avx512(e: &Mat3, pts: &Columns, t: f32, err: &mut [f32]) -> usize {
            body(e, pts, t, err)
        }
        #[target_feature(enable = "avx2")]
        fn avx2(e: &Mat3, pts: &Columns, t: f32, err: &mut [f32]) -> usize {
            body(e, pts, t, err)
        }
        if crate::simd::avx512f() {
            // SAFETY: the CPU has AVX-512 F, the one feature the function enables.
            return unsafe { avx512(e, pts, t, err) };
        }
        if crate::simd::avx2() {
            // SAFETY: the CPU has AVX2, the one feature the function enables.
            return unsafe { avx2(e, pts, t, err) };
        }
    }
    body(e, pts, t, err)
}

/// findEssentialMat on already normalized coordinates; `thr` is the
/// threshold divided by the mean focal length.
pub fn ransac_normalized(
    p1: &[[f64; 2]],
    p2: &[[f64; 2]],
    thr: f64,
    prob: f64,
    max_iters: usize,
) -> Result<EssentialResult> {
    let n = p1.len();
    if n != p2.len() {
        return Err(Error::InvalidArgument(format!(
            "findEssentialMat needs as many points in both sets ({} vs {})",
            n,
            p2.len()
        )));
    }
    if n < 5 {
        return Err(Error::Odometry(format!("only {n} tracked points: the essential matrix needs at least 5")));
    }
    let sample = |idx: &[usize; 5]| {
        let a: [[f64; 2]; 5] = std::array::from_fn(|i| p1[idx[i]]);
        let b: [[f64; 2]; 5] = std::array::from_fn(|i| p2[idx[i]]);
        five_point(&a, &b)
    };
    if n == 5 {
        let models = sample(&[0, 1, 2, 3, 4]);
        return Ok(EssentialResult { models, mask: vec![true; 5], inliers: 5, iterations: 1 });
    }
    let t = (thr * thr) as f32;
    let pts = Columns::new(p1, p2);
    let mut rng = CvRng::new(u64::MAX);
    let mut niters = max_iters;
    let mut max_good = 0usize;
    let mut best: Option<Mat3> = None;
    let mut best_mask = vec![false; n];
    let mut err = Vec::with_capacity(n);
    let mut iter = 0;
    while iter < niters {
        let mut idx = [0usize; 5];
        for i in 0..5 {
            loop {
                let v = rng.uniform(n as u32) as usize;
                if !idx[..i].contains(&v) {
                    idx[i] = v;
                    break;
                }
            }
        }
        for model in sample(&idx) {
            let good = sampson_errors(&model, &pts, t, &mut err);
            // Strictly more than the best so far and than modelPoints − 1.
            if good > max_good.max(4) {
                best = Some(model);
                for (m, &e) in best_mask.iter_mut().zip(&err) {
                    *m = e <= t;
                }
                max_good = good;
                niters = update_num_iters(prob, (n - good) as f64 / n as f64, 5, niters);
            }
        }
        iter += 1;
    }
    match best {
        Some(e) => Ok(EssentialResult { models: vec![e], mask: best_mask, inliers: max_good, iterations: iter }),
        None => Err(Error::Odometry(format!(
            "findEssentialMat found no model with at least 5 inliers among {n} points \
             (the frames may be identical or the tracking failed)"
        ))),
    }
}

/// `cv2.findEssentialMat(points1, points2, focal, pp, cv2.RANSAC, prob, threshold)`
/// with E satisfying `p2ᵀ·E·p1 = 0` for normalized points.
pub fn find_essential_mat(
    points1: &[[f32; 2]],
    points2: &[[f32; 2]],
    cam: &Camera,
    params: &RansacParams,
) -> Result<EssentialResult> {
    cam.validate()?;
    let p1: Vec<[f64; 2]> = points1.iter().map(|&p| cam.normalize(p)).collect();
    let p2: Vec<[f64; 2]> = points2.iter().map(|&p| cam.normalize(p)).collect();
    let thr = params.threshold / ((cam.fx + cam.fy) / 2.0);
    ransac_normalized(&p1, &p2, thr, params.prob, params.max_iters)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vo::testing::{distance_up_to_scale, golden_points, SCENE_R, SCENE_T};

    #[test]
    fn update_num_iters_matches_opencv_formula() {
        // log(0.001)/log(1 − 0.8^5) = 17.399 → 17; 0.5 outliers: 217.576 → 218.
        assert_eq!(update_num_iters(0.999, 0.2, 5, 1000), 17);
        assert_eq!(update_num_iters(0.999, 0.5, 5, 1000), 218);
        // Never above the current count; all inliers ends the loop.
        assert_eq!(update_num_iters(0.999, 0.5, 5, 100), 100);
        assert_eq!(update_num_iters(0.999, 0.0, 5, 1000), 0);
    }

    // cv2.findEssentialMat(p1, p2, focal=718.856, pp=(607.1928, 185.2157),
    // method=cv2.RANSAC, prob=0.999, threshold=1.0), 4.8.0.76 wheel.
    const OPENCV_E: [f64; 9] = [
        -0.003027709589195589,
        -0.7059965588327499,
        0.017700551497470813,
        0.7068382201135524,
        -0.0034119210600523824,
        0.01298659647089793,
        -0.014288717556143925,
        -0.03523154313259714,
        0.0006252841179491471,
    ];
    const OPENCV_INLIERS: usize = 241;
    const OPENCV_OUTLIERS: &[usize] = &[
        0, 5, 10, 15, 20, 25, 30, 35, 40, 45, 50, 55, 60, 65, 70, 75, 80, 85, 90, 95, 100, 105, 110, 115, 120, 125,
        130, 135, 140, 145, 150, 155, 160, 170, 175, 180, 185, 190, 195, 200, 205, 210, 215, 220, 225, 230, 235, 240,
        245, 250, 255, 260, 265, 270, 275, 280, 285, 290, 295,
    ];

    #[test]
    fn matches_opencv_on_a_scene_with_outliers() {
        let (p1, p2) = golden_points();
        let res = find_essential_mat(&p1, &p2, &Camera::default(), &RansacParams::default()).unwrap();
        let e = res.essential().unwrap();
        // Same winning sample as OpenCV: same mask, E equal to rounding.
        assert_eq!(res.inliers, OPENCV_INLIERS);
        let outliers: Vec<usize> = (0..300).filter(|&i| !res.mask[i]).collect();
        assert_eq!(outliers, OPENCV_OUTLIERS);
        for k in 0..9 {
            let d = (e[k / 3][k % 3] - OPENCV_E[k]).abs();
            assert!(d < 1e-10, "E[{k}] {} vs OpenCV {}", e[k / 3][k % 3], OPENCV_E[k]);
        }
        // The true motion: outlier 165 happens to lie on its epipolar line.
        let d = distance_up_to_scale(e, &SCENE_R, SCENE_T);
        assert!(d < 1e-4, "E off the true motion by {d}");
        assert!(res.iterations < 60, "{} iterations", res.iterations);
        // Deterministic: the RNG is reseeded on every call.
        let again = find_essential_mat(&p1, &p2, &Camera::default(), &RansacParams::default()).unwrap();
        assert_eq!(again, res);
    }

    #[test]
    fn too_few_points_is_an_error() {
        let p = [[1.0f32, 2.0]; 4];
        let err = find_essential_mat(&p, &p, &Camera::default(), &RansacParams::default()).unwrap_err();
        assert!(err.to_string().contains("only 4 tracked points"), "{err}");
    }
}
