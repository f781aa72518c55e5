//! Trajectory scores, as odometry papers and tools (the KITTI devkit, `evo`)
//! report them, over the poses of frames 0..N: the estimate S_i and the
//! ground truth G_i as camera-to-world matrices (KITTI pose rows).
//!
//! - ATE: RMSE of the position differences, raw (the lab's estimate is
//!   already in ground-truth scale) and after the least-squares rigid
//!   alignment of the estimated positions onto the true ones (Umeyama
//!   without scale), which forgives a constant offset and heading;
//! - RPE: RMSE over consecutive frames of the relative-motion error
//!   E_i = (G_{i−1}⁻¹G_i)⁻¹(S_{i−1}⁻¹S_i), its translation and its angle;
//! - the KITTI odometry metric: mean translation (%) and rotation (°/100 m)
//!   error of segments of 100 … 800 m of true path, from every 10th frame;
//!   [`kitti_segments`] lists the segments it averages over, which depend on
//!   the truth only (a short run has few: frames 0–150 of KITTI 00, 110 m,
//!   have two of 100 m).
//!
//! None of this has to equal OpenCV bit for bit, so it uses `nalgebra`.

use crate::dataset::PoseRow;
use crate::{Error, Result};
use nalgebra::{Matrix3, Matrix4, Vector3};

/// Root mean square of the position differences.
pub fn ate_rmse(est: &[[f64; 3]], gt: &[[f64; 3]]) -> Result<f64> {
    check_lengths(est.len(), gt.len())?;
    let sum: f64 = est.iter().zip(gt).map(|(e, g)| (0..3).map(|k| (e[k] - g[k]) * (e[k] - g[k])).sum::<f64>()).sum();
    Ok((sum / est.len() as f64).sqrt())
}

fn check_lengths(est: usize, gt: usize) -> Result<()> {
    if est != gt || est == 0 {
        return Err(Error::InvalidArgument(format!(
            "trajectory error needs the same non-zero number of estimated and ground-truth \
             positions ({est} vs {gt})"
        )));
    }
    Ok(())
}

/// Euclidean distance between the two trajectories, frame by frame.
pub fn position_differences(a: &[[f64; 3]], b: &[[f64; 3]]) -> Vec<f64> {
    a.iter().zip(b).map(|(p, q)| (0..3).map(|k| (p[k] - q[k]) * (p[k] - q[k])).sum::<f64>().sqrt()).collect()
}

/// (max, median) of a list of non-negative numbers; (0, 0) when empty.
pub fn max_median(v: &[f64]) -> (f64, f64) {
    if v.is_empty() {
        return (0.0, 0.0);
    }
    let mut s = v.to_vec();
    s.sort_by(|a, b| a.total_cmp(b));
    let n = s.len();
    let med = if n % 2 == 1 { s[n / 2] } else { (s[n / 2 - 1] + s[n / 2]) / 2.0 };
    (s[n - 1], med)
}

/// Every score of a trajectory (see the module's documentation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrajectoryMetrics {
    /// Number of poses scored (frames 0..frames).
    pub frames: usize,
    pub ate_rmse: f64,
    pub ate_rmse_aligned: f64,
    /// 0 with one pose (no consecutive pair).
    pub rpe_trans_rmse: f64,
    pub rpe_rot_rmse_deg: f64,
    /// `None` when the true path is shorter than 100 m (no KITTI segment fits).
    pub kitti_t_err_pct: Option<f64>,
    pub kitti_r_err_deg_per_100m: Option<f64>,
}

impl TrajectoryMetrics {
    /// One JSON object; floats in Rust's shortest round-trip form, `null`
    /// for a KITTI figure without a segment.
    pub fn to_json(&self) -> String {
        let opt = |v: Option<f64>| v.map_or("null".to_string(), |v| format!("{v:?}"));
        format!(
            "{{\"frames\": {}, \"ate_rmse\": {:?}, \"ate_rmse_aligned\": {:?}, \"rpe_trans_rmse\": {:?}, \
             \"rpe_rot_rmse_deg\": {:?}, \"kitti_t_err_pct\": {}, \"kitti_r_err_deg_per_100m\": {}}}",
            self.frames,
            self.ate_rmse,
            self.ate_rmse_aligned,
            self.rpe_trans_rmse,
            self.rpe_rot_rmse_deg,
            opt(self.kitti_t_err_pct),
            opt(self.kitti_r_err_deg_per_100m)
        )
    }

