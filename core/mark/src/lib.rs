//! Marking a student's `vision_tasks.py` as the lab's automarker does
//! (docs/marking.md): the cases from a seed, the messages to and from the
//! Python harness (`py/siftlab_harness.py` of this crate), the reference values,
//! the comparison and diagnosis of each case, the 20 marks and the report.
//! No I/O here: the CLI (`siftlab mark`) and the app's worker run the
//! harness and carry the messages.
//!
//! A marking is a [`Session`] (the loop, limits and restarts) driven by a
//! transport; underneath, in order:
//! 1. [`check_source`] on the file's bytes (a [`Rejection`] scores 0:
//!    [`Marks::rejected`]);
//! 2. [`plan`] the cases; send [`load_message`] and read its reply with
//!    [`parse_reply`] (an error is a [`Rejection::Load`]);
//! 3. for each case: its [`reference`] value on its pair; the pair sent
//!    once with [`pair_message`]; [`call_message`]; then read lines with
//!    [`parse_line`] until the reply, answering each knn request with
//!    [`knn_answer`]; [`judge`] the reply (or [`failed_call`] for a time-out
//!    or a crash);
//! 4. [`Marks::new`] on the results; [`report_text`] / [`report_json`].

mod b64;
mod cases;
mod diagnose;
mod escape;
mod knn;
mod protocol;
mod pyvalue;
mod reference;
mod report;
mod session;
mod source;
mod summary;

pub use b64::{base64, unbase64};
pub use cases::{frames_needed, markable_frames, plan, py_threshold, Case, Task, DEFAULT_CASES, NUM_FEATURES};
pub use diagnose::{failed_call, judge, CaseResult, Diagnosis, Difference, Status};
pub use escape::{escaped, is_clean};
pub use knn::{knn_answer, knn_answer_until, max_rows};
pub use protocol::{
    call_message, load_message, pair_message, parse_line, parse_reply, with_id, ErrorKind, HarnessLine, Pair, Reply,
    MAX_LINE_BYTES, MAX_MESSAGE_CHARS,
};
pub use pyvalue::{info_type_problem, info_value, PyValue};
pub use reference::{reference, Expected, Got};
pub use report::{report_json, report_text, Marks, TaskMarks};
pub use session::{Limits, Outcome, Pairs, Session, Step, WallClock};
pub use siftlab_core::json::{parse as parse_json, Json};
pub use source::{check_source, Rejection, MAX_SOURCE_BYTES};
pub use summary::{case_link, result_link, summary, Entry as SummaryEntry};

/// The Python side of the marking, as files: the harness and its parts, and
/// the two shims it loads, `cv2` with its parts and `vision_tasks_base`
/// (`py/` of this crate, every file of it). `siftlab mark` writes them into
/// its sandbox; `www/build` copies the folder into `dist/py/` for the app,
/// whose worker (`www/mark-worker.js`, `FILES`) names them too.
pub const HARNESS_FILES: [(&str, &str); 9] = [
    ("siftlab_harness.py", include_str!("../py/siftlab_harness.py")),
    ("_siftlab_harness_run.py", include_str!("../py/_siftlab_harness_run.py")),
    ("_siftlab_harness_values.py", include_str!("../py/_siftlab_harness_values.py")),
    ("_siftlab_harness_imports.py", include_str!("../py/_siftlab_harness_imports.py")),
    ("cv2.py", include_str!("../py/cv2.py")),
    ("_siftlab_cv2_base.py", include_str!("../py/_siftlab_cv2_base.py")),
    ("_siftlab_cv2_types.py", include_str!("../py/_siftlab_cv2_types.py")),
    ("_siftlab_cv2_descriptors.py", include_str!("../py/_siftlab_cv2_descriptors.py")),
    ("vision_tasks_base.py", include_str!("../py/vision_tasks_base.py")),
];

#[cfg(test)]
mod tests {
    use super::HARNESS_FILES;
    use std::collections::BTreeSet;
    use std::path::Path;

    /// Every file of `py/` is written into the sandbox and loaded by the
    /// browser's worker, and nothing else: a part left out of either would
    /// fail every marking there.
    #[test]
    fn harness_files_are_the_py_folder_and_the_workers_list() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR"));
        let listed: BTreeSet<&str> = HARNESS_FILES.iter().map(|(name, _)| *name).collect();
        assert_eq!(listed.len(), HARNESS_FILES.len(), "a file named twice");
        let on_disk: BTreeSet<String> = std::fs::read_dir(root.join("py"))
            .unwrap()
            .map(|e| e.unwrap().file_name().into_string().unwrap())
            .filter(|name| name.ends_with(".py"))
            .collect();
        assert_eq!(listed, on_disk.iter().map(String::as_str).collect::<BTreeSet<_>>());
        let worker = std::fs::read_to_string(root.join("../../www/mark-worker.js")).unwrap();
        let files = worker.split("const FILES = [").nth(1).and_then(|s| s.split("];").next()).unwrap();
        let in_worker: BTreeSet<&str> =
            files.split(',').map(|f| f.trim().trim_matches('\'')).filter(|f| !f.is_empty()).collect();
        assert_eq!(listed, in_worker, "www/mark-worker.js FILES");
    }
}
