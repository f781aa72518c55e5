//! The session's tests: a scripted transport answers each step.

use super::*;
use siftlab_core::sift::{Features, KeyPoint};

struct Fake(Vec<Pair>);

impl Pairs for Fake {
    fn pair(&mut self, frame: u32) -> Result<&Pair> {
        if !self.0.iter().any(|p| p.id == frame) {
            let f = |seed: usize| Features {
                keypoints: vec![KeyPoint { x: 5.0, y: 7.0, size: 2.0, angle: 0.0, response: 0.1, octave: 0 }; 1500],
                descriptors: (0..1500)
                    .map(|i| std::array::from_fn(|j| ((i * 31 + j * 7 + seed) % 200) as u8))
                    .collect(),
            };
            self.0.push(Pair { id: frame, prev: f(frame as usize), cur: f(frame as usize + 3) });
        }
        Ok(self.0.iter().find(|p| p.id == frame).expect("inserted"))
    }
}

/// Drives a session with `reply(step_line, id, limit) -> Outcome`, the
/// transport measuring `speed(start)` at each start (none if it returns
/// `None`, as the CLI).
fn drive_at(
    limits: Limits,
    mut speed: impl FnMut(usize) -> Option<f64>,
    mut reply: impl FnMut(&str, u64, f64) -> Outcome,
) -> (Marks, usize, usize) {
    let mut s = Session::new("class VisionTasks: pass", 1, 2, &[1, 2, 3], limits);
    let mut pairs = Fake(Vec::new());
    let (mut starts, mut sends) = (0, 0);
    loop {
        match s.next(&mut pairs).unwrap() {
            Step::Start => {
                starts += 1;
                if let Some(f) = speed(starts) {
                    s.measured(f);
                }
                s.started();
            }
            Step::Send { id, line, limit, .. } => {
                sends += 1;
                let o = reply(&line, id, limit);
                s.outcome(o, &mut pairs).unwrap();
            }
            Step::Done(m) => return (m, starts, sends),
        }
    }
}

/// Drives a session with `reply(step_line, id) -> Outcome`.
fn drive(limits: Limits, mut reply: impl FnMut(&str, u64) -> Outcome) -> (Marks, usize, usize) {
    drive_at(limits, |_| None, |line, id, _| reply(line, id))
}

#[test]
fn stray_lines_time_outs_and_crashes_never_end_the_marking() {
    let ok = |id: u64| format!("{{\"req\": {id}, \"ok\": true}}");
    let (m, starts, _) = drive(Limits::default(), |line, id| {
        if line.contains("\"op\": \"call\"") {
            if line.contains("\"fn\": \"dt\"") {
                Outcome::Timeout(10.0)
            } else if line.contains("\"fn\": \"nn\"") {
                Outcome::Crashed("signal 9".into(), 0.5)
            } else if line.contains("\"fn\": \"nndr\"") {
                // A reply for another request, then garbage: both dropped.
                Outcome::Reply(format!("{{\"req\": {}, \"ok\": []}}", id + 1), 0.1)
            } else {
                Outcome::Reply("\u{1b}[2J not json".into(), 0.1)
            }
        } else {
            Outcome::Reply(ok(id), 0.01)
        }
    });
    assert!(m.rejection.is_none());
    assert_eq!(m.tasks.iter().map(|t| (t.calls, t.errors)).collect::<Vec<_>>(), [(2, 2); 4]);
    // One start, then one after each of the 8 failed calls but the last.
    assert_eq!(starts, 8);
    let text = crate::report::report_text(&m);
    assert!(crate::escape::is_clean(&text), "{text}");
}

#[test]
fn budgets_count_reloads_and_cut_the_last_call() {
    let mut limits_seen = Vec::new();
    let limits = Limits { task: 25.0, ..Limits::default() };
    let (m, _, _) = drive(limits, |line, id| {
        if line.contains("\"op\": \"load\"") {
            // Every reload after the first takes 8 s.
            limits_seen.push(("load", id));
            Outcome::Reply(format!("{{\"req\": {id}, \"ok\": true}}"), if id == 1 { 1.0 } else { 8.0 })
        } else if line.contains("\"op\": \"call\"") && line.contains("\"fn\": \"dt\"") {
            Outcome::Timeout(10.0)
        } else if line.contains("\"op\": \"call\"") {
            Outcome::Reply(format!("{{\"req\": {id}, \"error\": \"x\", \"kind\": \"runtime\"}}"), 0.1)
        } else {
            Outcome::Reply(format!("{{\"req\": {id}, \"ok\": true}}"), 0.0)
        }
    });
    // dt: 10 s (time-out) + 8 s (reload) + 10 s: over 25 s, no third call.
    let dt: Vec<_> = m
        .results
        .iter()
        .filter(|r| r.case.task() == Task::Dt)
        .map(|r| r.diagnosis.as_ref().map(|d| d.code()))
        .collect();
    assert_eq!(dt, [Some("timeout"), Some("timeout")]);
    assert!(m.tasks.iter().all(|t| t.calls == 2));
}

#[test]
fn a_first_load_that_fails_rejects_the_file() {
    let (m, _, sends) = drive(Limits::default(), |_, id| {
        Outcome::Reply(format!("{{\"req\": {id}, \"error\": \"No module named 'yaml'\", \"kind\": \"import\"}}"), 0.1)
    });
    assert_eq!(m.rejection.as_ref().map(|r| r.code()), Some("import"));
    assert_eq!(sends, 1);
    let (m, _, _) = drive(Limits::default(), |_, _| Outcome::Timeout(60.0));
    assert_eq!(m.rejection.as_ref().map(|r| r.code()), Some("load_timeout"));
}