    /// [`Self::to_json`] with `"kitti_segments": N` (how many segments the
    /// KITTI figures average over, [`kitti_segments`]) as the last key: what
    /// `view_trajectory --metrics` writes.
    pub fn to_json_with_segments(&self, kitti_segments: usize) -> String {
        let json = self.to_json();
        format!("{}, \"kitti_segments\": {kitti_segments}}}", &json[..json.len() - 1])
    }

    /// The seven numbers in declaration order, `None` as NaN: how the app's
    /// worker posts them (a Float64Array).
    pub fn to_array(&self) -> [f64; 7] {
        [
            self.frames as f64,
            self.ate_rmse,
            self.ate_rmse_aligned,
            self.rpe_trans_rmse,
            self.rpe_rot_rmse_deg,
            self.kitti_t_err_pct.unwrap_or(f64::NAN),
            self.kitti_r_err_deg_per_100m.unwrap_or(f64::NAN),
        ]
    }

    /// The inverse of [`Self::to_array`].
    pub fn from_array(a: &[f64; 7]) -> TrajectoryMetrics {
        let opt = |v: f64| (!v.is_nan()).then_some(v);
        TrajectoryMetrics {
            frames: a[0] as usize,
            ate_rmse: a[1],
            ate_rmse_aligned: a[2],
            rpe_trans_rmse: a[3],
            rpe_rot_rmse_deg: a[4],
            kitti_t_err_pct: opt(a[5]),
            kitti_r_err_deg_per_100m: opt(a[6]),
        }
    }

    /// The figures in one line, for the CLI's stderr and the app's table.
    pub fn summary(&self) -> String {
        let kitti = match (self.kitti_t_err_pct, self.kitti_r_err_deg_per_100m) {
            (Some(t), Some(r)) => format!("{t:.2} % / {r:.3} °/100 m"),
            _ => "n/a (true path < 100 m)".to_string(),
        };
        format!(
            "ATE {:.4} m (aligned {:.4} m) · RPE {:.4} m / {:.4}° · KITTI {kitti}",
            self.ate_rmse, self.ate_rmse_aligned, self.rpe_trans_rmse, self.rpe_rot_rmse_deg
        )
    }
}

/// A KITTI pose row as a 4×4 camera-to-world matrix.
pub fn pose_matrix(p: &PoseRow) -> Matrix4<f64> {
    Matrix4::new(p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7], p[8], p[9], p[10], p[11], 0.0, 0.0, 0.0, 1.0)
}

fn inverse(m: &Matrix4<f64>, what: &str) -> Result<Matrix4<f64>> {
    m.lu().try_inverse().ok_or_else(|| {
        Error::InvalidArgument(format!("{what} is not invertible: a pose needs a rotation (check the pose file)"))
    })
}

/// The angle of a rotation (the upper-left 3×3 of `m`), in radians, as the
/// KITTI devkit computes it: arccos((tr R − 1)/2), the cosine clamped to [−1, 1].
pub fn rotation_angle(m: &Matrix4<f64>) -> f64 {
    let d = 0.5 * (m[(0, 0)] + m[(1, 1)] + m[(2, 2)] - 1.0);
    d.clamp(-1.0, 1.0).acos()
}

fn translation_norm(m: &Matrix4<f64>) -> f64 {
    Vector3::new(m[(0, 3)], m[(1, 3)], m[(2, 3)]).norm()
}

/// The estimated and the true motion from frame `a` to `b`: (S_a⁻¹S_b, G_a⁻¹G_b).
fn motions(s: &[Matrix4<f64>], g: &[Matrix4<f64>], a: usize, b: usize) -> Result<(Matrix4<f64>, Matrix4<f64>)> {
    Ok((inverse(&s[a], "an estimated pose")? * s[b], inverse(&g[a], "a ground-truth pose")? * g[b]))
}

