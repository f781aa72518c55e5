//! Replays the app target's fuzz findings (`tests/fuzz/regressions/app_state/`)
//! through the checks the cargo-fuzz target runs (`tests/fuzz/src/app_checks.rs`),
//! natively on stable Rust. docs/fuzzing.md.
#![cfg(not(target_arch = "wasm32"))]

#[path = "../../tests/fuzz/src/app_checks.rs"]
mod checks;

#[test]
fn app_state() {
    let dir = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../tests/fuzz/regressions/app_state");
    let mut files: Vec<_> = std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().path()).collect();
    files.sort();
    for p in files.into_iter().filter(|p| {
        p.is_file()
            && p.extension().is_none_or(|x| x != "md")
            && !p.file_name().unwrap().to_string_lossy().starts_with('.')
    }) {
        eprintln!("app_state/{}", p.file_name().unwrap().to_string_lossy());
        checks::app_state(&std::fs::read(&p).unwrap());
    }
}
