//! The files a class marking writes: grades.csv rows (RFC 4180), each
//! student's Gradescope results.json, and the atomic write they all use.

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

/// Gradescope's results.json: the score out of 20, the report as its
/// output, and one test per task with that task's failed cases.
/// `sandbox` names the tier the file ran in (`Tier::name`, or "not run"
/// for a file refused before running); `seconds` is the marking's wall time.
pub fn gradescope_json(m: &Marks, report: &str, none_found: bool, sandbox: &str, seconds: f64) -> String {
    let tests: Vec<Json> = Task::ALL
        .iter()
        .map(|&t| {
            let tm = m.tasks.iter().find(|x| x.task == t);
            let mut out = match (&m.rejection, tm, none_found) {
                (_, _, true) => "no vision_tasks.py was found in the submission".to_string(),
                (Some(r), _, _) => format!("the file scores 0: {r}"),
                (None, Some(x), _) => {
                    format!("{} of {} calls correct, {} with an error", x.correct, x.calls, x.errors)
                }
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
            let score = tm.map_or(0.0, |x| (x.marks * 100.0).round() / 100.0);
            Json::Obj(vec![
                ("name".into(), Json::Str(t.name().into())),
                ("score".into(), Json::Float(score)),
                ("max_score".into(), Json::Float(5.0)),
                // Gradescope colours a test by it (passed: full marks).
                ("status".into(), Json::Str(if score >= 5.0 { "passed" } else { "failed" }.into())),
                ("output".into(), Json::Str(out)),
                ("output_format".into(), Json::Str("text".into())),
                ("visibility".into(), Json::Str("visible".into())),
            ])
        })
        .collect();
    let top = Json::Obj(vec![
        ("score".into(), Json::Float((m.total * 100.0).round() / 100.0)),
        ("max_score".into(), Json::Float(20.0)),
        (
            "output".into(),
            Json::Str(format!("{report}\nmarked by siftlab {} (sandbox: {sandbox})\n", env!("CARGO_PKG_VERSION"))),
        ),
        ("output_format".into(), Json::Str("text".into())),
        ("visibility".into(), Json::Str("visible".into())),
        ("execution_time".into(), Json::Float((seconds * 10.0).round() / 10.0)),
        ("tests".into(), Json::Arr(tests)),
        // Gradescope keeps extra_data with the result, unread: how it was marked.
        (
            "extra_data".into(),
            Json::Obj(vec![
                ("sandbox".into(), Json::Str(sandbox.into())),
                ("siftlab".into(), Json::Str(env!("CARGO_PKG_VERSION").into())),
                ("seed".into(), Json::Float(m.seed as f64)),
                ("n".into(), Json::Float(m.cases_per_task as f64)),
            ]),
        ),
    ]);
    format!("{}\n", top.to_json())
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
