//! One marking, as a state machine with no I/O: the loop over the cases,
//! the pairs sent once per Python process, the limits and budgets, the
//! restarts and the error policy. The CLI (`siftlab mark`, a sandboxed
//! python3) and the app (a Pyodide worker) are transports: they start a
//! harness when told, send each line within its limit, and hand back the
//! reply line, a time-out or a crash. The same file, seed and n give the
//! same table through either (docs/marking.md, "One session").
//!
//! ```text
//! let mut s = Session::new(source, seed, n, &frames);
//! loop {
//!     match s.next(&mut pairs)? {
//!         Step::Start => { /* kill any harness, start a fresh one */ }
//!         Step::Send { id, line, limit, .. } => { /* send; wait for the reply to id */ s.outcome(o) }
//!         Step::Done(marks) => break,
//!     }
//! }
//! ```

use crate::cases::{plan, Case, Task};
use crate::diagnose::{failed_call, judge, CaseResult, Diagnosis};
use crate::protocol::{call_message, load_message, pair_message, parse_line, with_id, ErrorKind, HarnessLine, Pair};
use crate::protocol::{Reply, MAX_MESSAGE_CHARS};
use crate::reference::{reference, Expected};
use crate::report::Marks;
use crate::source::Rejection;
use siftlab_core::error::Result;
use std::collections::BTreeSet;

/// The lab's limits, in seconds of the call's CPU time (natively; the
/// browser measures wall time), and the wall-clock backstop's factor.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Limits {
    /// One call (the lab: 10 s).
    pub call: f64,
    /// All the calls of one task, reloads after a time-out included (300 s).
    pub task: f64,
    /// Loading the file: Python's start, numpy, the module and
    /// `VisionTasks()` (60 s of wall time, as the reference marker allows).
    pub load: f64,
    /// A pair's frames taken in by the harness: its own work, but in the
    /// file's interpreter, so patchable; wall time (15 s: an honest pair
    /// takes under 0.1 s), charged to the task like a reload.
    pub pair: f64,
    /// A request still running after `wall_factor` × its limit of wall time
    /// ends, whatever its CPU time (a stopped or sleeping process).
    pub wall_factor: f64,
    /// Set where only wall time can be measured (the browser): the limits
    /// then follow the machine's speed and a call over its limit is re-run
    /// once before it counts. `None` natively: CPU time needs neither.
    pub wall_clock: Option<WallClock>,
}

/// How limits measured in wall time follow the machine (docs/marking.md,
/// "Mark my code"): every limit is scaled by the speed the transport
/// measured ([`Session::measured`]), never below the lab's and at most by
/// `cap`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WallClock {
    /// The largest factor: on a machine slower than this a time-out cannot
    /// be told from the machine ([`Diagnosis::TooSlowHere`]), and an endless
    /// loop still ends within `call` × `cap` seconds a try.
    pub cap: f64,
}

impl Default for Limits {
    fn default() -> Limits {
        Limits { call: 10.0, task: 300.0, load: 60.0, pair: 15.0, wall_factor: 3.0, wall_clock: None }
    }
}

impl Limits {
    /// The browser's: the lab's limits in wall time, scaled by the speed.
    pub fn wall_clock(cap: f64) -> Limits {
        Limits { wall_clock: Some(WallClock { cap }), ..Limits::default() }
    }
}

