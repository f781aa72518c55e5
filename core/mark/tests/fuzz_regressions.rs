//! Replays every input the `mark_reply` fuzzer found (and minimised) under
//! `tests/fuzz/regressions/mark_reply/` through the same checks the
//! cargo-fuzz target runs (`tests/fuzz/src/mark_checks.rs`, included
//! below), on stable Rust. docs/fuzzing.md.

#[path = "../../../tests/fuzz/src/mark_checks.rs"]
mod checks;

use std::path::PathBuf;

#[test]
fn mark_reply() {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../tests/fuzz/regressions/mark_reply");
    let mut inputs: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_file() && p.extension().is_none_or(|x| x != "md"))
        .collect();
    inputs.sort();
    assert!(!inputs.is_empty(), "no input in {}", dir.display());
    for path in inputs {
        // One line per input, so a failure names the file.
        eprintln!("mark_reply/{}", path.file_name().unwrap().to_string_lossy());
        checks::mark_reply(&std::fs::read(&path).unwrap());
    }
}
