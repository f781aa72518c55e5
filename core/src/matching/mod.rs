//! Matching as the lab does it: `cv2.BFMatcher()` (L2, brute force, k-NN),
//! the dt / nn / nndr strategies, `matching_info`, and the explanation of a
//! result for the app; whole-frame matches judged by the true epipolar
//! geometry (`epipolar`) and the threshold sweep (`sweep`).

// Every unsafe operation sits in its own `unsafe` block with the reason it
// holds, also inside `unsafe fn`s.
#![deny(unsafe_op_in_unsafe_fn)]

pub mod distance;
pub mod epipolar;
pub mod explain;
pub mod info;
pub mod knn;
pub mod strategy;
pub mod sweep;

pub use explain::{explain, mistaken_answers, Explanation, Mistake, Verdict};
pub use info::{matching_info, MatchInfo};
pub use knn::{knn_match, DMatch};
pub use strategy::{match_all, match_feature, Strategy};
