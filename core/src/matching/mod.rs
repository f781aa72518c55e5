//! Matching as the lab does it: `cv2.BFMatcher()` (L2, brute force, k-NN),
//! the dt / nn / nndr strategies, `matching_info`, and the explanation of a
//! result for the app; whole-frame matches judged by the true epipolar
//! geometry (`epipolar`) and the threshold sweep (`sweep`).

// Every unsafe operation sits in its own `unsafe` block with the reason it
// holds, also inside `unsafe fn`s.

pub(crate) mod distance;
// Whole-frame matching judged by the true geometry, and the threshold sweep:
// APIs of their own for the app's "see inside" view and `match_all`.
pub mod args;
pub mod epipolar;
pub(crate) mod explain;
pub(crate) mod info;
pub(crate) mod kind;
pub(crate) mod knn;
pub(crate) mod strategy;
pub mod sweep;

pub use explain::{explain, mistaken_answers, Explanation, Mistake, Verdict};
pub use info::{matching_info, py_int, MatchInfo};
pub use kind::StrategyKind;
pub use knn::{knn_match, DMatch};
pub use strategy::{check_feature, match_all, match_feature, Strategy};
