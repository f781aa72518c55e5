//! What a class got wrong: the class summary (`summary.json`) built from
//! each student's report.json, for the lecturer. Plain functions over
//! [`Json`], so the CLI (`siftlab mark --out`, `--summary`) and the app's
//! "Class results" view build the same numbers.
//!
//! It holds counts, the stable diagnosis codes with their explanation in
//! plain words ([`Diagnosis::explain_code`], never a student's own text),
//! student ids as examples and links to the explorer. No student's code or
//! output is in it.

use crate::cases::{Case, Task, NUM_FEATURES};
use crate::diagnose::{CaseResult, Diagnosis, Difference};
use siftlab_core::json::Json;
use std::collections::{BTreeMap, BTreeSet};

/// The summary's format, for readers to check.
pub const FORMAT: &str = "siftlab-class-summary/1";
/// Examples kept per mistake.
pub const EXAMPLES: usize = 3;
/// Cases listed as the hardest.
pub const HARDEST: usize = 10;

/// One row of the class: its id, status (`ok`, `zero`, `refused`,
/// `failed`), reason, and its report.json when it has one.
pub struct Entry<'a> {
    pub id: &'a str,
    pub status: &'a str,
    pub reason: &'a str,
    pub report: Option<&'a Json>,
}

/// A case as the report names it: (task, index).
type CaseKey = (usize, i64);

fn task_index(name: &str) -> Option<usize> {
    Task::ALL.iter().position(|t| t.name() == name)
}

/// The explorer's link for a case of a report: `?src=demo&frame=F&feature=K&algo=A&t=T`
/// (the query string the app's URL state reads, as the manual's examples).
/// The feature is matching_info's own, or for dt / nn / nndr the first list
/// that differed (`differs_at`); a case without one links the pair at feature 0.
pub fn case_link(case: &Json) -> Option<String> {
    let task = case.get("task")?.as_str()?;
    let frame = case.get("frame")?.as_i64()?;
    let algo = match task {
        "matching_info" => case.get("strategy")?.as_str()?,
        t => t,
    };
    if !["dt", "nn", "nndr"].contains(&algo) || !(1..=1_000_000).contains(&frame) {
        return None;
    }
    let feature = case.get("feature").and_then(Json::as_i64).or_else(|| case.get("differs_at").and_then(Json::as_i64));
    Some(link(frame, feature, algo, case.get("threshold").and_then(Json::as_f64)))
}

/// The explorer's link for a marked case ([`case_link`] of its report entry):
/// "Mark my code"'s "see this case".
pub fn result_link(r: &CaseResult) -> String {
    let feature = match (&r.case, &r.difference) {
        (Case::Info { feature, .. }, _) => Some(*feature as i64),
        (_, Some(Difference::Matches { feature, .. })) => Some(*feature as i64),
        _ => None,
    };
    let s = r.case.strategy();
    link(r.case.frame() as i64, feature, s.name(), s.threshold())
}

fn link(frame: i64, feature: Option<i64>, algo: &str, threshold: Option<f64>) -> String {
    let feature = feature.filter(|f| (0..NUM_FEATURES as i64).contains(f)).unwrap_or(0);
    let mut link = format!("?src=demo&frame={frame}&feature={feature}&algo={algo}");
    if let Some(t) = threshold.filter(|t| t.is_finite()) {
        link.push_str(&format!("&t={}", crate::cases::py_threshold(Some(t))));
    }
    link
}

/// The call a case made, in words (`dt #3, frames 11 -> 12, threshold 232.5`).
fn case_words(case: &Json) -> String {
    let task = case.get("task").and_then(Json::as_str).unwrap_or("?");
    let index = case.get("index").and_then(Json::as_i64).unwrap_or(-1);
    let frame = case.get("frame").and_then(Json::as_i64).unwrap_or(0);
    let t = case.get("threshold").and_then(Json::as_f64);
    let t = crate::cases::py_threshold(t.filter(|t| t.is_finite()));
    match (task, case.get("strategy").and_then(Json::as_str), case.get("feature").and_then(Json::as_i64)) {
        ("matching_info", Some(s), Some(f)) => {
            format!("matching_info #{index}, frames {} -> {frame}, {s}({t}) of feature {f}", frame - 1)
        }
        _ => format!("{task} #{index}, frames {} -> {frame}, threshold {t}", frame - 1),
    }
}

