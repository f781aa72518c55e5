//! The `siftlab` binary end to end: `get_info` against OpenCV goldens, `sift --json`
//! against the SIFT goldens, and every bad input the issue lists.
//!
//! This file holds the helpers every module uses; the tests are grouped by command:
//! `get_info` (the goldens and the manual's examples), `sift`, `bad_input` and
//! `view_trajectory`.

#![cfg(not(target_arch = "wasm32"))]

#[path = "../../../tests/golden_data/mod.rs"]
mod golden_data;

mod bad_input;
mod get_info;
mod sift;
mod view_trajectory;

use golden_data::{golden_lanes, kitti};

use std::fs;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The bundled real KITTI frames the primary goldens were computed on.
fn dataset() -> PathBuf {
    kitti()
}

fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn golden_lanes_args() -> [String; 2] {
    ["--opencv-lanes".into(), golden_lanes().to_string()]
}

fn siftlab_in(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_siftlab"))
        .current_dir(dir)
        .args(args)
        .output()
        .expect("cannot start the siftlab binary")
}

fn siftlab(args: &[&str]) -> Output {
    siftlab_in(&repo_root(), args)
}

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// A fresh scratch directory per test (no tempfile crate in the core).
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("siftlab-cli-{}-{name}", std::process::id()));
    let _ = fs::remove_dir_all(&dir);
    fs::create_dir_all(&dir).unwrap();
    dir
}

/// Asserts a clean failure: non-zero exit, no panic, a message on stderr that
/// contains every one of `words` (case-insensitive), nothing on stdout after the
/// header lines.
fn assert_fails(o: &Output, words: &[&str], what: &str) {
    let err = stderr(o);
    assert!(!o.status.success(), "{what}: exit status {:?} should be a failure\nstderr: {err}", o.status);
    assert_ne!(o.status.code(), Some(101), "{what}: exit code 101 is Rust's panic code\nstderr: {err}");
    assert!(!err.contains("panicked"), "{what}: panicked\nstderr: {err}");
    assert!(!err.contains("RUST_BACKTRACE"), "{what}: panicked\nstderr: {err}");
    let lower = err.to_lowercase();
    for w in words {
        assert!(lower.contains(&w.to_lowercase()), "{what}: stderr does not mention {w:?}\nstderr: {err}");
    }
    assert!(!stdout(o).contains("ret value"), "{what}: printed a result anyway\nstdout: {}", stdout(o));
}
