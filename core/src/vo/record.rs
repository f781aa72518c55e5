//! The end of an odometry run, built once for the CLI's `view_trajectory`
//! and the app's tracking worker: each step is pushed as it comes, and
//! [`Record::finish`] scores the run against the ground truth (ATE, the
//! evo-equal metrics, the KITTI segments and their line). Both callers then
//! only carry the figures to their user.

use super::linalg::{Mat3, Vec3};
use super::metrics::{ate_rmse, describe_kitti_segments, evaluate, kitti_segments, KittiSegment, TrajectoryMetrics};
use super::odometry::{pose_row, StepResult};
use crate::dataset::{dist3, position, PoseRow};
use crate::error::Result;

/// The poses of a run so far, in frame order: what the lab draws after each
/// frame (accumulated R, the drawn position).
#[derive(Clone, Debug, Default)]
pub struct Record {
    poses: Vec<(Mat3, Vec3)>,
}

/// A finished run's figures against the first `frames` true poses.
#[derive(Clone, Debug)]
pub struct RunEnd {
    pub frames: usize,
    /// The lab's trajectory error: RMSE of the drawn positions, unaligned.
    pub ate: f64,
    pub metrics: TrajectoryMetrics,
    /// The KITTI segments the metric rests on (none under 100 m of path).
    pub segments: Vec<KittiSegment>,
    /// The true positions of frames 0 … frames − 1.
    pub truth: Vec<Vec3>,
}

impl Record {
    /// Adds the pose a step ended on.
    pub fn push(&mut self, step: &StepResult) {
        self.poses.push((step.rotation, step.position));
    }

    pub fn len(&self) -> usize {
        self.poses.len()
    }

    pub fn is_empty(&self) -> bool {
        self.poses.is_empty()
    }

    /// (R, position) per frame: what `kitti_text` and `tum_text` write.
    pub fn poses(&self) -> &[(Mat3, Vec3)] {
        &self.poses
    }

    /// The drawn positions per frame.
    pub fn positions(&self) -> Vec<Vec3> {
        self.poses.iter().map(|p| p.1).collect()
    }

    /// The poses as KITTI rows (evo's input, the app's download).
    pub fn rows(&self) -> Vec<PoseRow> {
        self.poses.iter().map(|(r, t)| pose_row(r, t)).collect()
    }

    /// Scores the run against `gt`, the true poses from frame 0 (at least as
    /// many as the run's frames; the callers check that before the run with
    /// [`crate::dataset::check_pose_count`]).
    pub fn finish(&self, gt: &[PoseRow]) -> Result<RunEnd> {
        let n = self.poses.len();
        let gt = gt.get(..n).ok_or_else(|| {
            crate::Error::InvalidArgument(format!("{n} frames were run but {} true poses are given", gt.len()))
        })?;
        let truth: Vec<Vec3> = gt.iter().map(position).collect();
        let ate = ate_rmse(&self.positions(), &truth)?;
        let metrics = evaluate(&self.rows(), gt)?;
        Ok(RunEnd { frames: n, ate, metrics, segments: kitti_segments(gt), truth })
    }
}

impl RunEnd {
    /// The line printed under the metrics: the segments the KITTI figures
    /// rest on and the true path's length.
    pub fn kitti_line(&self) -> String {
        kitti_line_of(&self.truth, &self.segments)
    }
}

/// [`RunEnd::kitti_line`] for the first true poses alone, before any run
/// (the app's note beside its metrics table):
/// "KITTI metric: 2 segments of 100 m (true path 109.9 m)".
pub fn kitti_line(gt: &[PoseRow]) -> String {
    let truth: Vec<Vec3> = gt.iter().map(position).collect();
    kitti_line_of(&truth, &kitti_segments(gt))
}

fn kitti_line_of(truth: &[Vec3], segments: &[KittiSegment]) -> String {
    let path: f64 = truth.windows(2).map(|w| dist3(&w[0], &w[1])).sum();
    format!("KITTI metric: {} (true path {path:.1} m)", describe_kitti_segments(segments))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vo::IDENTITY;

    fn row(x: f64, z: f64) -> PoseRow {
        [1.0, 0.0, 0.0, x, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, z]
    }

    fn step(frame: usize, x: f64, z: f64) -> StepResult {
        let mut s = StepResult::start(frame, None, IDENTITY);
        s.position = [x, 0.0, z];
        s
    }

    #[test]
    fn scores_the_pushed_poses_against_the_first_true_ones() {
        let mut rec = Record::default();
        for (i, (x, z)) in [(0.0, 0.0), (0.0, 1.0), (3.0, 2.0)].into_iter().enumerate() {
            rec.push(&step(i, x, z));
        }
        // One more true pose than frames: only the first three count.
        let gt = [row(0.0, 0.0), row(0.0, 1.0), row(0.0, 2.0), row(0.0, 50.0)];
        let end = rec.finish(&gt).unwrap();
        // Errors 0, 0, 3 m: RMSE √(9/3).
        assert_eq!(end.frames, 3);
        assert!((end.ate - 3f64.sqrt()).abs() < 1e-12, "{}", end.ate);
        assert_eq!(end.metrics.frames, 3);
        assert!(end.segments.is_empty());
        assert_eq!(end.kitti_line(), "KITTI metric: no segment of 100 m or more (true path 2.0 m)");
        assert_eq!(end.kitti_line(), kitti_line(&gt[..3]));
        assert_eq!(rec.rows()[2][3], 3.0);
        let e = rec.finish(&gt[..2]).unwrap_err().to_string();
        assert!(e.contains("3 frames were run but 2 true poses are given"), "{e}");
    }
}
