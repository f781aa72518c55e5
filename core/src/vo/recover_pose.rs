//! `cv2.recoverPose(E, points1, points2, focal=..., pp=...)` in OpenCV 4.8
//! (docs/fidelity.md §VO-4): decomposeEssentialMat by the Jacobi SVD, the four
//! candidates in OpenCV's order, DLT triangulation and the cheirality /
//! distance (50) votes of every point (the lab passes no mask).

#[cfg(test)]
use super::linalg::null_vector_4x4;
use super::linalg::{det3, mat_mul, null_vectors_4x4, svd, Mat3, Vec3};
use crate::camera::Camera;
use crate::{Error, Result};

/// recoverPose's default `distanceThresh`.
pub const DISTANCE_THRESH: f64 = 50.0;

/// recoverPose's answer: `X2 = R·X1 + t` maps points of the points1 camera
/// into the points2 camera; `t` has unit norm.
#[derive(Clone, Debug, PartialEq)]
pub struct Pose {
    pub r: Mat3,
    pub t: Vec3,
    /// Points in front of both cameras (closer than 50) for the chosen pose.
    pub inliers: usize,
    pub mask: Vec<bool>,
    /// Votes of the four candidates [R1|t], [R2|t], [R1|−t], [R2|−t].
    pub votes: [usize; 4],
}

/// `decomposeEssentialMat`: (R1, R2, t).
pub fn decompose_essential(e: &Mat3) -> (Mat3, Mat3, Vec3) {
    let flat: Vec<f64> = e.iter().flatten().copied().collect();
    let s = svd(&flat, 3, 3, false);
    let mut u: Mat3 = std::array::from_fn(|r| std::array::from_fn(|c| s.u[r * 3 + c]));
    let mut vt: Mat3 = std::array::from_fn(|r| std::array::from_fn(|c| s.vt[r * 3 + c]));
    if det3(&u) < 0.0 {
        u = u.map(|row| row.map(|v| -v));
    }
    if det3(&vt) < 0.0 {
        vt = vt.map(|row| row.map(|v| -v));
    }
    let w: Mat3 = [[0.0, 1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 1.0]];
    let wt: Mat3 = [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]];
    let r1 = mat_mul(&mat_mul(&u, &w), &vt);
    let r2 = mat_mul(&mat_mul(&u, &wt), &vt);
    (r1, r2, [u[0][2], u[1][2], u[2][2]])
}

/// Whether the point triangulated with `P0 = [I|0]` and `P = [R|t]`, and the
/// one triangulated with `[R|−t]`, lie in front of both cameras and closer
/// than `dist` (the tests of §VO-4 step 4).
///
/// One SVD serves both: the DLT matrix of `[R|−t]` is that of `[R|t]` with
/// its last column negated, and every step of the Jacobi SVD commutes
/// exactly with negating a working vector (products, sums, `hypot` and
/// `sqrt` see the same magnitudes; each rotation only moves the sign between
/// the two vectors it mixes). So OpenCV's separate SVD gives exactly
/// `±(X0, X1, X2, −X3)`, and its tests, which do not depend on the sign of X,
/// come out as the negated quantities below: the same votes, bit for bit.
/// (`recover_pose_normalized` does the same, four SVDs at a time.)
#[cfg(test)]
fn votes_for(r: &Mat3, t: &Vec3, a: [f64; 2], b: [f64; 2], dist: f64) -> (bool, bool) {
    let (m, p) = dlt(r, t, a, b);
    votes_from(null_vector_4x4(&m), &p, dist)
}

/// The triangulation matrix of `a` ↔ `b` for `P0 = [I|0]` and `P = [R|t]`,
/// and `P`.
#[inline]
fn dlt(r: &Mat3, t: &Vec3, a: [f64; 2], b: [f64; 2]) -> ([[f64; 4]; 4], [[f64; 4]; 3]) {
    let (x1, y1, x2, y2) = (a[0], a[1], b[0], b[1]);
    let p: [[f64; 4]; 3] = std::array::from_fn(|i| [r[i][0], r[i][1], r[i][2], t[i]]);
    let m = [
        [-1.0, 0.0, x1, 0.0],
        [0.0, -1.0, y1, 0.0],
        std::array::from_fn(|k| x2 * p[2][k] - p[0][k]),
        std::array::from_fn(|k| y2 * p[2][k] - p[1][k]),
    ];
    (m, p)
}

