//! Judging matches by the true geometry: the fundamental matrix between two
//! frames from their ground-truth poses, and each match's Sampson distance
//! to it. Nothing here must equal OpenCV bit for bit, so it uses `nalgebra`
//! in f64 (docs/architecture.md, `core/`: nalgebra only where no OpenCV bits are at stake).
//!
//! With camera-to-world poses P_prev, P_cur (KITTI's `poses/00.txt`),
//! [R|t] = P_cur⁻¹·P_prev maps the previous camera's coordinates into the
//! current one's, E = [t]ₓR and F = K⁻ᵀ E K⁻¹, so x₂ᵀ F x₁ = 0 for a point
//! seen at x₁ in the previous frame and x₂ in the current one.

use crate::camera::Camera;
use crate::dataset::PoseRow;
use crate::error::{Error, Result};
use crate::matching::DMatch;
use crate::sift::KeyPoint;
use nalgebra::{Matrix3, Matrix4, Vector3};

/// The default correctness threshold: a match is correct when its Sampson
/// distance is at most this many pixels.
pub const DEFAULT_EPIPOLAR_PX: f64 = 2.0;

/// A KITTI pose row as a 4×4 homogeneous camera-to-world matrix.
fn pose_matrix(p: &PoseRow) -> Matrix4<f64> {
    Matrix4::new(p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7], p[8], p[9], p[10], p[11], 0.0, 0.0, 0.0, 1.0)
}

/// The intrinsic matrix K.
fn intrinsics(cam: &Camera) -> Matrix3<f64> {
    Matrix3::new(cam.fx, 0.0, cam.cx, 0.0, cam.fy, cam.cy, 0.0, 0.0, 1.0)
}

/// The fundamental matrix from the previous frame to the current one.
/// Errors when a pose is not invertible or the camera is unusable, or when
/// the frames were taken from the same place (t = 0: no epipolar geometry).
pub fn fundamental(prev: &PoseRow, cur: &PoseRow, cam: &Camera) -> Result<Matrix3<f64>> {
    cam.validate()?;
    let cur_inv = pose_matrix(cur).try_inverse().ok_or_else(|| {
        Error::InvalidArgument("the current frame's pose is not invertible: check poses/00.txt".into())
    })?;
    let rel = cur_inv * pose_matrix(prev);
    let r = rel.fixed_view::<3, 3>(0, 0).into_owned();
    let t = Vector3::new(rel[(0, 3)], rel[(1, 3)], rel[(2, 3)]);
    if t.norm() == 0.0 {
        return Err(Error::InvalidArgument(
            "the two frames' poses are at the same place: without a baseline there is no epipolar geometry to judge matches by".into(),
        ));
    }
    let k_inv = intrinsics(cam).try_inverse().ok_or_else(|| Error::InvalidArgument("singular intrinsics".into()))?;
    let e = t.cross_matrix() * r;
    Ok(k_inv.transpose() * e * k_inv)
}

/// The Sampson distance of x₂ (current frame) and x₁ (previous frame) to F:
/// |x₂ᵀFx₁| / √((Fx₁)₁² + (Fx₁)₂² + (Fᵀx₂)₁² + (Fᵀx₂)₂²), in pixels.
pub fn sampson(f: &Matrix3<f64>, x1: [f32; 2], x2: [f32; 2]) -> f64 {
    let (a, b) = (homogeneous(x1), homogeneous(x2));
    sampson_of(&(f * a), &(f.transpose() * b), &b)
}

/// A pixel as a homogeneous point.
pub fn homogeneous(x: [f32; 2]) -> Vector3<f64> {
    Vector3::new(x[0] as f64, x[1] as f64, 1.0)
}

/// The Sampson distance from its parts Fx₁, Fᵀx₂ and x₂: the sweep computes
/// Fx₁ once per query and Fᵀx₂ once per train keypoint instead of once per
/// pair, with the same operations, so the same bits as [`sampson`].
#[inline]
pub fn sampson_of(fa: &Vector3<f64>, ftb: &Vector3<f64>, b: &Vector3<f64>) -> f64 {
    let num = b.dot(fa).abs();
    let den = (fa[0] * fa[0] + fa[1] * fa[1] + ftb[0] * ftb[0] + ftb[1] * ftb[1]).sqrt();
    num / den
}