fn histogram(values: impl Iterator<Item = f64>, bins: usize, max: f64) -> Vec<Json> {
    let mut counts = vec![0i128; bins];
    for v in values.filter(|v| v.is_finite()) {
        let b = ((v / max * bins as f64).floor().max(0.0) as usize).min(bins - 1);
        counts[b] += 1;
    }
    counts.into_iter().map(Json::Int).collect()
}

fn obj(pairs: Vec<(&str, Json)>) -> Json {
    Json::Obj(pairs.into_iter().map(|(k, v)| (k.to_string(), v)).collect())
}

fn median(mut v: Vec<f64>) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    v.sort_by(f64::total_cmp);
    let m = v.len() / 2;
    if v.len() % 2 == 1 {
        v[m]
    } else {
        (v[m - 1] + v[m]) / 2.0
    }
}

fn round4(v: f64) -> f64 {
    (v * 10_000.0).round() / 10_000.0
}

/// The summary of a class. `meta` are the run's facts (seed, n, dataset,
/// siftlab) as the reports record them, taken from the first report.
pub fn summary(entries: &[Entry]) -> Json {
    let marked: Vec<&Entry> = entries.iter().filter(|e| matches!(e.status, "ok" | "zero")).collect();
    let mut status: BTreeMap<&str, i128> = ["ok", "zero", "refused", "failed"].into_iter().map(|s| (s, 0)).collect();
    let mut zero_reasons: BTreeMap<String, i128> = BTreeMap::new();
    for e in entries {
        *status.entry(e.status).or_insert(0) += 1;
        if e.status == "zero" {
            let code = e
                .report
                .and_then(|r| r.get("rejection"))
                .and_then(|r| r.get("code"))
                .and_then(Json::as_str)
                .map(str::to_string)
                .unwrap_or_else(|| if e.reason.is_empty() { "wrong values".into() } else { e.reason.to_string() });
            *zero_reasons.entry(code).or_insert(0) += 1;
        }
    }
    let totals: Vec<f64> =
        marked.iter().filter_map(|e| e.report.and_then(|r| r.get("total")).and_then(Json::as_f64)).collect();

    // Per task: calls, correct, marks; per mistake: the students, cases, examples;
    // per case: how many students failed it.
    let mut calls = [0i128; 4];
    let mut correct = [0i128; 4];
    let mut task_marks: [Vec<f64>; 4] = Default::default();
    struct Mistake {
        students: BTreeSet<String>,
        cases: i128,
        tasks: BTreeSet<usize>,
        examples: Vec<Json>,
    }
    let mut mistakes: BTreeMap<String, Mistake> = BTreeMap::new();
    let mut failed_by_case: BTreeMap<CaseKey, (i128, i128, Json)> = BTreeMap::new();
    for e in &marked {
        let Some(r) = e.report else { continue };
        for t in r.get("tasks").and_then(Json::as_arr).unwrap_or(&[]) {
            let Some(i) = t.get("task").and_then(Json::as_str).and_then(task_index) else { continue };
            calls[i] += t.get("calls").and_then(Json::as_i64).unwrap_or(0) as i128;
            correct[i] += t.get("correct").and_then(Json::as_i64).unwrap_or(0) as i128;
            task_marks[i].push(t.get("marks").and_then(Json::as_f64).unwrap_or(0.0));
        }
        for c in r.get("cases").and_then(Json::as_arr).unwrap_or(&[]) {
            let Some(ti) = c.get("task").and_then(Json::as_str).and_then(task_index) else { continue };
            let index = c.get("index").and_then(Json::as_i64).unwrap_or(-1);
            let ok = c.get("status").and_then(Json::as_str) == Some("correct");
            let slot = failed_by_case.entry((ti, index)).or_insert_with(|| (0, 0, c.clone()));
            slot.1 += 1;
            if ok {
                continue;
            }
            slot.0 += 1;
            // Only the codes siftlab writes: a report is siftlab's, but a
            // summary never shows a string it did not choose as a mistake.
            let Some(code) = c.get("diagnosis").and_then(Json::as_str).filter(|c| Diagnosis::explain_code(c).is_some())
            else {
                continue;
            };
            let m = mistakes.entry(code.to_string()).or_insert_with(|| Mistake {
                students: BTreeSet::new(),
                cases: 0,
                tasks: BTreeSet::new(),
                examples: Vec::new(),
            });
            m.cases += 1;
            m.tasks.insert(ti);
            if m.students.insert(e.id.to_string()) && m.examples.len() < EXAMPLES {
                m.examples.push(obj(vec![
                    ("student", Json::Str(e.id.to_string())),
                    ("case", Json::Str(case_words(c))),
                    ("link", case_link(c).map_or(Json::Null, Json::Str)),
                ]));
            }
        }
    }

    let tasks: Vec<Json> = Task::ALL
        .iter()
        .enumerate()
        .map(|(i, t)| {
            let share = if calls[i] > 0 { correct[i] as f64 / calls[i] as f64 } else { 0.0 };
            let n = task_marks[i].len().max(1) as f64;
            obj(vec![
                ("task", Json::Str(t.name().into())),
                ("calls", Json::Int(calls[i])),
                ("correct", Json::Int(correct[i])),
                ("share_correct", Json::Float(round4(share))),
                ("mean_marks", Json::Float(round4(task_marks[i].iter().sum::<f64>() / n))),
                // Half-mark bins from 0 to 5 (5 in the last).
                ("histogram", Json::Arr(histogram(task_marks[i].iter().copied(), 10, 5.0))),
            ])
        })
        .collect();

    // Ranked: most students first, then most cases, then the code.
    let mut ranked: Vec<(String, Mistake)> = mistakes.into_iter().collect();
    ranked.sort_by(|a, b| {
        (b.1.students.len(), b.1.cases).cmp(&(a.1.students.len(), a.1.cases)).then_with(|| a.0.cmp(&b.0))
    });
    let mistakes: Vec<Json> = ranked
        .into_iter()
        .map(|(code, m)| {
            obj(vec![
                ("code", Json::Str(code.clone())),
                ("explanation", Json::Str(Diagnosis::explain_code(&code).unwrap_or("").into())),
                ("students", Json::Int(m.students.len() as i128)),
                ("cases", Json::Int(m.cases)),
                ("tasks", Json::Arr(m.tasks.iter().map(|&i| Json::Str(Task::ALL[i].name().into())).collect())),
                ("examples", Json::Arr(m.examples)),
            ])
        })
        .collect();

    let mut hardest: Vec<(CaseKey, (i128, i128, Json))> = failed_by_case.into_iter().filter(|c| c.1 .0 > 0).collect();
    hardest.sort_by(|a, b| b.1 .0.cmp(&a.1 .0).then_with(|| a.0.cmp(&b.0)));
    let hardest: Vec<Json> = hardest
        .into_iter()
        .take(HARDEST)
        .map(|((ti, index), (failed, of, c))| {
            obj(vec![
                ("task", Json::Str(Task::ALL[ti].name().into())),
                ("index", Json::Int(index as i128)),
                ("case", Json::Str(case_words(&c))),
                ("failed", Json::Int(failed)),
                ("of", Json::Int(of)),
                ("link", case_link(&c).map_or(Json::Null, Json::Str)),
            ])
        })
        .collect();

    let first = entries.iter().find_map(|e| e.report);
    let fact = |k: &str| first.and_then(|r| r.get(k)).cloned().unwrap_or(Json::Null);
    obj(vec![
        ("format", Json::Str(FORMAT.into())),
        ("siftlab", fact("siftlab")),
        ("seed", fact("seed")),
        ("n", fact("cases_per_task")),
        ("dataset", fact("dataset")),
        ("students", Json::Int(entries.len() as i128)),
        ("status", Json::Obj(status.into_iter().map(|(k, v)| (k.to_string(), Json::Int(v))).collect())),
        (
            "zero_reasons",
            Json::Arr(
                zero_reasons
                    .into_iter()
                    .map(|(k, v)| obj(vec![("reason", Json::Str(k)), ("students", Json::Int(v))]))
                    .collect(),
            ),
        ),
        (
            "totals",
            obj(vec![
                ("marked", Json::Int(totals.len() as i128)),
                ("mean", Json::Float(round4(totals.iter().sum::<f64>() / totals.len().max(1) as f64))),
                ("median", Json::Float(round4(median(totals.clone())))),
                // One-mark bins from 0 to 20 (20 in the last).
                ("histogram", Json::Arr(histogram(totals.iter().copied(), 20, 20.0))),
            ]),
        ),
        ("tasks", Json::Arr(tasks)),
        ("mistakes", Json::Arr(mistakes)),
        ("hardest_cases", Json::Arr(hardest)),
    ])
}

