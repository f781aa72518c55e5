//! "Mark my code" as plain logic: the limits of the view's inputs and the
//! marking's time limits (the lab's: 10 s a call, 300 s a task).

/// Cases per task when none are asked for (the lab's automarker: 25).
pub const DEFAULT_CASES: u32 = siftlab_mark::DEFAULT_CASES as u32;
/// At most this many cases per task from the link or the box.
pub const MAX_CASES: u32 = 200;
/// The lab's limits, in ms.
pub const CALL_LIMIT_MS: i32 = 10_000;
pub const TASK_LIMIT_MS: f64 = 300_000.0;
/// Starting Python (Pyodide, ~12 MB the first time) may take this long.
pub const START_LIMIT_MS: i32 = 120_000;