/// What the transport does next.
#[derive(Debug)]
pub enum Step {
    /// End any running harness (and everything it started) and start a
    /// fresh one with nothing loaded.
    Start,
    /// Send `line` (one line, its request `id` inside), then read lines
    /// until [`Session::is_reply`]; answer knn requests on the way. Report
    /// the end with [`Session::outcome`]: the reply, or a time-out once the
    /// request has used `limit` seconds (or `limit` × `wall_factor` of wall
    /// time), or a crash.
    Send { id: u64, line: String, limit: f64, op: &'static str, pair: Option<u32> },
    /// The marking is over.
    Done(Marks),
}

/// How a request ended.
#[derive(Clone, Debug, PartialEq)]
pub enum Outcome {
    /// The reply line and the seconds the request used.
    Reply(String, f64),
    /// Over its limit: the harness was ended. The seconds used.
    Timeout(f64),
    /// The harness ended (or could not be reached): why, and the seconds
    /// used. The text is the transport's; the session escapes it.
    Crashed(String, f64),
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Waiting {
    Nothing,
    Load,
    Pair(u32),
    Call,
}

/// A marking in progress.
pub struct Session {
    source: String,
    seed: u64,
    n: usize,
    cases: Vec<Case>,
    limits: Limits,
    next_case: usize,
    results: Vec<CaseResult>,
    /// Seconds used by each task (in `Task::ALL` order).
    spent: [f64; 4],
    /// A harness is running with the file loaded.
    loaded: bool,
    /// A harness was started and not yet loaded.
    started: bool,
    /// Loaded once already (a later load is a reload after a failure).
    ever_loaded: bool,
    /// Pairs the running harness holds.
    sent: BTreeSet<u32>,
    waiting: Waiting,
    request: u64,
    /// The current case's reference value.
    expected: Option<Expected>,
    rejection: Option<Rejection>,
    /// The machine's last measured time for the reference workload over its
    /// nominal time (1: as fast as the machine the limits assume).
    speed: f64,
    /// The current call went over its limit once and is being re-run; the
    /// speed measured before that first try.
    retried: Option<f64>,
    /// Lines dropped because they were no reply (shown on stderr by the CLI).
    pub stray_lines: usize,
}

/// Where the session finds a case's frame pair (SIFT of both frames).
pub trait Pairs {
    /// The pair of FRAME_ID `frame` (FRAME_ID-1 → FRAME_ID).
    fn pair(&mut self, frame: u32) -> Result<&Pair>;
}

impl Session {
    /// A marking of `source` (already accepted by `check_source`): the cases
    /// of `seed`, `n` per task, on the FRAME_IDs `frames`.
    pub fn new(source: &str, seed: u64, n: usize, frames: &[u32], limits: Limits) -> Session {
        Session {
            source: source.to_string(),
            seed,
            n,
            cases: plan(seed, n, frames),
            limits,
            next_case: 0,
            results: Vec::new(),
            spent: [0.0; 4],
            loaded: false,
            started: false,
            ever_loaded: false,
            sent: BTreeSet::new(),
            waiting: Waiting::Nothing,
            request: 0,
            expected: None,
            rejection: None,
            speed: 1.0,
            retried: None,
            stray_lines: 0,
        }
    }

    /// The cases, in the order they are marked.
    pub fn cases(&self) -> &[Case] {
        &self.cases
    }

    /// The results so far.
    pub fn results(&self) -> &[CaseResult] {
        &self.results
    }

    /// The case being marked (`None` before the first and after the last).
    pub fn current(&self) -> Option<&Case> {
        self.cases.get(self.next_case).filter(|_| self.next_case < self.cases.len())
    }

    /// Seconds `task`'s calls have used.
    pub fn spent(&self, task: Task) -> f64 {
        self.spent[task_index(task)]
    }

    /// Whether `line` is the reply to request `id` (else the transport
    /// answers it if it is a knn request, or drops it).
    pub fn is_reply(line: &str, id: u64) -> bool {
        matches!(parse_line(line, id), HarnessLine::Reply(_))
    }

    /// The transport measured the machine's speed (its time for the
    /// reference workload over the nominal time); with
    /// [`Limits::wall_clock`] the limits follow it. A factor that is not a
    /// positive number counts as the slowest allowed (the cap).
    pub fn measured(&mut self, speed: f64) {
        self.speed = if speed.is_finite() && speed > 0.0 { speed } else { f64::INFINITY };
    }

    /// The last measured speed factor (1 until one is measured).
    pub fn speed(&self) -> f64 {
        self.speed
    }

    /// What the limits are multiplied by now: 1 natively; in wall time the
    /// speed, never below 1 (the lab's) and at most the cap.
    pub fn scale(&self) -> f64 {
        match self.limits.wall_clock {
            Some(w) => self.speed.clamp(1.0, w.cap.max(1.0)),
            None => 1.0,
        }
    }

    /// Whether the current call went over its limit once and is to be run
    /// again (the next [`Step::Start`] is for its re-run).
    pub fn retrying(&self) -> bool {
        self.retried.is_some()
    }

    /// A call's limit now, in seconds (the lab's 10 s, scaled).
    pub fn call_limit(&self) -> f64 {
        self.limits.call * self.scale()
    }

    /// The transport started a fresh harness (after [`Step::Start`]).
    pub fn started(&mut self) {
        self.started = true;
        self.loaded = false;
        self.sent.clear();
    }