/// The votes of [`votes_for`] from the null vector `x` of the DLT matrix.
#[inline]
fn votes_from(x: [f64; 4], p: &[[f64; 4]; 3], dist: f64) -> (bool, bool) {
    // OpenCV's `mask = X2·X3 > 0` then `Q /= Q.row(3)`: an X3 of 0 or NaN
    // fails this first test, so afterwards the fourth coordinate is exactly 1.
    // With −t: X2·(−X3), Q0..2 negated, and Z' = −(R·Q + t)_z exactly.
    let sign = x[2] * x[3];
    if sign.is_nan() || sign == 0.0 {
        return (false, false);
    }
    let q = [x[0] / x[3], x[1] / x[3], x[2] / x[3], 1.0];
    let z2 = p[2][0] * q[0] + p[2][1] * q[1] + p[2][2] * q[2] + p[2][3] * q[3];
    // `Z < dist` is false for NaN, as OpenCV's comparisons.
    let ok = |s: f64, z: f64, z2: f64| s > 0.0 && z < dist && z2 > 0.0 && z2 < dist;
    (ok(sign, q[2], z2), ok(-sign, -q[2], -z2))
}

/// recoverPose on normalized coordinates.
pub fn recover_pose_normalized(e: &Mat3, p1: &[[f64; 2]], p2: &[[f64; 2]], dist: f64) -> Result<Pose> {
    if p1.len() != p2.len() || p1.is_empty() {
        return Err(Error::Odometry(format!(
            "recoverPose needs the same non-zero number of points in both sets ({} vs {})",
            p1.len(),
            p2.len()
        )));
    }
    if e.iter().flatten().any(|v| !v.is_finite()) {
        return Err(Error::Odometry("recoverPose got a non-finite essential matrix".into()));
    }
    let (r1, r2, t) = decompose_essential(e);
    let nt = [-t[0], -t[1], -t[2]];
    let cands: [(&Mat3, &Vec3); 4] = [(&r1, &t), (&r2, &t), (&r1, &nt), (&r2, &nt)];
    let mut masks: [Vec<bool>; 4] = std::array::from_fn(|_| Vec::with_capacity(p1.len()));
    // Two points under both rotations are the four SVDs one call solves at
    // once; an odd last point fills the other two lanes with itself.
    type Lane = ([[f64; 4]; 4], [[f64; 4]; 3]);
    for i in (0..p1.len()).step_by(2) {
        let pair = [i, (i + 1).min(p1.len() - 1)];
        let lanes: [Lane; 4] = std::array::from_fn(|l| dlt(cands[l % 2].0, &t, p1[pair[l / 2]], p2[pair[l / 2]]));
        let xs = null_vectors_4x4(&lanes.map(|(m, _)| m));
        for l in 0..if pair[0] == pair[1] { 2 } else { 4 } {
            let (plus, minus) = votes_from(xs[l], &lanes[l].1, dist);
            masks[l % 2].push(plus);
            masks[l % 2 + 2].push(minus);
        }
    }
    let votes: [usize; 4] = std::array::from_fn(|k| masks[k].iter().filter(|&&m| m).count());
    // The first candidate whose count is ≥ all others.
    let best = (0..4).find(|&k| (0..4).all(|j| votes[k] >= votes[j])).unwrap_or(0);
    let (r, t) = cands[best];
    Ok(Pose { r: *r, t: *t, inliers: votes[best], mask: masks[best].clone(), votes })
}