/// The epipolar line of x₁ (a pixel of the previous frame) in the current
/// frame: l = F·x₁ as [a, b, c], the points with a·x + b·y + c = 0. Where x₁
/// is seen again must lie on it; the Sampson distance measures how far off
/// a match is from this line (and from x₁'s counterpart on Fᵀx₂) together.
pub fn epipolar_line(f: &Matrix3<f64>, x1: [f32; 2]) -> [f64; 3] {
    let l = f * homogeneous(x1);
    [l[0], l[1], l[2]]
}

/// The Sampson distance of each match (query in `prev`, train in `cur`), in
/// the order of `matches`: [`sampson`] of its two keypoints, the same bits.
/// Panics when a match names a keypoint the frames do not have.
pub fn sampsons(f: &Matrix3<f64>, prev: &[KeyPoint], cur: &[KeyPoint], matches: &[DMatch]) -> Vec<f64> {
    matches
        .iter()
        .map(|m| {
            let (a, b) = (&prev[m.query_idx], &cur[m.train_idx]);
            sampson(f, [a.x, a.y], [b.x, b.y])
        })
        .collect()
}

/// Whether each match (query in `prev`, train in `cur`) lies within `px`
/// pixels of its epipolar geometry: [`sampsons`] ≤ `px`.
pub fn judge(f: &Matrix3<f64>, prev: &[KeyPoint], cur: &[KeyPoint], matches: &[DMatch], px: f64) -> Vec<bool> {
    sampsons(f, prev, cur, matches).into_iter().map(|s| s <= px).collect()
}

/// Counts of a whole-frame match set.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Verdicts {
    pub matches: usize,
    /// `None` without ground truth.
    pub correct: Option<usize>,
}

