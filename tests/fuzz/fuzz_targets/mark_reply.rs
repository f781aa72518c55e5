#![no_main]
//! See tests/fuzz/src/mark_checks.rs and docs/fuzzing.md.

#[path = "../src/mark_checks.rs"]
mod checks;

libfuzzer_sys::fuzz_target!(|data: &[u8]| checks::mark_reply(data));