#[cfg(test)]
mod tests {
    use super::*;
    use siftlab_core::json::parse;

    fn report(total: f64, cases: &str) -> Json {
        parse(&format!(
            r#"{{"seed": 5, "cases_per_task": 1, "total": {total}, "siftlab": "0.1", "dataset": "d", "rejection": null,
               "tasks": [{{"task": "dt", "calls": 1, "correct": 0, "errors": 0, "marks": 0.5}},
                         {{"task": "nn", "calls": 1, "correct": 1, "errors": 0, "marks": 5.0}}],
               "cases": [{cases}]}}"#
        ))
        .unwrap()
    }

    const LE: &str = r#"{"task": "dt", "index": 0, "frame": 12, "threshold": 232.5, "strategy": null, "feature": null,
        "differs_at": 17, "status": "wrong", "diagnosis": "less_or_equal", "diagnosis_text": "x"}"#;
    const NN_OK: &str =
        r#"{"task": "nn", "index": 0, "frame": 3, "threshold": null, "status": "correct", "diagnosis": null}"#;
    const K: &str = r#"{"task": "dt", "index": 0, "frame": 12, "threshold": 232.5, "differs_at": 4, "status": "wrong",
        "diagnosis": "k_too_small"}"#;

    #[test]
    fn counts_ranks_and_links() {
        let (a, b, c) =
            (report(5.5, &format!("{LE}, {NN_OK}")), report(5.5, &format!("{LE}, {NN_OK}")), report(5.5, K));
        let entries = [
            Entry { id: "a", status: "ok", reason: "", report: Some(&a) },
            Entry { id: "b", status: "ok", reason: "", report: Some(&b) },
            Entry { id: "c", status: "ok", reason: "", report: Some(&c) },
            Entry { id: "d", status: "refused", reason: "no file", report: None },
        ];
        let s = summary(&entries);
        assert_eq!(s.get("students").and_then(Json::as_i64), Some(4));
        assert_eq!(s.get("status").and_then(|x| x.get("refused")).and_then(Json::as_i64), Some(1));
        let m = s.get("mistakes").and_then(Json::as_arr).unwrap();
        let codes: Vec<_> = m.iter().map(|x| x.get("code").and_then(Json::as_str).unwrap()).collect();
        assert_eq!(codes, ["less_or_equal", "k_too_small"], "two students before one");
        assert_eq!(m[0].get("students").and_then(Json::as_i64), Some(2));
        let ex = m[0].get("examples").and_then(Json::as_arr).unwrap();
        assert_eq!(ex[0].get("link").and_then(Json::as_str), Some("?src=demo&frame=12&feature=17&algo=dt&t=232.5"));
        let hard = s.get("hardest_cases").and_then(Json::as_arr).unwrap();
        assert_eq!((hard.len(), hard[0].get("failed").and_then(Json::as_i64)), (1, Some(3)));
        let totals = s.get("totals").unwrap();
        let bins = totals.get("histogram").and_then(Json::as_arr).unwrap();
        assert_eq!((bins.len(), bins[5].as_i64()), (20, Some(3)));
        let dt = &s.get("tasks").and_then(Json::as_arr).unwrap()[0];
        assert_eq!(dt.get("share_correct").and_then(Json::as_f64), Some(0.0));
    }

    #[test]
    fn a_code_siftlab_does_not_write_is_no_mistake() {
        let r = report(0.0, r#"{"task": "dt", "index": 0, "frame": 2, "status": "wrong", "diagnosis": "<script>"}"#);
        let s = summary(&[Entry { id: "x", status: "ok", reason: "", report: Some(&r) }]);
        assert_eq!(s.get("mistakes").and_then(Json::as_arr).map(<[Json]>::len), Some(0));
    }

    #[test]
    fn links_read_the_case() {
        let info =
            parse(r#"{"task": "matching_info", "frame": 150, "strategy": "nn", "threshold": null, "feature": 209}"#);
        assert_eq!(case_link(&info.unwrap()).as_deref(), Some("?src=demo&frame=150&feature=209&algo=nn"));
        for bad in [r#"{"task": "dt", "frame": 0}"#, r#"{"task": "matching_info", "frame": 3, "strategy": "x"}"#] {
            assert_eq!(case_link(&parse(bad).unwrap()), None, "{bad}");
        }
    }
}
