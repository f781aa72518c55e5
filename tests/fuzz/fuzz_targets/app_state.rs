#![no_main]
//! See tests/fuzz/src/app_checks.rs and docs/fuzzing.md.

#[path = "../src/app_checks.rs"]
mod checks;

libfuzzer_sys::fuzz_target!(|data: &[u8]| checks::app_state(data));
