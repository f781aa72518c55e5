//! The files a class marking writes: grades.csv rows (RFC 4180), each
//! student's Gradescope results.json, and the atomic write they all use.

use crate::pictures::Picture;
use sha2::{Digest, Sha256};
use siftlab_core::error::{Error, Result};
use siftlab_mark::{Json, Marks, Rejection, Status as CaseStatus, Task};
use std::path::Path;

/// A student's outcome in grades.csv.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Status {
    /// Marked (whatever the marks).
    Ok,
    /// Scores 0 without running: not ASCII, syntax, import, none found, …
    Zero,
    /// Could not be marked (the reason says why); not a mark of the student's.
    Failed,
    /// Not marked: an entry of the submissions that is no student's file
    /// (a link, a special file, an odd name, an id found twice, …).
    Refused,
}

impl Status {
    pub fn name(self) -> &'static str {
        match self {
            Status::Ok => "ok",
            Status::Zero => "zero",
            Status::Failed => "failed",
            Status::Refused => "refused",
        }
    }

    fn parse(s: &str) -> Option<Status> {
        [Status::Ok, Status::Zero, Status::Failed, Status::Refused].into_iter().find(|x| x.name() == s)
    }
}

/// grades.csv's reason for a file that scores 0 without a call.
pub fn zero_reason(r: &Rejection) -> String {
    match r.code() {
        "not_ascii" => "not ASCII".into(),
        "binary" => "not a text file".into(),
        "syntax" => "syntax".into(),
        "import" => "import".into(),
        "empty" => "empty".into(),
        "too_large" => "too large".into(),
        "load_timeout" => "load took over 60 s".into(),
        _ => "failed to load".into(),
    }
}

/// The folder of student `id`'s files in `out`: under students/, so no id
/// (`grades.csv` from a file grades.csv.py) names a class-level file.
pub fn student_dir(out: &Path, id: &str) -> std::path::PathBuf {
    out.join("students").join(id)
}

/// One line of grades.csv.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    pub student: String,
    /// dt, nn, nndr, matching_info, as printed (two decimals).
    pub marks: [String; 4],
    pub total: f64,
    pub status: Status,
    pub reason: String,
}

pub const HEADER: &str = "student,dt,nn,nndr,matching_info,total,status,reason";

impl Row {
    pub fn of(student: &str, m: &Marks, status: Status, reason: &str) -> Row {
        let mark = |t: Task| m.tasks.iter().find(|x| x.task == t).map_or(0.0, |x| x.marks);
        Row {
            student: student.to_string(),
            marks: Task::ALL.map(|t| format!("{:.2}", mark(t))),
            total: (m.total * 100.0).round() / 100.0,
            status,
            reason: reason.to_string(),
        }
    }

    /// The row of an entry that is not marked.
    pub fn refused(name: &str, reason: &str) -> Row {
        Row {
            student: name.to_string(),
            marks: std::array::from_fn(|_| "0.00".to_string()),
            total: 0.0,
            status: Status::Refused,
            reason: reason.to_string(),
        }
    }

    /// Whether the row is a mark (`ok` or `zero`), not a failure or refusal.
    pub fn marked(&self) -> bool {
        matches!(self.status, Status::Ok | Status::Zero)
    }

    /// Where the row goes in grades.csv (by id, bytes, then reason) and
    /// what tells two rows apart: an id twice is two refusals with different reasons.
    pub fn key(&self) -> (Vec<u8>, Vec<u8>) {
        let reason = if self.status == Status::Refused { self.reason.as_bytes() } else { b"" };
        (self.student.as_bytes().to_vec(), reason.to_vec())
    }

