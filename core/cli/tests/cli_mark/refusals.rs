//! Files that score 0 without a call, what cannot be marked at all, and the
//! sandbox that is required unless waived.

use crate::{fixture, frame_file, mark, mark_with, num, report, scratch_file, small_dataset, stderr, stdout};
use siftlab_core::json::{self, Json};
use siftlab_mark::MAX_SOURCE_BYTES;
use std::fs;
use std::path::Path;
use std::process::{Command, Output};

/// A file that scores 0 without a call: non-zero exit, the reason on
/// stderr and in the report, no panic.
fn assert_zero(o: &Output, code: &str, words: &[&str]) {
    let (out, err) = (stdout(o), stderr(o));
    assert_eq!(o.status.code(), Some(1), "{code}: {out}\n{err}");
    assert!(!err.contains("panicked"), "{err}");
    for w in words {
        assert!(err.contains(w), "{code}: stderr lacks {w:?}: {err}");
    }
    let r = json::parse(&out).unwrap_or_else(|e| panic!("{code}: not JSON ({e}): {out}"));
    assert_eq!(num(&r, "total"), 0.0);
    assert_eq!(r.get("rejection").and_then(|j| j.get("code")).and_then(Json::as_str), Some(code), "{out}");
}

#[test]
fn files_that_score_zero() {
    let o = mark(&fixture("nonascii"), &["--json"]);
    assert_zero(&o, "not_ascii", &["line 15, column 12", "'é' (U+00E9)", "printable ASCII"]);
    let r = report(&o);
    assert_eq!(r.get("rejection").and_then(|j| j.get("line")).and_then(Json::as_i64), Some(15));
    assert_zero(&mark(&fixture("syntax"), &["--json"]), "syntax", &["SyntaxError", "line 32"]);
    assert_zero(&mark(&fixture("imports"), &["--json"]), "import", &["scipy"]);
    assert_zero(&mark(&scratch_file("empty-file", b""), &["--json"]), "empty", &["empty"]);
    assert_zero(&mark(&scratch_file("blank-file", b"\n  \n"), &["--json"]), "empty", &["empty"]);
    let big = vec![b'#'; MAX_SOURCE_BYTES + 1];
    assert_zero(&mark(&scratch_file("big-file", &big), &["--json"]), "too_large", &["1000001 bytes", "limit"]);
    // A binary file: a PNG frame under the name.
    let png = fs::read(frame_file(small_dataset(), 0)).unwrap();
    assert_zero(&mark(&scratch_file("binary-file", &png), &["--json"]), "binary", &["not a Python text file"]);
    // The text report says it too.
    let o = mark(&fixture("nonascii"), &[]);
    assert!(stdout(&o).contains("scores 0: the file is not printable ASCII: line 15, column 12"), "{}", stdout(&o));
}

#[test]
fn what_cannot_be_marked_exits_2() {
    let o = mark(Path::new("no/such/vision_tasks.py"), &[]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("cannot read no/such/vision_tasks.py"), "{}", stderr(&o));
    let o = mark_with(&fixture("good"), &["-n", "1"], &[("SIFTLAB_PYTHON", "/no/such/python3")]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("/no/such/python3 not found"), "{}", stderr(&o));
    let o = Command::new(env!("CARGO_BIN_EXE_siftlab"))
        .args(["-d", "/no/such/MyKITTI", "mark"])
        .arg(fixture("good"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("dataset folder /no/such/MyKITTI does not exist"), "{}", stderr(&o));
    assert!(!stderr(&o).contains("panicked"));
}

/// `--no-sandbox` runs the file as a plain child and says so; without
/// bubblewrap the marker refuses (exit 2) and names the way out.
#[test]
fn the_sandbox_is_required_unless_waived() {
    let o = mark_with(&fixture("good"), &["-n", "1", "--no-sandbox"], &[]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(stderr(&o).contains("--no-sandbox: the file runs with your own rights"), "{}", stderr(&o));
    assert!(stderr(&o).contains("NOT sandboxed"), "{}", stderr(&o));
    let o = mark_with(&fixture("good"), &["-n", "1"], &[]);
    assert!(stderr(&o).contains("sandboxed (bubblewrap)"), "{}", stderr(&o));
    // No bwrap on the PATH (python3 named by its own path): refused, nothing run.
    let probe = Command::new("python3")
        .args(["-c", "import os, sys; print(os.path.realpath(sys.executable))"])
        .output()
        .expect("python3");
    let python = String::from_utf8_lossy(&probe.stdout).trim().to_string();
    let empty = std::env::temp_dir().join(format!("siftlab-no-bwrap-{}", std::process::id()));
    fs::create_dir_all(&empty).unwrap();
    // SIFTLAB_SANDBOX=bubblewrap: nothing weaker is taken.
    let path = ("PATH", empty.to_str().unwrap());
    let o = mark_with(
        &fixture("good"),
        &["-n", "1"],
        &[path, ("SIFTLAB_PYTHON", &python), ("SIFTLAB_SANDBOX", "bubblewrap")],
    );
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    for w in ["no usable sandbox", "bubblewrap", "--no-sandbox"] {
        assert!(stderr(&o).contains(w), "lacks {w:?}: {}", stderr(&o));
    }
    assert!(stdout(&o).is_empty(), "{}", stdout(&o));
    // Otherwise, as root (a platform's container), the container tier runs
    // the file with an interpreter every user may run; not as root, refused.
    let o = mark_with(&fixture("good"), &["-n", "1"], &[path, ("SIFTLAB_PYTHON", "/usr/bin/python3")]);
    // SAFETY: geteuid has no preconditions.
    if unsafe { libc::geteuid() } == 0 {
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
        assert!(stderr(&o).contains("sandboxed (container tier"), "{}", stderr(&o));
    } else {
        assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
        assert!(stderr(&o).contains("--no-sandbox"), "{}", stderr(&o));
    }
    let _ = fs::remove_dir_all(&empty);
}
