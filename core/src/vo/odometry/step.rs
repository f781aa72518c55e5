//! What one frame of the loop did ([`StepResult`], [`StepDetail`]) and the
//! lab's pose arithmetic: the scale from the true poses, the update of R and
//! t, a pose as a KITTI line. Shared by the LK loop and the matcher's loop.

use crate::dataset::{dist3, position, PoseRow};
use crate::vo::linalg::{mat_mul, mat_vec, Mat3, Vec3};
use crate::{Error, Result};

/// What one frame did.
#[derive(Clone, Debug, PartialEq)]
pub struct StepResult {
    pub frame: usize,
    /// The position the lab draws after this frame: t for i ≥ 2, else 0.
    pub position: Vec3,
    /// Ground-truth position of this frame, if given.
    pub gt_position: Option<Vec3>,
    /// Accumulated rotation after this frame.
    pub rotation: Mat3,
    /// Points given to LK / tracked with status 1 (0 for frame 0).
    pub points_in: usize,
    pub tracked: usize,
    /// findEssentialMat inliers and RANSAC iterations, recoverPose inliers.
    pub essential_inliers: usize,
    pub ransac_iterations: usize,
    pub pose_inliers: usize,
    /// GT scale used (frames ≥ 2) and whether it passed the 0.1 test.
    pub scale: Option<f64>,
    pub updated: bool,
    /// Whether the points were re-detected (frame 0 counts as detected).
    pub redetected: bool,
    /// Points carried to the next frame.
    pub points_out: usize,
    /// The points themselves, when the loop was asked to record them
    /// ([`Odometry::record_detail`](super::Odometry::record_detail)): what the app draws on the frame.
    pub detail: Option<Box<StepDetail>>,
}

/// One frame's points, as the loop used them: each tracked (or matched)
/// point where it was in the previous frame and where it is in this one
/// (the `points2`, `points1` of findEssentialMat), whether RANSAC kept it
/// (findEssentialMat's mask) and whether recoverPose counted it (its mask:
/// in front of both cameras), and the points re-detected on this frame.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct StepDetail {
    pub prev: Vec<[f32; 2]>,
    pub cur: Vec<[f32; 2]>,
    pub essential_mask: Vec<bool>,
    pub pose_mask: Vec<bool>,
    /// The detector's points on this frame when the loop re-detected (frame 0
    /// included); empty otherwise.
    pub detected: Vec<[f32; 2]>,
}

impl StepResult {
    /// Frame `frame` before anything happened: the pose so far, no counts.
    pub fn start(frame: usize, gt: Option<&PoseRow>, rotation: Mat3) -> StepResult {
        StepResult {
            frame,
            position: [0.0; 3],
            gt_position: gt.map(position),
            rotation,
            points_in: 0,
            tracked: 0,
            essential_inliers: 0,
            ransac_iterations: 0,
            pose_inliers: 0,
            scale: None,
            updated: false,
            redetected: false,
            points_out: 0,
            detail: None,
        }
    }
}

/// The lab's scale for frame `i`: `math.dist` of the true positions of frames
/// i−1 and i, from frame 2 on (frame 1 keeps recoverPose's unit translation).
pub(crate) fn lab_scale(i: usize, prev_gt: Option<&PoseRow>, gt: Option<&PoseRow>) -> Result<Option<f64>> {
    if i < 2 {
        return Ok(None);
    }
    let (Some(prev), Some(cur)) = (prev_gt, gt) else {
        return Err(Error::Odometry(format!(
            "frame {i} needs the ground-truth poses of frames {} and {i} for its scale \
             (poses/00.txt is missing lines)",
            i - 1
        )));
    };
    Ok(Some(dist3(&position(prev), &position(cur))))
}

/// The lab's update with a scale that passed its `> 0.1` test:
/// t += s·R·t_rel, then R = R_rel·R.
pub(crate) fn apply_motion(r: &mut Mat3, t: &mut Vec3, pose_r: &Mat3, pose_t: &Vec3, s: f64) {
    let rt = mat_vec(r, pose_t);
    *t = [t[0] + s * rt[0], t[1] + s * rt[1], t[2] + s * rt[2]];
    *r = mat_mul(pose_r, r);
}

/// A KITTI pose line for (R, t): `R00 R01 R02 t0 R10 ... t2`.
pub fn pose_row(r: &Mat3, t: &Vec3) -> PoseRow {
    [r[0][0], r[0][1], r[0][2], t[0], r[1][0], r[1][1], r[1][2], t[1], r[2][0], r[2][1], r[2][2], t[2]]
}
