//! Each case judged: correct, wrong or an error, and for a failed case why.
//! The self-check's mistakes ([`Mistake`](siftlab_core::matching::Mistake))
//! where they apply, and the ones a whole result shows (a list per query
//! dropped, float64 distances, another order, a threshold ignored, the empty
//! case, …).
//!
//! One file per job: `judge.rs` the verdict of a case ([`judge`],
//! [`failed_call`]), `diagnosis.rs` the kinds of mistake and their words to
//! the student ([`Diagnosis`]), `matches.rs` why dt / nn / nndr's lists
//! differ, `info.rs` why matching_info's tuple differs, `difference.rs` what
//! a picture of a wrong value shows.

mod diagnosis;
mod difference;
mod info;
mod judge;
mod matches;
#[cfg(test)]
mod tests;

pub use diagnosis::Diagnosis;
pub use difference::Difference;
pub use judge::{failed_call, judge, CaseResult, Status};