/// The error of the estimated motion from frame `a` to `b` against the true
/// one, as RPE takes it: (G_a⁻¹G_b)⁻¹(S_a⁻¹S_b).
fn motion_error(s: &[Matrix4<f64>], g: &[Matrix4<f64>], a: usize, b: usize) -> Result<Matrix4<f64>> {
    let (est, truth) = motions(s, g, a, b)?;
    Ok(inverse(&truth, "a true motion")? * est)
}

/// The same error the other way round, as the KITTI devkit takes it
/// (`inverse(pose_delta_result) * pose_delta_gt`): (S_a⁻¹S_b)⁻¹(G_a⁻¹G_b).
/// Its translation's length and its angle equal [`motion_error`]'s only for
/// exact rotations; the true ones are orthonormal to 1.6e-7, which moved the
/// KITTI figures of frames 0–150 by 1e-8 relative.
fn kitti_motion_error(s: &[Matrix4<f64>], g: &[Matrix4<f64>], a: usize, b: usize) -> Result<Matrix4<f64>> {
    let (est, truth) = motions(s, g, a, b)?;
    Ok(inverse(&est, "an estimated motion")? * truth)
}

/// The least-squares rigid motion (R, t) that maps `src` onto `dst`
/// (Umeyama 1991 without scale): R from the SVD of the cross-covariance,
/// with the reflection case turned into a rotation.
pub fn rigid_alignment(src: &[[f64; 3]], dst: &[[f64; 3]]) -> (Matrix3<f64>, Vector3<f64>) {
    let n = src.len().max(1) as f64;
    let v = |p: &[f64; 3]| Vector3::new(p[0], p[1], p[2]);
    let ms = src.iter().map(v).sum::<Vector3<f64>>() / n;
    let md = dst.iter().map(v).sum::<Vector3<f64>>() / n;
    let mut h = Matrix3::zeros();
    for (a, b) in src.iter().zip(dst) {
        h += (v(b) - md) * (v(a) - ms).transpose();
    }
    let svd = h.svd(true, true);
    let (u, vt) = (svd.u.unwrap_or_else(Matrix3::identity), svd.v_t.unwrap_or_else(Matrix3::identity));
    let mut d = Matrix3::identity();
    if (u * vt).determinant() < 0.0 {
        d[(2, 2)] = -1.0;
    }
    let r = u * d * vt;
    (r, md - r * ms)
}

/// ATE after [`rigid_alignment`] of the estimated positions onto the true ones.
pub fn ate_rmse_aligned(est: &[[f64; 3]], gt: &[[f64; 3]]) -> Result<f64> {
    check_lengths(est.len(), gt.len())?;
    let (r, t) = rigid_alignment(est, gt);
    let moved: Vec<[f64; 3]> = est
        .iter()
        .map(|p| {
            let q = r * Vector3::new(p[0], p[1], p[2]) + t;
            [q[0], q[1], q[2]]
        })
        .collect();
    ate_rmse(&moved, gt)
}

/// One segment of the KITTI metric: frames `first` to `last` of the truth,
/// scored against `length` metres of true path.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KittiSegment {
    pub first: usize,
    pub last: usize,
    pub length: f64,
}

/// The segments the KITTI devkit scores on the true poses `gt` (frames
/// 0..N), in its order: by first frame, then by length.
pub fn kitti_segments(gt: &[PoseRow]) -> Vec<KittiSegment> {
    let g: Vec<Matrix4<f64>> = gt.iter().map(pose_matrix).collect();
    segments(&g)
}

/// "2 segments of 100 m", "3 segments (2 of 100 m, 1 of 200 m)", or why there
/// is none: what the CLI prints beside the KITTI figures.
pub fn describe_kitti_segments(segs: &[KittiSegment]) -> String {
    let plural = |n: usize| if n == 1 { "" } else { "s" };
    let mut by_length: Vec<(f64, usize)> = Vec::new();
    for s in segs {
        match by_length.iter_mut().find(|(l, _)| *l == s.length) {
            Some((_, n)) => *n += 1,
            None => by_length.push((s.length, 1)),
        }
    }
    match by_length.as_slice() {
        [] => "no segment of 100 m or more".to_string(),
        [(l, n)] => format!("{n} segment{} of {l} m", plural(*n)),
        many => format!(
            "{} segments ({})",
            segs.len(),
            many.iter().map(|(l, n)| format!("{n} of {l} m")).collect::<Vec<_>>().join(", ")
        ),
    }
}

