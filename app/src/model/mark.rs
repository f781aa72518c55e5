//! "Mark my code" as plain logic: the view's state (in the link), the limits
//! of its inputs and the marking's time limits (the lab's: 10 s a call, 300 s a task).

use leptos::prelude::*;

/// The view's state: the cases' seed and how many per task (`mark`, `mn`).
#[derive(Clone, Copy)]
pub struct MarkState {
    pub seed: RwSignal<u64>,
    pub n: RwSignal<u32>,
}

impl MarkState {
    pub fn new() -> Self {
        MarkState { seed: RwSignal::new(0), n: RwSignal::new(DEFAULT_CASES) }
    }
}

impl Default for MarkState {
    fn default() -> Self {
        Self::new()
    }
}

/// Cases per task when none are asked for (the lab's automarker: 25).
pub const DEFAULT_CASES: u32 = siftlab_mark::DEFAULT_CASES as u32;
/// At most this many cases per task from the link or the box.
pub const MAX_CASES: u32 = 200;
/// The reference workload's time (`www/mark-worker.js`, `REFERENCE`: the
/// median of three runs after a warm-up) on the machine the browser's
/// limits take for the lab's: Chromium 156 on the 2-core build machine, the
/// lowest of its `app/mark.test.mjs` runs (84 ms at load average 9; 275-880
/// ms while the machine was shared with builds at load average 15-50). Its
/// honest dt call took 14-27 times the reference under load, WebKit's 30-45
/// times: at 275 ms WebKit's dt still timed out at a factor of 1.1. A
/// browser that takes longer gets its limits scaled by the ratio.
pub const REFERENCE_NOMINAL_MS: f64 = 85.0;
/// Limits are scaled by at most this factor: on a slower machine a
/// time-out cannot be told from the machine (`too_slow_here`), and an
/// endless loop is still stopped within 2 × 10 s × this. WebKit measured
/// up to 4.2× (at 200 ms nominal) on the shared build machine.
pub const SPEED_CAP: f64 = 8.0;
/// Starting Python (Pyodide, ~12 MB the first time) may take this long.
pub const START_LIMIT_MS: i32 = 120_000;