impl Verdicts {
    /// correct / matches; `None` for no matches or no ground truth.
    pub fn precision(&self) -> Option<f64> {
        let c = self.correct?;
        (self.matches > 0).then(|| c as f64 / self.matches as f64)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A row-major pose [R|t] from a yaw angle and a position.
    fn pose(yaw: f64, pos: [f64; 3]) -> PoseRow {
        let (s, c) = yaw.sin_cos();
        [c, 0.0, s, pos[0], 0.0, 1.0, 0.0, pos[1], -s, 0.0, c, pos[2]]
    }

    /// Projects a world point into a camera with camera-to-world pose `p`.
    fn project(p: &PoseRow, cam: &Camera, x: [f64; 3]) -> [f32; 2] {
        let w = pose_matrix(p).try_inverse().unwrap() * nalgebra::Vector4::new(x[0], x[1], x[2], 1.0);
        [(cam.fx * w[0] / w[2] + cam.cx) as f32, (cam.fy * w[1] / w[2] + cam.cy) as f32]
    }

    /// A synthetic pair with known geometry: 40 world points seen by two
    /// cameras (forward motion and a turn). True correspondences are 40
    /// correct matches; 10 matches to a point shifted 20 px across the
    /// epipolar line are wrong, so the precision is exactly 40/50 = 0.8.
    #[test]
    fn synthetic_pair_gives_the_exact_precision() {
        let cam = Camera::default();
        let (p0, p1) = (pose(0.0, [0.0, 0.0, 0.0]), pose(0.05, [0.2, 0.0, 1.0]));
        let f = fundamental(&p0, &p1, &cam).unwrap();
        let kp = |p: [f32; 2]| KeyPoint { x: p[0], y: p[1], size: 2.0, angle: 0.0, response: 0.0, octave: 0 };
        let world: Vec<[f64; 3]> =
            (0..40).map(|i| [(i % 8) as f64 * 2.0 - 7.0, (i / 8) as f64 - 2.0, 12.0 + (i % 5) as f64 * 3.0]).collect();
        let prev: Vec<KeyPoint> = world.iter().map(|w| kp(project(&p0, &cam, *w))).collect();
        let mut cur: Vec<KeyPoint> = world.iter().map(|w| kp(project(&p1, &cam, *w))).collect();
        for q in 0..40 {
            assert!(sampson(&f, [prev[q].x, prev[q].y], [cur[q].x, cur[q].y]) < 1e-3, "true match {q}");
        }
        // Wrong partners: the true point moved 20 px perpendicular to its
        // epipolar line, so its Sampson distance is ~20 / √2·(scale) > 2 px.
        for q in 0..10 {
            let x1 = Vector3::new(prev[q].x as f64, prev[q].y as f64, 1.0);
            let l = f * x1;
            let n = (l[0] * l[0] + l[1] * l[1]).sqrt();
            let moved = [cur[q].x + (20.0 * l[0] / n) as f32, cur[q].y + (20.0 * l[1] / n) as f32];
            cur.push(kp(moved));
        }
        let mut matches: Vec<DMatch> = (0..40).map(|q| DMatch { query_idx: q, train_idx: q, distance: 0.0 }).collect();
        matches.extend((0..10).map(|q| DMatch { query_idx: q, train_idx: 40 + q, distance: 0.0 }));
        let ok = judge(&f, &prev, &cur, &matches, DEFAULT_EPIPOLAR_PX);
        let v = Verdicts { matches: ok.len(), correct: Some(ok.iter().filter(|&&b| b).count()) };
        assert_eq!(v.precision(), Some(0.8));
        // The shifted points sit well beyond 2 px, as built.
        for q in 0..10 {
            let d = sampson(&f, [prev[q].x, prev[q].y], [cur[40 + q].x, cur[40 + q].y]);
            assert!(d > 5.0 && d < 20.0, "{d}");
        }
    }

    /// A pure sideways move (x to the right, no turn): F = K⁻ᵀ[t]ₓK⁻¹ makes
    /// every epipolar line the image row of x₁, so l = (0, b, −b·y₁) up to
    /// scale, and a point on it has Sampson distance 0 while one d rows
    /// away has |d|/√2 (the two gradient terms are equal).
    #[test]
    fn epipolar_lines_and_sampsons_of_a_sideways_move() {
        let cam = Camera::default();
        let f = fundamental(&pose(0.0, [0.0, 0.0, 0.0]), &pose(0.0, [0.5, 0.0, 0.0]), &cam).unwrap();
        let x1 = [300.0f32, 120.0];
        let [a, b, c] = epipolar_line(&f, x1);
        assert!(a.abs() < 1e-12 * b.abs(), "{a} {b}");
        assert!((c / b + 120.0).abs() < 1e-9, "the line is y = 120: {}", -c / b);
        // The line is F·x₁: a point on it satisfies x₂ᵀ F x₁ = 0.
        let on = [700.0f32, 120.0];
        assert!((a * 700.0 + b * 120.0 + c).abs() < 1e-12);
        let kp = |p: [f32; 2]| KeyPoint { x: p[0], y: p[1], size: 2.0, angle: 0.0, response: 0.0, octave: 0 };
        let (prev, cur) = (vec![kp(x1)], vec![kp(on), kp([700.0, 124.0]), kp([10.0, 117.0])]);
        let m = |t| DMatch { query_idx: 0, train_idx: t, distance: 0.0 };
        let s = sampsons(&f, &prev, &cur, &[m(0), m(1), m(2)]);
        assert!(s[0] < 1e-9, "{}", s[0]);
        assert!((s[1] - 4.0 / 2f64.sqrt()).abs() < 1e-9, "{}", s[1]);
        assert!((s[2] - 3.0 / 2f64.sqrt()).abs() < 1e-9, "{}", s[2]);
        // The same bits as one at a time, and judge is sampsons ≤ px.
        for (i, t) in [on, [700.0, 124.0], [10.0, 117.0]].into_iter().enumerate() {
            assert_eq!(s[i].to_bits(), sampson(&f, x1, t).to_bits());
        }
        assert_eq!(judge(&f, &prev, &cur, &[m(0), m(1), m(2)], 2.2), vec![true, false, true]);
        assert!(sampsons(&f, &prev, &cur, &[]).is_empty());
    }

    #[test]
    fn no_baseline_and_no_matches_are_explained() {
        let p = pose(0.0, [1.0, 2.0, 3.0]);
        let e = fundamental(&p, &p, &Camera::default()).unwrap_err().to_string();
        assert!(e.contains("same place"), "{e}");
        assert_eq!(Verdicts { matches: 0, correct: Some(0) }.precision(), None);
        assert_eq!(Verdicts { matches: 3, correct: None }.precision(), None);
    }
}