/// The devkit's segments over 4×4 true poses (see [`kitti_errors`]).
fn segments(g: &[Matrix4<f64>]) -> Vec<KittiSegment> {
    let mut dist = vec![0.0f64; g.len()];
    for i in 1..g.len() {
        dist[i] = dist[i - 1] + translation_norm(&(g[i] - g[i - 1]));
    }
    let mut out = Vec::new();
    for first in (0..g.len()).step_by(KITTI_STEP) {
        for length in KITTI_LENGTHS {
            if let Some(last) = (first..g.len()).find(|&i| dist[i] > dist[first] + length) {
                out.push(KittiSegment { first, last, length });
            }
        }
    }
    out
}

/// Segment lengths of the KITTI odometry benchmark, in metres of true path.
pub const KITTI_LENGTHS: [f64; 8] = [100.0, 200.0, 300.0, 400.0, 500.0, 600.0, 700.0, 800.0];
/// The benchmark starts a segment at every 10th frame.
pub const KITTI_STEP: usize = 10;

/// The KITTI devkit's metric: for each start frame (every 10th) and each
/// length L, the segment ends at the first frame whose true path distance
/// exceeds the start's by more than L; the error's translation / L and its
/// angle / L are averaged over all segments. Returns (t_err in %, r_err in
/// °/100 m), `None` when no segment fits.
pub fn kitti_errors(s: &[Matrix4<f64>], g: &[Matrix4<f64>]) -> Result<Option<(f64, f64)>> {
    let (mut t_sum, mut r_sum) = (0.0, 0.0);
    let segs = segments(g);
    for seg in &segs {
        let e = kitti_motion_error(s, g, seg.first, seg.last)?;
        t_sum += translation_norm(&e) / seg.length;
        r_sum += rotation_angle(&e) / seg.length;
    }
    let count = segs.len() as f64;
    Ok((!segs.is_empty()).then(|| (100.0 * t_sum / count, (r_sum / count).to_degrees() * 100.0)))
}

/// Every score of the estimate `est` against the truth `gt` (pose rows of
/// frames 0..N, the same N).
pub fn evaluate(est: &[PoseRow], gt: &[PoseRow]) -> Result<TrajectoryMetrics> {
    check_lengths(est.len(), gt.len())?;
    let pos = |p: &PoseRow| [p[3], p[7], p[11]];
    let ep: Vec<[f64; 3]> = est.iter().map(pos).collect();
    let gp: Vec<[f64; 3]> = gt.iter().map(pos).collect();
    let s: Vec<Matrix4<f64>> = est.iter().map(pose_matrix).collect();
    let g: Vec<Matrix4<f64>> = gt.iter().map(pose_matrix).collect();
    let (mut t2, mut r2) = (0.0, 0.0);
    for i in 1..s.len() {
        let e = motion_error(&s, &g, i - 1, i)?;
        t2 += translation_norm(&e).powi(2);
        r2 += rotation_angle(&e).powi(2);
    }
    let pairs = (s.len() - 1).max(1) as f64;
    let kitti = kitti_errors(&s, &g)?;
    Ok(TrajectoryMetrics {
        frames: est.len(),
        ate_rmse: ate_rmse(&ep, &gp)?,
        ate_rmse_aligned: ate_rmse_aligned(&ep, &gp)?,
        rpe_trans_rmse: (t2 / pairs).sqrt(),
        rpe_rot_rmse_deg: (r2 / pairs).sqrt().to_degrees(),
        kitti_t_err_pct: kitti.map(|k| k.0),
        kitti_r_err_deg_per_100m: kitti.map(|k| k.1),
    })
}

// Native only: the tests read the bundled poses and fixtures from disk.
#[cfg(all(test, not(target_arch = "wasm32")))]
mod tests;
