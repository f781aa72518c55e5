//! The lab's monocular visual odometry, stage by stage as OpenCV 4.8 computes it
//! (`../shared/docs/opencv-vo-4.8.md`).

pub mod linalg;
pub mod lk;