/// `cv2.recoverPose(E, points1, points2, focal=f, pp=(cx, cy))` without a mask.
pub fn recover_pose(e: &Mat3, points1: &[[f32; 2]], points2: &[[f32; 2]], cam: &Camera) -> Result<Pose> {
    cam.validate()?;
    let p1: Vec<[f64; 2]> = points1.iter().map(|&p| cam.normalize(p)).collect();
    let p2: Vec<[f64; 2]> = points2.iter().map(|&p| cam.normalize(p)).collect();
    recover_pose_normalized(e, &p1, &p2, DISTANCE_THRESH)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vo::linalg::skew;
    use crate::vo::ransac::{find_essential_mat, RansacParams};
    use crate::vo::testing::{golden_points, rodrigues, scene, SCENE_R, SCENE_T};

    #[test]
    fn recovers_r_and_t_from_the_true_essential_matrix() {
        let r = rodrigues([0.02, -0.04, 0.01]);
        let t: [f64; 3] = [0.1, -0.05, -0.99];
        let tn = (t[0] * t[0] + t[1] * t[1] + t[2] * t[2]).sqrt();
        let (a, b) = scene(&r, t, 200, 5);
        // Both signs of E must give the same pose.
        for sign in [1.0, -1.0] {
            let e = mat_mul(&skew(t), &r).map(|row| row.map(|v| v * sign / tn));
            let pose = recover_pose_normalized(&e, &a, &b, DISTANCE_THRESH).unwrap();
            assert!(close(pose.t, t.map(|v| v / tn), 1e-12), "t {:?}", pose.t);
            assert!(close(pose.r.concat(), r.concat(), 1e-12), "R {:?}", pose.r);
            // Depths are 5–25 (< 50) in camera 1 and the motion is short:
            // every point votes for the right candidate, none for the others.
            assert_eq!(pose.inliers, 200);
            assert_eq!(pose.votes.iter().filter(|&&v| v == 200).count(), 1);
        }
    }

    /// Whether every value is within `tol` of its counterpart (NaN is not).
    fn close(a: impl IntoIterator<Item = f64>, b: impl IntoIterator<Item = f64>, tol: f64) -> bool {
        a.into_iter().zip(b).all(|(x, y)| (x - y).abs() < tol)
    }

    /// The old way, as OpenCV does it: one SVD per candidate.
    fn votes_separately(r: &Mat3, t: &Vec3, a: [f64; 2], b: [f64; 2], dist: f64) -> bool {
        let (m, p) = dlt(r, t, a, b);
        let x = null_vector_4x4(&m);
        // `X2·X3 > 0`, false for NaN.
        let sign = x[2] * x[3];
        if sign.is_nan() || sign <= 0.0 {
            return false;
        }
        let q = [x[0] / x[3], x[1] / x[3], x[2] / x[3], 1.0];
        let z2 = p[2][0] * q[0] + p[2][1] * q[1] + p[2][2] * q[2] + p[2][3] * q[3];
        q[2] < dist && z2 > 0.0 && z2 < dist
    }

    #[test]
    fn one_svd_for_both_signs_of_t_gives_opencvs_votes() {
        let (p1, p2) = golden_points();
        let cam = Camera::default();
        let e = find_essential_mat(&p1, &p2, &cam, &RansacParams::default()).unwrap();
        let (r1, r2, t) = decompose_essential(e.essential().unwrap());
        let nt = [-t[0], -t[1], -t[2]];
        // The golden scene (inliers and outliers) plus points scattered over
        // the frame and beyond, so every test of §VO-4 passes and fails somewhere,
        // with short distance thresholds to hit `Z < dist` both ways.
        let mut a: Vec<[f64; 2]> = p1.iter().map(|&p| cam.normalize(p)).collect();
        let mut b: Vec<[f64; 2]> = p2.iter().map(|&p| cam.normalize(p)).collect();
        let mut rnd = crate::testutil::signed_units(0x2545_f491_4f6c_dd1d);
        for _ in 0..2000 {
            let (x, y) = (rnd(), rnd() * 0.5);
            a.push([x, y]);
            b.push([x + 0.05 * rnd(), y + 0.05 * rnd()]);
        }
        let mut counts = [[0usize; 2]; 4];
        for dist in [50.0, 5.0, 1.0] {
            for (&pa, &pb) in a.iter().zip(&b) {
                for (k, r) in [&r1, &r2].into_iter().enumerate() {
                    let (plus, minus) = votes_for(r, &t, pa, pb, dist);
                    assert_eq!(plus, votes_separately(r, &t, pa, pb, dist), "[R{}|t] at {pa:?} {pb:?}", k + 1);
                    assert_eq!(minus, votes_separately(r, &nt, pa, pb, dist), "[R{}|-t] at {pa:?} {pb:?}", k + 1);
                    counts[k][plus as usize] += 1;
                    counts[k + 2][minus as usize] += 1;
                }
            }
        }
        // [R2|±t] turns the scene around: it wins almost no points.
        assert!(counts.iter().all(|c| c[0] > 100), "{counts:?}");
        assert!(counts[0][1] > 100 && counts[2][1] > 100, "{counts:?}");
    }

    #[test]
    fn matches_opencv_recover_pose() {
        // cv2.recoverPose(E, p1, p2, focal=718.856, pp=(607.1928, 185.2157))
        // on the RANSAC golden scene (testdata/gen_goldens.py), no mask: the
        // 60 outliers vote too.
        const OPENCV_POSE_INLIERS: usize = 272;
        const OPENCV_R: [f64; 9] = [
            0.9994882662951008,
            -0.005078179988538283,
            -0.031581919295975695,
            0.004920195910347442,
            0.9999750021635226,
            -0.0050780626489777304,
            0.031606917132446344,
            0.004920074803003417,
            0.9994882668912705,
        ];
        const OPENCV_T: [f64; 3] = [0.049927594927897265, -0.019971864884850813, -0.9985531332271392];
        let (p1, p2) = golden_points();
        let cam = Camera::default();
        let e = find_essential_mat(&p1, &p2, &cam, &RansacParams::default()).unwrap();
        let pose = recover_pose(e.essential().unwrap(), &p1, &p2, &cam).unwrap();
        assert_eq!(pose.inliers, OPENCV_POSE_INLIERS);
        assert_eq!(pose.mask.iter().filter(|&&m| m).count(), OPENCV_POSE_INLIERS);
        assert!(close(pose.r.concat(), OPENCV_R, 1e-10), "R {:?}", pose.r);
        assert!(close(pose.t, OPENCV_T, 1e-10), "t {:?}", pose.t);
        // And the truth: R within 1e-5, t within 1e-3 of the unit direction.
        let tn = (SCENE_T[0].powi(2) + SCENE_T[1].powi(2) + SCENE_T[2].powi(2)).sqrt();
        assert!(close(pose.t, SCENE_T.map(|v| v / tn), 1e-3));
        assert!(close(pose.r.concat(), SCENE_R.concat(), 1e-5));
    }

    #[test]
    fn pixel_pipeline_recovers_forward_motion() {
        let cam = Camera::default();
        let r = rodrigues([0.0, 0.02, 0.0]);
        let t = [0.0, 0.0, -1.0];
        let (a, b) = scene(&r, t, 400, 8);
        let px = |p: [f64; 2]| [(p[0] * cam.fx + cam.cx) as f32, (p[1] * cam.fy + cam.cy) as f32];
        let p1: Vec<[f32; 2]> = a.iter().map(|&p| px(p)).collect();
        let p2: Vec<[f32; 2]> = b.iter().map(|&p| px(p)).collect();
        let e = find_essential_mat(&p1, &p2, &cam, &RansacParams::default()).unwrap();
        let pose = recover_pose(e.essential().unwrap(), &p1, &p2, &cam).unwrap();
        assert_eq!(pose.inliers, 400);
        assert!(close(pose.t, t, 1e-3), "t {:?}", pose.t);
        assert!(close(pose.r.concat(), r.concat(), 1e-4), "R {:?}", pose.r);
    }
}
