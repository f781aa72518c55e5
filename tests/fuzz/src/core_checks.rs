//! The oracles of the core's fuzz targets. One module, included by the
//! cargo-fuzz targets (`tests/fuzz/fuzz_targets/*.rs`, nightly) and by the stable
//! replay test `core/tests/fuzz_regressions.rs`, so a committed finding is
//! replayed through exactly the checks that found it. A check panics only on
//! a bug: a panic inside the core, a wrong answer, or a refusal without a
//! message. docs/fuzzing.md says what each target compares.
//!
//! This file holds the targets' entry points and what they share; the checks
//! are beside it, one file a target: `core_checks/png.rs`, `core_checks/sift.rs`,
//! `core_checks/matcher.rs` and `core_checks/poses.rs`. Each `mod` names its path:
//! the includers load this file with `#[path]`, which changes where a plain
//! `mod` would look.
#![allow(dead_code)]

use siftlab_core::image::MAX_PIXELS;
use siftlab_core::Error;

#[path = "core_checks/matcher.rs"]
mod matcher;
#[path = "core_checks/png.rs"]
mod png;
#[path = "core_checks/poses.rs"]
mod poses;
#[path = "core_checks/sift.rs"]
mod sift;

pub use matcher::matching;
pub use png::png_diff;
pub use poses::poses;
pub use sift::sift;

/// Any failure must say something a student can act on.
fn check_message(e: &Error) {
    let m = e.to_string();
    assert!(m.len() >= 20, "an error without a useful message: {m:?}");
    if let Error::TooLarge { width, height, limit } = e {
        assert_eq!(*limit, MAX_PIXELS);
        assert!(*width as u64 * *height as u64 > MAX_PIXELS, "TooLarge for {width}x{height}");
    }
}