fn ok(id: u64) -> Outcome {
    Outcome::Reply(format!("{{\"req\": {id}, \"ok\": true}}"), 0.01)
}

fn runtime_error(id: u64, secs: f64) -> Outcome {
    Outcome::Reply(format!("{{\"req\": {id}, \"error\": \"boom\", \"kind\": \"runtime\"}}"), secs)
}

fn codes(m: &Marks, task: Task) -> Vec<Option<&'static str>> {
    m.results.iter().filter(|r| r.case.task() == task).map(|r| r.diagnosis.as_ref().map(|d| d.code())).collect()
}

#[test]
fn in_wall_time_a_call_over_its_limit_is_run_again_before_it_counts() {
    // Speed 1.5: every limit 1.5 x the lab's. Each dt call times out on its
    // first try only, nn's first call returns late (over 15 s) once; the
    // re-runs answer (a runtime error, so that the answer is judged).
    let mut dt_tries = 0;
    let mut nn_late = false;
    let mut limits_seen = Vec::new();
    let (m, starts, sends) = drive_at(
        Limits::wall_clock(4.0),
        |_| Some(1.5),
        |line, id, limit| {
            if !line.contains("\"op\": \"call\"") {
                return ok(id);
            }
            limits_seen.push(limit);
            if line.contains("\"fn\": \"dt\"") {
                dt_tries += 1;
                if dt_tries % 2 == 1 {
                    return Outcome::Timeout(limit);
                }
            } else if line.contains("\"fn\": \"nn\"") && !nn_late {
                nn_late = true;
                return runtime_error(id, 15.5);
            }
            runtime_error(id, 0.1)
        },
    );
    assert_eq!(dt_tries, 4, "each of the 2 dt calls ran twice");
    assert_eq!(codes(&m, Task::Dt), [Some("runtime_error"); 2]);
    assert_eq!(codes(&m, Task::Nn), [Some("runtime_error"); 2]);
    assert!(limits_seen.iter().all(|&l| l == 15.0), "{limits_seen:?}");
    // One start, one per re-run (2 dt, 1 nn); 8 calls + 3 re-runs, each
    // start followed by a load and its pairs.
    assert_eq!(starts, 4);
    assert!(sends > 11, "{sends}");
    // Only the counted tries are charged: dt's two 0.1 s answers and the
    // reloads (0.01 s each) after the time-outs.
    assert!(m.results.iter().filter(|r| r.case.task() == Task::Dt).all(|r| r.seconds == 0.1));
}

#[test]
fn in_wall_time_an_endless_loop_is_still_a_time_out_on_a_normal_machine() {
    let mut dt_limits = Vec::new();
    let (m, starts, _) = drive_at(
        Limits::wall_clock(4.0),
        |start| Some(if start == 1 { 0.7 } else { 2.0 }),
        |line, id, limit| {
            if line.contains("\"op\": \"call\"") && line.contains("\"fn\": \"dt\"") {
                dt_limits.push(limit);
                Outcome::Timeout(limit)
            } else if line.contains("\"op\": \"call\"") {
                runtime_error(id, 0.1)
            } else {
                ok(id)
            }
        },
    );
    // A faster machine keeps the lab's 10 s; a slower one gets its factor.
    assert_eq!(dt_limits, [10.0, 20.0, 20.0, 20.0]);
    assert_eq!(codes(&m, Task::Dt), [Some("timeout"); 2]);
    assert_eq!(m.tasks[0].errors, 2);
    assert_eq!(starts, 5, "a start for each try after a time-out");
    // Natively nothing is re-run nor scaled.
    let mut native = Vec::new();
    let (m, _, _) = drive_at(
        Limits::default(),
        |_| Some(3.0),
        |line, id, limit| {
            if line.contains("\"fn\": \"dt\"") {
                native.push(limit);
                Outcome::Timeout(limit)
            } else {
                ok(id)
            }
        },
    );
    assert_eq!(native, [10.0, 10.0]);
    assert_eq!(codes(&m, Task::Dt), [Some("timeout"); 2]);
}

#[test]
fn past_the_cap_a_time_out_is_too_slow_to_tell_and_counts_as_an_error() {
    // The first try on a machine at the cap, the re-run measured past it.
    let mut dt_limits = Vec::new();
    let (m, _, _) = drive_at(
        Limits::wall_clock(4.0),
        |start| Some(if start == 1 { 4.0 } else { 6.5 }),
        |line, id, limit| {
            if line.contains("\"op\": \"call\"") && line.contains("\"fn\": \"dt\"") {
                dt_limits.push(limit);
                Outcome::Timeout(limit)
            } else if line.contains("\"op\": \"call\"") {
                runtime_error(id, 0.1)
            } else {
                ok(id)
            }
        },
    );
    assert_eq!(dt_limits, [40.0; 4], "capped at 4 x 10 s");
    assert_eq!(codes(&m, Task::Dt), [Some("too_slow_here"); 2]);
    assert_eq!((m.tasks[0].errors, m.tasks[0].marks), (2, 0.0));
    let d = m.results[0].diagnosis.as_ref().unwrap().describe();
    assert!(d.contains("6.5x") && d.contains("40 s") && d.contains("siftlab mark"), "{d}");
    // A speed that is no number is taken as past the cap.
    let mut s = Session::new("x", 1, 1, &[1], Limits::wall_clock(4.0));
    s.measured(f64::NAN);
    assert_eq!(s.call_limit(), 40.0);
    s.measured(0.25);
    assert_eq!(s.call_limit(), 10.0);
}