    /// The row a report.json (as `class::mark_student` writes it) records.
    pub fn from_report(student: &str, j: &Json) -> Option<Row> {
        let status = Status::parse(j.get("status")?.as_str()?)?;
        let tasks = j.get("tasks")?.as_arr()?;
        let mark = |t: Task| {
            tasks
                .iter()
                .find(|x| x.get("task").and_then(Json::as_str) == Some(t.name()))
                .and_then(|x| x.get("marks")?.as_f64())
        };
        let marks = Task::ALL.map(|t| format!("{:.2}", mark(t).unwrap_or(0.0)));
        Some(Row {
            student: student.to_string(),
            marks,
            total: (j.get("total")?.as_f64()? * 100.0).round() / 100.0,
            status,
            reason: j.get("reason").and_then(Json::as_str).unwrap_or("").to_string(),
        })
    }

    pub fn status_text(&self) -> String {
        if self.reason.is_empty() {
            self.status.name().to_string()
        } else {
            format!("{}: {}", self.status.name(), self.reason)
        }
    }

    /// grades.csv: the header and the rows (sorted by the caller), CRLF line
    /// ends and quoting as RFC 4180 asks.
    pub fn csv(rows: &[Row]) -> String {
        let mut s = format!("{HEADER}\r\n");
        for r in rows {
            let mut fields = vec![field(&r.student)];
            fields.extend(r.marks.iter().cloned());
            fields.push(format!("{:.2}", r.total));
            fields.push(r.status.name().to_string());
            fields.push(field(&r.reason));
            s.push_str(&fields.join(","));
            s.push_str("\r\n");
        }
        s
    }

    /// Reads grades.csv as [`Row::csv`] writes it.
    pub fn parse_csv(text: &str) -> std::result::Result<Vec<Row>, String> {
        let records = records(text)?;
        let mut it = records.into_iter();
        match it.next() {
            Some(h) if h.join(",") == HEADER => {}
            _ => return Err(format!("the first line is not {HEADER}")),
        }
        it.map(|f| {
            if f.len() != 8 {
                return Err(format!("a row of {} fields, not 8", f.len()));
            }
            Ok(Row {
                student: f[0].clone(),
                marks: [f[1].clone(), f[2].clone(), f[3].clone(), f[4].clone()],
                total: f[5].parse().map_err(|_| format!("total {:?} is not a number", f[5]))?,
                status: Status::parse(&f[6])
                    .ok_or_else(|| format!("status {:?} is not ok, zero, failed or refused", f[6]))?,
                reason: f[7].clone(),
            })
        })
        .collect()
    }
}