    fn send(&mut self, message: &str, limit: f64, waiting: Waiting) -> Step {
        self.request += 1;
        self.waiting = waiting;
        let (op, pair) = match waiting {
            Waiting::Load => ("load", None),
            Waiting::Pair(f) => ("pair", Some(f)),
            _ => ("call", None),
        };
        Step::Send { id: self.request, line: with_id(self.request, message), limit, op, pair }
    }

    /// What to do next.
    pub fn next<P: Pairs>(&mut self, pairs: &mut P) -> Result<Step> {
        loop {
            if let Some(r) = &self.rejection {
                return Ok(Step::Done(Marks::rejected(self.seed, self.n, r.clone())));
            }
            let Some(&case) = self.cases.get(self.next_case) else {
                return Ok(Step::Done(Marks::new(self.seed, self.n, std::mem::take(&mut self.results))));
            };
            let t = task_index(case.task());
            if self.expected.is_none() {
                let p = pairs.pair(case.frame())?;
                self.expected = Some(reference(&case, &p.prev, &p.cur)?);
            }
            if self.spent[t] >= self.limits.task * self.scale() {
                // The reference marker: once a task's 300 s are used, its
                // remaining calls are errors without running.
                let d = Diagnosis::TaskTimeLimit { seconds: self.limits.task };
                self.finish_case(|e| failed_call(&case, e, d, 0.0));
                continue;
            }
            if !self.started && !self.loaded {
                return Ok(Step::Start);
            }
            if !self.loaded {
                let limit = self.limit_for(t, self.limits.load * self.scale());
                let msg = load_message(&self.source);
                return Ok(self.send(&msg, limit, Waiting::Load));
            }
            let frame = case.frame();
            if !self.sent.contains(&frame) {
                let p = pairs.pair(frame)?;
                let msg = pair_message(p.id, &p.prev, &p.cur);
                let limit = self.limit_for(t, self.limits.pair * self.scale());
                return Ok(self.send(&msg, limit, Waiting::Pair(frame)));
            }
            let limit = self.limit_for(t, self.call_limit());
            let msg = call_message(&case, frame, self.expected.as_ref().expect("set above"));
            return Ok(self.send(&msg, limit, Waiting::Call));
        }
    }

    /// `limit`, cut to what is left of the task's budget once the file has
    /// been loaded (the first load is no task's).
    fn limit_for(&self, t: usize, limit: f64) -> f64 {
        if self.ever_loaded {
            limit.min(self.limits.task * self.scale() - self.spent[t])
        } else {
            limit
        }
    }

    fn finish_case(&mut self, f: impl FnOnce(&Expected) -> CaseResult) {
        let e = self.expected.take().expect("a case's reference is computed before it is judged");
        self.results.push(f(&e));
        self.next_case += 1;
        self.retried = None;
    }

    /// The harness is no longer usable: the next step starts another.
    fn restart(&mut self) {
        self.started = false;
        self.loaded = false;
        self.sent.clear();
    }

