//! Replays every input the fuzzers found (and minimised) under
//! `tests/fuzz/regressions/<target>/` through the same checks the cargo-fuzz
//! targets run (`tests/fuzz/src/core_checks.rs`, included below), on stable Rust:
//! a fixed finding stays fixed without nightly in CI. The app's target is
//! replayed by `app/tests/fuzz_regressions.rs`. docs/fuzzing.md.
#![cfg(not(target_arch = "wasm32"))]

#[path = "../../tests/fuzz/src/core_checks.rs"]
mod checks;

use std::path::PathBuf;

/// Every file of one target's regression folder, with its name.
pub fn inputs(target: &str) -> Vec<(String, Vec<u8>)> {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../tests/fuzz/regressions").join(target);
    let mut out: Vec<(String, Vec<u8>)> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .filter(|p| {
            p.is_file()
                && p.extension().is_none_or(|x| x != "md")
                && !p.file_name().unwrap().to_string_lossy().starts_with('.')
        })
        .map(|p| (p.file_name().unwrap().to_string_lossy().into_owned(), std::fs::read(&p).unwrap()))
        .collect();
    out.sort();
    out
}

fn replay(target: &str, check: fn(&[u8])) {
    for (name, bytes) in inputs(target) {
        // One line per input, so a failure names the file.
        eprintln!("{target}/{name}");
        check(&bytes);
    }
}

/// One test per fuzz target, each replaying that target's folder through the
/// check of the same name.
macro_rules! replay_tests {
    ($($target:ident),*) => {$(
        #[test]
        fn $target() {
            replay(stringify!($target), checks::$target);
        }
    )*};
}

replay_tests!(png_diff, sift, matching, poses);
