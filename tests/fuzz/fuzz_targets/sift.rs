#![no_main]
//! See tests/fuzz/src/core_checks.rs and docs/fuzzing.md.

#[path = "../src/core_checks.rs"]
mod checks;

libfuzzer_sys::fuzz_target!(|data: &[u8]| checks::sift(data));
