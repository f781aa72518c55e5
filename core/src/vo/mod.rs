//! The lab's monocular visual odometry, stage by stage as OpenCV 4.8 computes
//! it (`docs/fidelity.md` §VO-1 to §VO-7): [`lk`] tracks points
//! (`calcOpticalFlowPyrLK`), [`ransac`] estimates the essential matrix with the
//! [`five_point`] kernel (`findEssentialMat`), [`recover_pose`](fn@recover_pose) picks R, t
//! (`recoverPose`), [`odometry`] is the lab's accumulation loop, [`matched`]
//! the same loop driven by the student's matcher instead of LK, [`metrics`]
//! scores a trajectory against ground truth, [`Record`] keeps a run's poses
//! and scores it at its end. [`linalg`] holds the numeric
//! routines they share (OpenCV's Jacobi SVD, LU inverse, `solvePoly`, `cv::RNG`).

// Every unsafe operation sits in its own `unsafe` block with the reason it
// holds, also inside `unsafe fn`s.

pub mod export;
pub(crate) mod five_point;
pub(crate) mod linalg;
pub(crate) mod lk;
pub mod matched;
pub mod metrics;
pub mod odometry;
pub(crate) mod ransac;
pub(crate) mod record;
pub(crate) mod recover_pose;
#[cfg(test)]
mod testing;

pub use crate::camera::Camera;
pub use export::{kitti_rows_text, kitti_text, tum_text};
pub use linalg::{det3, mat_mul, mat_vec, skew, transpose, Mat3, Vec3, IDENTITY};
pub use lk::{calc_optical_flow_pyr_lk, LkParams, LkResult};
pub use matched::{matched_points, run_matched, MatchedOdometry};
pub use metrics::{
    ate_rmse, describe_kitti_segments, evaluate, kitti_segments, max_median, position_differences, KittiSegment,
    TrajectoryMetrics,
};
pub use odometry::{pose_row, run, sift_detector, Odometry, StepDetail, StepResult, Steps};
pub use ransac::{find_essential_mat, EssentialResult, RansacParams};
pub use record::{kitti_line, Record, RunEnd};
pub use recover_pose::{recover_pose, Pose};
