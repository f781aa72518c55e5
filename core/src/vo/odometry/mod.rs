//! The lab's trajectory loop (docs/fidelity.md §VO-5) as a step API: feed frames
//! in order with their ground-truth pose, get the position after each one.
//!
//! ```text
//! frame 0:  ref = SIFT keypoint positions
//! frame i:  cur = LK(last, img, ref), keep status 1
//!           E = findEssentialMat(cur, ref); Ri, ti = recoverPose(E, cur, ref)
//!           i == 1: R, t = Ri, ti (unscaled)
//!           else:   scale = |gt_i − gt_{i−1}|; if scale > 0.1: t += scale·R·ti; R = Ri·R
//!                   if #tracked < 1500: cur = SIFT positions of img
//!           ref = cur
//! ```
//!
//! One file per job: `step.rs` what a frame did and the lab's pose arithmetic
//! (shared with [`super::matched`]), `tracker.rs` the LK loop itself
//! ([`Odometry`], one frame per step), `pipeline.rs` a whole run with the
//! detection ahead on other threads ([`run`]).

mod pipeline;
mod step;
#[cfg(test)]
mod tests;
mod tracker;

pub use pipeline::run;
pub(crate) use step::{apply_motion, lab_scale};
pub use step::{pose_row, StepDetail, StepResult};
pub use tracker::{sift_detector, Detector, Odometry, Steps};