    /// How the request of the last [`Step::Send`] ended. `pairs` is the
    /// store [`Session::next`] read (for the judgement's diagnoses).
    pub fn outcome<P: Pairs>(&mut self, outcome: Outcome, pairs: &mut P) -> Result<()> {
        let waiting = std::mem::replace(&mut self.waiting, Waiting::Nothing);
        let Some(&case) = self.cases.get(self.next_case) else {
            return Ok(());
        };
        let t = task_index(case.task());
        let used = match &outcome {
            Outcome::Reply(_, s) | Outcome::Timeout(s) | Outcome::Crashed(_, s) => *s,
        };
        let over = match &outcome {
            Outcome::Timeout(_) => true,
            Outcome::Reply(..) => used > self.call_limit(),
            Outcome::Crashed(..) => false,
        };
        if waiting == Waiting::Call && over && self.limits.wall_clock.is_some() && self.retried.is_none() {
            // In wall time the machine may have been busy: the call is run
            // again in a fresh harness (after a new speed measurement)
            // before it counts, and the first try is charged to no task.
            self.retried = Some(self.speed);
            self.restart();
            return Ok(());
        }
        // Reloads and pairs after the first load count against the task,
        // as its calls do.
        if self.ever_loaded || waiting == Waiting::Call {
            self.spent[t] += used;
        }
        let reply = match &outcome {
            Outcome::Reply(line, _) => match parse_line(line, self.request) {
                HarnessLine::Reply(r) => Some(r),
                HarnessLine::Knn | HarnessLine::Stray(_) => {
                    self.stray_lines += 1;
                    None
                }
            },
            _ => None,
        };
        let crash = |why: &str| Diagnosis::Crashed(crate::escape::escaped(why, MAX_MESSAGE_CHARS));
        match waiting {
            Waiting::Nothing => {}
            Waiting::Load => {
                let first = !self.ever_loaded;
                let failed = match (&outcome, reply) {
                    (_, Some(Reply::Ok { .. })) => {
                        self.loaded = true;
                        self.ever_loaded = true;
                        return Ok(());
                    }
                    (_, Some(Reply::Error { message, kind })) if first && kind != ErrorKind::Protocol => {
                        self.rejection = Some(Rejection::Load { kind, message });
                        return Ok(());
                    }
                    (Outcome::Timeout(s), _) if first => {
                        self.rejection = Some(Rejection::LoadTimeout { seconds: *s });
                        return Ok(());
                    }
                    (Outcome::Timeout(_), _) => Diagnosis::Timeout { seconds: self.limits.load },
                    (_, Some(Reply::Error { message, .. })) => {
                        crash(&format!("the file failed to load again: {message}"))
                    }
                    (Outcome::Crashed(why, _), _) => crash(&format!("while loading the file: {why}")),
                    (Outcome::Reply(..), None) => crash("the harness's reply to loading the file was unreadable"),
                };
                if first {
                    // No mark can come from a file that never loaded.
                    self.rejection = Some(Rejection::Load { kind: ErrorKind::Runtime, message: failed.describe() });
                    return Ok(());
                }
                self.restart();
                self.finish_case(|e| failed_call(&case, e, failed, used));
            }
            Waiting::Pair(frame) => match (&outcome, reply) {
                (_, Some(Reply::Ok { .. })) => {
                    self.sent.insert(frame);
                }
                (o, r) => {
                    let d = match (o, r) {
                        (Outcome::Timeout(_), _) => Diagnosis::Timeout { seconds: self.limits.pair },
                        (Outcome::Crashed(why, _), _) => crash(why),
                        (_, Some(Reply::Error { message, .. })) => {
                            crash(&format!("the harness refused the frames: {message}"))
                        }
                        _ => crash("the harness's reply to the frames was unreadable"),
                    };
                    self.restart();
                    self.finish_case(|e| failed_call(&case, e, d, used));
                }
            },
            Waiting::Call => {
                let timeout = self.timeout_diagnosis();
                let (result, restart) = match (&outcome, reply) {
                    // Over the limit by the lab's measure, even if it returned.
                    (Outcome::Reply(..), Some(_)) if over => (Err(timeout), false),
                    (Outcome::Reply(..), Some(Reply::Error { message, kind: ErrorKind::Protocol })) => {
                        // The harness lives in the student's interpreter: a
                        // refusal is the call's error, and the process is
                        // not trusted further.
                        (Err(Diagnosis::Runtime { message, hint: Some("the harness refused the call") }), true)
                    }
                    (Outcome::Reply(..), Some(reply)) => (Ok(reply), false),
                    (Outcome::Reply(..), None) => (Err(crash("its reply was unreadable")), true),
                    (Outcome::Timeout(_), _) => (Err(timeout), true),
                    (Outcome::Crashed(why, _), _) => (Err(crash(why)), true),
                };
                if restart {
                    self.restart();
                }
                match result {
                    Ok(reply) => {
                        let p = pairs.pair(case.frame())?;
                        let (prev, cur) = (p.prev.clone(), p.cur.clone());
                        self.finish_case(|e| judge(&case, e, &reply, &prev, &cur, used));
                    }
                    Err(d) => self.finish_case(|e| failed_call(&case, e, d, used)),
                }
            }
        }
        Ok(())
    }
}

impl Session {
    /// A call over its limit: a time-out, or in wall time on a machine
    /// slower than the cap (on either try) a case that cannot be told.
    fn timeout_diagnosis(&self) -> Diagnosis {
        match self.limits.wall_clock {
            Some(w) if self.speed.max(self.retried.unwrap_or(0.0)) > w.cap => {
                Diagnosis::TooSlowHere { limit: self.call_limit(), speed: self.speed.max(self.retried.unwrap_or(0.0)) }
            }
            _ => Diagnosis::Timeout { seconds: self.limits.call },
        }
    }
}

fn task_index(task: Task) -> usize {
    Task::ALL.iter().position(|&t| t == task).unwrap_or(0)
}

#[cfg(test)]
#[path = "session_tests.rs"]
mod tests;