/// A CSV field, quoted when it holds a comma, a quote or a line break.
fn field(s: &str) -> String {
    if s.contains([',', '"', '\r', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// RFC 4180 records (quoted fields may hold commas, quotes and line breaks).
fn records(text: &str) -> std::result::Result<Vec<Vec<String>>, String> {
    let (mut out, mut rec, mut cur) = (Vec::new(), Vec::new(), String::new());
    let mut chars = text.chars().peekable();
    let mut quoted = false;
    while let Some(c) = chars.next() {
        match (quoted, c) {
            (true, '"') if chars.peek() == Some(&'"') => {
                cur.push('"');
                chars.next();
            }
            (true, '"') => quoted = false,
            (true, c) => cur.push(c),
            (false, '"') if cur.is_empty() => quoted = true,
            (false, ',') => rec.push(std::mem::take(&mut cur)),
            (false, '\r') => {}
            (false, '\n') => {
                rec.push(std::mem::take(&mut cur));
                out.push(std::mem::take(&mut rec));
            }
            (false, c) => cur.push(c),
        }
    }
    if quoted {
        return Err("a quoted field does not end".into());
    }
    if !cur.is_empty() || !rec.is_empty() {
        rec.push(cur);
        out.push(rec);
    }
    Ok(out)
}

/// One task's text for a platform: its counts, then each failed case with
/// its diagnosis and, where there is one, the expected and returned values.
fn task_output(m: &Marks, t: Task, none_found: bool) -> String {
    let tm = m.tasks.iter().find(|x| x.task == t);
    let mut out = match (&m.rejection, tm, none_found) {
        (_, _, true) => "no vision_tasks.py was found in the submission".to_string(),
        (Some(r), _, _) => format!("the file scores 0: {r}"),
        (None, Some(x), _) => format!("{} of {} calls correct, {} with an error", x.correct, x.calls, x.errors),
        (None, None, _) => String::new(),
    };
    for r in m.results.iter().filter(|r| r.case.task() == t && r.status != CaseStatus::Correct) {
        out.push_str(&format!(
            "\n\n{} ({}): {}",
            r.case.call_text(),
            r.status.name(),
            r.diagnosis.as_ref().map_or_else(String::new, |d| d.describe())
        ));
        if !r.expected.is_empty() {
            out.push_str(&format!("\n  expected: {}\n  returned: {}", r.expected, r.returned));
        }
    }
    out
}

fn task_marks(m: &Marks, t: Task) -> f64 {
    m.tasks.iter().find(|x| x.task == t).map_or(0.0, |x| (x.marks * 100.0).round() / 100.0)
}

fn footer(sandbox: &str) -> String {
    format!("marked by siftlab {} (sandbox: {sandbox})", env!("CARGO_PKG_VERSION"))
}

/// Gradescope's results.json: the score out of 20, the report as its
/// output, and one test per task with that task's failed cases.
/// `sandbox` names the tier the file ran in (`Tier::name`, or "not run"
/// for a file refused before running); `seconds` is the marking's wall time.
pub fn gradescope_json(m: &Marks, report: &str, none_found: bool, sandbox: &str, seconds: f64) -> String {
    let tests: Vec<Json> = Task::ALL
        .iter()
        .map(|&t| {
            let score = task_marks(m, t);
            Json::Obj(vec![
                ("name".into(), Json::Str(t.name().into())),
                ("score".into(), Json::Float(score)),
                ("max_score".into(), Json::Float(5.0)),
                // Gradescope colours a test by it (passed: full marks).
                ("status".into(), Json::Str(if score >= 5.0 { "passed" } else { "failed" }.into())),
                ("output".into(), Json::Str(task_output(m, t, none_found))),
                ("output_format".into(), Json::Str("text".into())),
                ("visibility".into(), Json::Str("visible".into())),
            ])
        })
        .collect();
    let top = Json::Obj(vec![
        ("score".into(), Json::Float((m.total * 100.0).round() / 100.0)),
        ("max_score".into(), Json::Float(20.0)),
        ("output".into(), Json::Str(format!("{report}\n{}\n", footer(sandbox)))),
        ("output_format".into(), Json::Str("text".into())),
        ("visibility".into(), Json::Str("visible".into())),
        ("execution_time".into(), Json::Float((seconds * 10.0).round() / 10.0)),
        ("tests".into(), Json::Arr(tests)),
        // Gradescope keeps extra_data with the result, unread: how it was marked.
        ("extra_data".into(), extra(m, sandbox)),
    ]);
    format!("{}\n", top.to_json())
}

fn extra(m: &Marks, sandbox: &str) -> Json {
    Json::Obj(vec![
        ("sandbox".into(), Json::Str(sandbox.into())),
        ("siftlab".into(), Json::Str(env!("CARGO_PKG_VERSION").into())),
        ("seed".into(), Json::Float(m.seed as f64)),
        ("n".into(), Json::Float(m.cases_per_task as f64)),
    ])
}

/// PrairieLearn's external grader results.json: `score` in [0, 1] (the
/// total over 20), `gradable`, `message`, `output`, one test per task
/// (`name`, `points`, `max_points`, `message`, `output`). A file the lab
/// refuses before it runs (empty, too large, not printable ASCII, not
/// Python) or none found is not gradable: PrairieLearn then shows
/// `format_errors` and does not count the submission.
pub fn prairielearn_json(m: &Marks, report: &str, none_found: bool, sandbox: &str, pictures: &[Picture]) -> String {
    // The whole file stays under PrairieLearn's 1 MB: pictures are left out
    // from the last task back until it fits.
    (0..=pictures.len())
        .rev()
        .map(|k| prairielearn_with(m, report, none_found, sandbox, &pictures[..k]))
        .find(|j| j.len() <= PRAIRIELEARN_MAX_BYTES)
        .unwrap_or_else(|| prairielearn_with(m, report, none_found, sandbox, &[]))
}

/// PrairieLearn reads results.json files of up to 1 MB.
pub const PRAIRIELEARN_MAX_BYTES: usize = 1_000_000;

fn prairielearn_with(m: &Marks, report: &str, none_found: bool, sandbox: &str, pictures: &[Picture]) -> String {
    use siftlab_mark::ErrorKind;
    let format_error = match (&m.rejection, none_found) {
        (_, true) => Some("no vision_tasks.py was found in the submission".to_string()),
        (Some(r @ (Rejection::Empty | Rejection::TooLarge { .. } | Rejection::NotAscii { .. })), _) => {
            Some(r.to_string())
        }
        (Some(r @ Rejection::Load { kind: ErrorKind::Syntax, .. }), _) => Some(r.to_string()),
        _ => None,
    };
    let tests: Vec<Json> = Task::ALL
        .iter()
        .map(|&t| {
            let points = task_marks(m, t);
            let message = m.tasks.iter().find(|x| x.task == t).map_or_else(String::new, |x| {
                format!("{} of {} calls correct, {} with an error", x.correct, x.calls, x.errors)
            });
            let mut test = vec![
                ("name".into(), Json::Str(t.name().into())),
                ("points".into(), Json::Float(points)),
                ("max_points".into(), Json::Float(5.0)),
                ("message".into(), Json::Str(message)),
                ("output".into(), Json::Str(task_output(m, t, none_found))),
            ];
            let images: Vec<Json> = pictures
                .iter()
                .filter(|p| p.task == t)
                .map(|p| {
                    Json::Obj(vec![
                        ("label".into(), Json::Str(p.label.clone())),
                        ("url".into(), Json::Str(p.url.clone())),
                    ])
                })
                .collect();
            if !images.is_empty() {
                test.push(("images".into(), Json::Arr(images)));
            }
            Json::Obj(test)
        })
        .collect();
    let score = ((m.total / 20.0).clamp(0.0, 1.0) * 10_000.0).round() / 10_000.0;
    let mut top = vec![
        ("gradable".into(), Json::Bool(format_error.is_none())),
        ("score".into(), Json::Float(score)),
        ("message".into(), Json::Str(format!("{:.2} / 20", m.total))),
        ("output".into(), Json::Str(format!("{report}\n{}\n", footer(sandbox)))),
        ("tests".into(), Json::Arr(tests)),
        ("sandbox".into(), Json::Str(sandbox.into())),
    ];
    if let Some(e) = format_error {
        top.push(("format_errors".into(), Json::Arr(vec![Json::Str(e)])));
    }
    format!("{}\n", Json::Obj(top).to_json())
}

/// Writes `bytes` to `path` through a temporary file in the same folder and
/// a rename: a reader (or a run killed halfway) sees the old file or the new
/// one, never a part.
pub fn atomic_write(path: &Path, bytes: &[u8]) -> Result<()> {
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let tmp = path.with_file_name(format!(".{name}.tmp-{}", std::process::id()));
    std::fs::write(&tmp, bytes)
        .and_then(|_| std::fs::rename(&tmp, path))
        .map_err(|e| Error::InvalidArgument(format!("cannot write {}: {e}", path.display())))
}

/// The SHA-256 of `bytes`, in hex.
pub fn sha256_hex(bytes: &[u8]) -> String {
    Sha256::digest(bytes).iter().map(|b| format!("{b:02x}")).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// PrairieLearn: a refused file is not gradable and says why; one that
    /// loads and fails is gradable with 0; the score is over 1, not 20.
    #[test]
    fn prairielearn_grades_only_files_that_run() {
        let parse = |m: &Marks, none: bool| {
            siftlab_core::json::parse(&prairielearn_json(m, "r", none, "container", &[])).unwrap()
        };
        let empty = parse(&Marks::rejected(0, 1, Rejection::Empty), false);
        assert!(matches!(empty.get("gradable"), Some(Json::Bool(false))));
        let errors = empty.get("format_errors").and_then(Json::as_arr).unwrap();
        assert_eq!(errors.len(), 1);
        assert!(errors[0].as_str().unwrap().contains("empty"), "{:?}", errors[0]);
        let none = parse(&Marks::new(0, 1, Vec::new()), true);
        assert!(matches!(none.get("gradable"), Some(Json::Bool(false))));
        let load = Rejection::Load { kind: siftlab_mark::ErrorKind::Runtime, message: "boom".into() };
        let failed = parse(&Marks::rejected(0, 1, load), false);
        assert!(matches!(failed.get("gradable"), Some(Json::Bool(true))));
        assert!(failed.get("format_errors").is_none());
        assert_eq!(failed.get("score").and_then(Json::as_f64), Some(0.0));
        let tests = failed.get("tests").and_then(Json::as_arr).unwrap();
        let names: Vec<&str> = tests.iter().map(|t| t.get("name").and_then(Json::as_str).unwrap()).collect();
        assert_eq!(names, ["dt", "nn", "nndr", "matching_info"]);
        assert!(tests.iter().all(|t| t.get("max_points").and_then(Json::as_f64) == Some(5.0)));
    }

    /// Pictures go to their task's test, and are left out from the last
    /// back while the file would pass PrairieLearn's 1 MB.
    #[test]
    fn prairielearn_pictures_fit_in_a_megabyte() {
        let picture = |task, kb: usize| Picture { task, label: format!("{kb} KB"), url: "A".repeat(kb * 1000) };
        let pictures = [picture(Task::Dt, 400), picture(Task::Nndr, 500), picture(Task::MatchingInfo, 200)];
        let m = Marks::new(0, 1, Vec::new());
        let text = prairielearn_json(&m, "r", false, "container", &pictures);
        assert!(text.len() <= PRAIRIELEARN_MAX_BYTES, "{} bytes", text.len());
        let j = siftlab_core::json::parse(&text).unwrap();
        let labels: Vec<(String, String)> = j
            .get("tests")
            .and_then(Json::as_arr)
            .unwrap()
            .iter()
            .flat_map(|t| {
                let name = t.get("name").and_then(Json::as_str).unwrap().to_string();
                t.get("images")
                    .and_then(Json::as_arr)
                    .unwrap_or(&[])
                    .iter()
                    .map(move |i| (name.clone(), i.get("label").and_then(Json::as_str).unwrap().to_string()))
            })
            .collect();
        // 400 + 500 fit; the third would pass 1 MB.
        assert_eq!(labels, [("dt".to_string(), "400 KB".to_string()), ("nndr".to_string(), "500 KB".to_string())]);
        let none = prairielearn_json(&m, "r", false, "container", &[picture(Task::Dt, 1200)]);
        assert!(!none.contains("images") && none.len() < 10_000);
    }

    #[test]
    fn csv_round_trips_with_quotes() {
        let rows = vec![
            Row {
                student: "a,b".into(),
                marks: ["5.00".into(), "0.00".into(), "5.00".into(), "2.66".into()],
                total: 12.66,
                status: Status::Ok,
                reason: String::new(),
            },
            Row {
                student: "c".into(),
                marks: ["0.00".into(), "0.00".into(), "0.00".into(), "0.00".into()],
                total: 0.0,
                status: Status::Failed,
                reason: "said \"no\"\nthen left".into(),
            },
        ];
        let text = Row::csv(&rows);
        assert!(text.starts_with("student,dt,nn,nndr,matching_info,total,status,reason\r\n\"a,b\",5.00,"), "{text}");
        assert!(text.contains("\"said \"\"no\"\"\nthen left\""), "{text}");
        assert_eq!(Row::parse_csv(&text).unwrap(), rows);
        assert_eq!(sha256_hex(b"abc"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
    }
}
