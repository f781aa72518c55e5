//! The marks: per task 0.5 when every call returned a value (no exception,
//! wrong type or time-out) plus 4.5 × the share of correct values, 5 per
//! task, 20 in all; and the report, as text and as JSON.

use crate::cases::{py_threshold, Case, Task};
use crate::diagnose::{CaseResult, Difference, Status};
use crate::source::Rejection;
use siftlab_core::json::{push_f64, push_str};
use std::fmt::Write as _;

/// One task's row of the table.
#[derive(Clone, Debug, PartialEq)]
pub struct TaskMarks {
    pub task: Task,
    pub calls: usize,
    pub correct: usize,
    /// Calls that returned no value (exception, wrong type, time-out).
    pub errors: usize,
    pub marks: f64,
}

/// The whole marking.
#[derive(Clone, Debug, PartialEq)]
pub struct Marks {
    pub seed: u64,
    pub cases_per_task: usize,
    /// Set when the file scores 0 without being run (or could not be loaded).
    pub rejection: Option<Rejection>,
    /// dt, nn, nndr, matching_info.
    pub tasks: Vec<TaskMarks>,
    /// Out of 20.
    pub total: f64,
    /// Every case in the order marked.
    pub results: Vec<CaseResult>,
}

impl Marks {
    /// The marks of the judged cases.
    pub fn new(seed: u64, cases_per_task: usize, results: Vec<CaseResult>) -> Marks {
        let tasks: Vec<TaskMarks> = Task::ALL
            .iter()
            .map(|&task| {
                let of = || results.iter().filter(|r| r.case.task() == task);
                let calls = of().count();
                let correct = of().filter(|r| r.status == Status::Correct).count();
                let errors = of().filter(|r| r.status == Status::Error).count();
                let marks = if calls == 0 {
                    0.0
                } else {
                    (if errors == 0 { 0.5 } else { 0.0 }) + 4.5 * correct as f64 / calls as f64
                };
                TaskMarks { task, calls, correct, errors, marks }
            })
            .collect();
        let total = tasks.iter().map(|t| t.marks).sum();
        Marks { seed, cases_per_task, rejection: None, tasks, total, results }
    }

    /// 0 on every task, for a file refused before any call.
    pub fn rejected(seed: u64, cases_per_task: usize, rejection: Rejection) -> Marks {
        let mut m = Marks::new(seed, cases_per_task, Vec::new());
        m.rejection = Some(rejection);
        m
    }

    /// 20 / 20: every call of every task correct.
    pub fn full(&self) -> bool {
        self.rejection.is_none() && self.tasks.iter().all(|t| t.calls > 0 && t.correct == t.calls && t.errors == 0)
    }
}

/// The table, then each failed case: its call, the expected and returned
/// values (shortened) and the diagnosis.
pub fn report_text(m: &Marks) -> String {
    let mut s = String::new();
    let plural = if m.cases_per_task == 1 { "" } else { "s" };
    let _ = writeln!(s, "seed {}, {} call{plural} per task", m.seed, m.cases_per_task);
    if let Some(r) = &m.rejection {
        let _ = writeln!(s, "\nscores 0: {r}");
    }
    let _ = writeln!(s, "\n{:<15}{:>6}{:>9}{:>8}{:>8}", "task", "calls", "correct", "errors", "marks");
    for t in &m.tasks {
        let _ = writeln!(s, "{:<15}{:>6}{:>9}{:>8}{:>8.2}", t.task.name(), t.calls, t.correct, t.errors, t.marks);
    }
    let _ = writeln!(s, "{:<38}{:>8.2} / 20", "total", m.total);
    let failed: Vec<(usize, &CaseResult)> = numbered(&m.results).filter(|(_, r)| r.status != Status::Correct).collect();
    if !failed.is_empty() {
        let _ = writeln!(s, "\nFailed cases");
        for (i, r) in failed {
            let _ = writeln!(
                s,
                "\n{} {} of {} ({}): {}",
                r.case.task().name(),
                i + 1,
                m.cases_per_task,
                r.status.name(),
                r.case.call_text()
            );
            let _ = writeln!(s, "  expected: {}", r.expected);
            let _ = writeln!(s, "  returned: {}", r.returned);
            if let Some(d) = &r.diagnosis {
                let _ = writeln!(s, "  diagnosis: {}", d.describe());
            }
        }
    }
    s
}

/// Each result with its number within its task.
fn numbered(results: &[CaseResult]) -> impl Iterator<Item = (usize, &CaseResult)> {
    let mut seen = [0usize; 4];
    results.iter().map(move |r| {
        let t = Task::ALL.iter().position(|&t| t == r.case.task()).unwrap_or(0);
        seen[t] += 1;
        (seen[t] - 1, r)
    })
}

/// Marks rounded for JSON (the shares of 25 calls are exact in 4 decimals).
fn round4(v: f64) -> f64 {
    (v * 1e4).round() / 1e4
}

/// The report as one JSON object:
/// `{"seed", "cases_per_task", "total", "full_marks", "rejection", "tasks": [{"task", "calls", "correct",
/// "errors", "marks"}], "cases": [{"task", "index", "frame", "threshold", "strategy", "feature", "differs_at", "status",
/// "seconds", "diagnosis", "diagnosis_text", "expected", "returned"}]}`. `rejection` is null or
/// `{"code", "message"}` (with `line` and `column` for a character the lab does not accept); a case's
/// `strategy` and `feature` are null except for matching_info, `differs_at` (the first query feature whose
/// list differs) is null except for a wrong dt / nn / nndr value, `threshold` is null for nn's None, and
/// `diagnosis`, `expected` and `returned` are null for a correct case.
pub fn report_json(m: &Marks) -> String {
    let mut s = String::new();
    let _ = write!(s, "{{\"seed\": {}, \"cases_per_task\": {}, \"total\": ", m.seed, m.cases_per_task);
    push_f64(&mut s, round4(m.total));
    let _ = write!(s, ", \"full_marks\": {}, \"rejection\": ", m.full());
    match &m.rejection {
        None => s.push_str("null"),
        Some(r) => {
            let _ = write!(s, "{{\"code\": \"{}\", \"message\": ", r.code());
            push_str(&mut s, &r.to_string());
            if let Rejection::NotAscii { line, column, .. } = r {
                let _ = write!(s, ", \"line\": {line}, \"column\": {column}");
            }
            s.push('}');
        }
    }
    s.push_str(", \"tasks\": [");
    for (i, t) in m.tasks.iter().enumerate() {
        if i > 0 {
            s.push_str(", ");
        }
        let _ = write!(
            s,
            "{{\"task\": \"{}\", \"calls\": {}, \"correct\": {}, \"errors\": {}, \"marks\": ",
            t.task.name(),
            t.calls,
            t.correct,
            t.errors
        );
        push_f64(&mut s, round4(t.marks));
        s.push('}');
    }
    s.push_str("], \"cases\": [");
    for (n, (i, r)) in numbered(&m.results).enumerate() {
        s.push_str(if n == 0 { "\n" } else { ",\n" });
        let t = r.case.strategy().threshold();
        let (strategy, feature) = match r.case {
            Case::Info { strategy, feature, .. } => (format!("\"{}\"", strategy.name()), feature.to_string()),
            _ => ("null".into(), "null".into()),
        };
        let differs_at = match &r.difference {
            Some(Difference::Matches { feature, .. }) => feature.to_string(),
            _ => "null".into(),
        };
        let _ = write!(
            s,
            "{{\"task\": \"{}\", \"index\": {i}, \"frame\": {}, \"threshold\": {}, \"strategy\": {strategy}, \
             \"feature\": {feature}, \"differs_at\": {differs_at}, \"status\": \"{}\", \"seconds\": {:.3}, \"diagnosis\": ",
            r.case.task().name(),
            r.case.frame(),
            t.map_or("null".into(), |t| py_threshold(Some(t))),
            r.status.name(),
            r.seconds
        );
        match &r.diagnosis {
            Some(d) => {
                let _ = write!(s, "\"{}\", \"diagnosis_text\": ", d.code());
                push_str(&mut s, &d.describe());
            }
            None => s.push_str("null, \"diagnosis_text\": null"),
        }
        for (key, v) in [("expected", &r.expected), ("returned", &r.returned)] {
            let _ = write!(s, ", \"{key}\": ");
            if r.status == Status::Correct {
                s.push_str("null");
            } else {
                push_str(&mut s, v);
            }
        }
        s.push('}');
    }
    s.push_str(if m.results.is_empty() { "]}" } else { "\n]}" });
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::diagnose::Diagnosis;
    use siftlab_core::json::parse;
    use siftlab_core::matching::Strategy;

    fn r(case: Case, status: Status) -> CaseResult {
        let diagnosis = match status {
            Status::Correct => None,
            Status::Wrong => Some(Diagnosis::Order),
            Status::Error => Some(Diagnosis::Timeout { seconds: 10.0 }),
        };
        CaseResult {
            case,
            status,
            diagnosis,
            expected: "e".into(),
            returned: "r".into(),
            seconds: 0.25,
            difference: None,
        }
    }

    #[test]
    fn marks_follow_the_lab() {
        let dt = Case::Dt { frame: 1, threshold: 100.0 };
        let nn = Case::Nn { frame: 2, threshold: None };
        let nndr = Case::Nndr { frame: 3, threshold: 0.8 };
        let info = Case::Info { frame: 4, strategy: Strategy::Nndr(0.8), feature: 9 };
        let mut results = Vec::new();
        for _ in 0..4 {
            results.push(r(dt, Status::Correct));
        }
        results.extend([r(nn, Status::Correct), r(nn, Status::Correct), r(nn, Status::Wrong), r(nn, Status::Wrong)]);
        results.extend([
            r(nndr, Status::Correct),
            r(nndr, Status::Correct),
            r(nndr, Status::Correct),
            r(nndr, Status::Error),
        ]);
        results.extend((0..4).map(|_| r(info, Status::Error)));
        let m = Marks::new(0, 4, results);
        let marks: Vec<f64> = m.tasks.iter().map(|t| t.marks).collect();
        assert_eq!(marks, vec![5.0, 0.5 + 2.25, 4.5 * 0.75, 0.0]);
        assert_eq!(m.total, 5.0 + 2.75 + 3.375);
        assert!(!m.full());
        let text = report_text(&m);
        assert!(text.contains("nn                  4        2       0    2.75"), "{text}");
        assert!(text.contains("11.12 / 20"), "{text}");
        assert!(text.contains("nn 3 of 4 (wrong): nn(des1, des2, None) on frames 1 -> 2"), "{text}");
        assert!(text.contains("  diagnosis: the right matches in another order"), "{text}");
        let j = parse(&report_json(&m)).unwrap();
        assert_eq!(j.get("total").unwrap().as_f64(), Some(11.125));
        let cases = j.get("cases").unwrap().as_arr().unwrap();
        assert_eq!(cases.len(), 16);
        assert_eq!(cases[6].get("index").unwrap().as_i64(), Some(2));
        assert_eq!(cases[6].get("diagnosis").unwrap().as_str(), Some("wrong_order"));
        assert_eq!(cases[4].get("threshold"), Some(&siftlab_core::json::Json::Null));
        assert_eq!(cases[12].get("strategy").unwrap().as_str(), Some("nndr"));
        assert_eq!(cases[0].get("expected"), Some(&siftlab_core::json::Json::Null));

        let all: Vec<CaseResult> = [dt, nn, nndr, info].iter().map(|&c| r(c, Status::Correct)).collect();
        let m = Marks::new(3, 1, all);
        assert_eq!(m.total, 20.0);
        assert!(m.full());
        let m = Marks::rejected(0, 25, Rejection::Empty);
        assert_eq!((m.total, m.full()), (0.0, false));
        assert!(report_text(&m).contains("scores 0: the file is empty"));
        let j = parse(&report_json(&Marks::rejected(
            0,
            25,
            Rejection::NotAscii { line: 3, column: 7, found: "x".into(), binary: false },
        )))
        .unwrap();
        assert_eq!(j.get("rejection").unwrap().get("line").unwrap().as_i64(), Some(3));
        assert_eq!(j.get("rejection").unwrap().get("code").unwrap().as_str(), Some("not_ascii"));
    }
}
