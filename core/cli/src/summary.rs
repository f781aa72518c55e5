//! The class summary for the lecturer (docs/marking.md, "What the class got
//! wrong"): `DIR/summary.json` (`siftlab_mark::summary`) and
//! `DIR/summary.html`, one self-contained page (inline SVG, no network, opens
//! from disk), written at the end of `mark --out` and `--merge`, and by
//! `siftlab mark --summary DIR...` from the class folders' grades.csv and
//! sealed report.json files.

use crate::report_files::{atomic_write, student_dir, Row};
use crate::seal::{Seal, KEY_FILE};
use siftlab_core::error::{Error, Result};
use siftlab_core::render::palette::{hex, BLUE, REST};
use siftlab_mark::{parse_json, summary, Json, SummaryEntry, Task};
use std::path::Path;

/// Where links to the explorer point unless the page is told otherwise
/// (`www/serve`'s address).
const APP_URL: &str = "http://localhost:8080/";

/// Reads the class folders `dirs` (one, or a run's shards) and writes
/// summary.json and summary.html into `out`. A report whose seal does not
/// hold is left out of the counts (and said so); its row still counts in
/// the statuses. Returns the number of students.
pub fn write(dirs: &[&Path], out: &Path) -> Result<usize> {
    let mut rows: Vec<(Row, Option<Json>)> = Vec::new();
    let mut unsealed = Vec::new();
    for dir in dirs {
        let grades = dir.join("grades.csv");
        let text = std::fs::read_to_string(&grades).map_err(|e| {
            Error::InvalidArgument(format!(
                "cannot read {}: {e}; give the folder `siftlab mark --out` wrote (or its shards)",
                grades.display()
            ))
        })?;
        if std::fs::symlink_metadata(dir.join(KEY_FILE)).is_err() {
            return Err(Error::InvalidArgument(format!(
                "{} has no {KEY_FILE}: it is not a folder `siftlab mark --out` wrote",
                dir.display()
            )));
        }
        let seal = Seal::open(dir)?;
        let parsed = Row::parse_csv(&text).map_err(|e| Error::InvalidArgument(format!("{}: {e}", grades.display())))?;
        for row in parsed {
            let report = if row.marked() {
                let j = seal
                    .verified(&row.student, &student_dir(dir, &row.student))
                    .and_then(|b| parse_json(std::str::from_utf8(&b).ok()?).ok());
                if j.is_none() {
                    unsealed.push(row.student.clone());
                }
                j
            } else {
                None
            };
            rows.push((row, report));
        }
    }
    if !unsealed.is_empty() {
        eprintln!(
            "siftlab: {} report(s) missing or not sealed by this class's key, left out of the summary: {}",
            unsealed.len(),
            siftlab_mark::escaped(&unsealed.join(", "), 300)
        );
    }
    let entries: Vec<SummaryEntry> = rows
        .iter()
        .map(|(r, j)| SummaryEntry { id: &r.student, status: r.status.name(), reason: &r.reason, report: j.as_ref() })
        .collect();
    let s = summary(&entries);
    std::fs::create_dir_all(out)
        .map_err(|e| Error::InvalidArgument(format!("cannot create {}: {e}", out.display())))?;
    atomic_write(&out.join("summary.json"), format!("{}\n", s.to_json()).as_bytes())?;
    atomic_write(&out.join("summary.html"), html(&s).as_bytes())?;
    Ok(entries.len())
}

/// `siftlab mark --summary DIR... [--out OUT]`: exit 0, or 2 with the reason.
pub fn main(dirs: &[std::path::PathBuf], out: Option<&Path>) -> i32 {
    let refs: Vec<&Path> = dirs.iter().map(|d| d.as_path()).collect();
    let target = match (out, refs.as_slice()) {
        (Some(o), _) => o,
        (None, [one]) => one,
        (None, _) => {
            eprintln!("siftlab: error: --summary of several folders (shards) needs --out DIR for the summary");
            return 2;
        }
    };
    match write(&refs, target) {
        Ok(n) => {
            eprintln!("summary: {} ({n} student(s))", target.join("summary.html").display());
            0
        }
        Err(e) => {
            eprintln!("siftlab: error: {e}");
            2
        }
    }
}

/// Text for HTML: the SVG writer's escape (`&`, `<`, `>`, `"`), plus `'`,
/// and control characters as spaces.
fn esc(s: &str) -> String {
    let plain: String = s.chars().map(|c| if c.is_control() { ' ' } else { c }).collect();
    siftlab_core::render::plot::svg::escape(&plain).replace('\'', "&#39;")
}

fn num(j: Option<&Json>) -> String {
    match j {
        Some(Json::Int(v)) => v.to_string(),
        Some(Json::Float(v)) => format!("{v}"),
        Some(Json::Str(s)) => esc(s),
        _ => "–".into(),
    }
}

/// A bar chart of `counts` with `labels` under the bars, as inline SVG
/// (Okabe–Ito blue bars, scaled to fit any width).
fn bars(counts: &[i64], labels: &[String], title: &str) -> String {
    let (w, h, pad) = (36.0 * counts.len() as f64 + 40.0, 170.0, 30.0);
    let max = counts.iter().copied().max().unwrap_or(0).max(1) as f64;
    let bw = (w - 40.0) / counts.len().max(1) as f64;
    let mut s = format!(
        "<svg viewBox=\"0 0 {w} {h}\" role=\"img\" aria-label=\"{}\" class=\"hist\"><title>{}</title>",
        esc(title),
        esc(title)
    );
    s.push_str(&format!(
        "<line x1=\"30\" y1=\"{0}\" x2=\"{1}\" y2=\"{0}\" stroke=\"{2}\"/>",
        h - pad,
        w - 6.0,
        hex(REST)
    ));
    for (i, &c) in counts.iter().enumerate() {
        let bh = (h - pad - 20.0) * c as f64 / max;
        let x = 34.0 + i as f64 * bw;
        s.push_str(&format!(
            "<rect x=\"{x:.1}\" y=\"{:.1}\" width=\"{:.1}\" height=\"{bh:.1}\" fill=\"{}\"><title>{}: {c}</title></rect>",
            h - pad - bh,
            bw - 4.0,
            hex(BLUE),
            esc(&labels[i])
        ));
        if c > 0 {
            s.push_str(&format!(
                "<text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"middle\" class=\"n\">{c}</text>",
                x + (bw - 4.0) / 2.0,
                h - pad - bh - 4.0
            ));
        }
        s.push_str(&format!(
            "<text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"middle\" class=\"l\">{}</text>",
            x + (bw - 4.0) / 2.0,
            h - pad + 14.0,
            esc(&labels[i])
        ));
    }
    s.push_str("</svg>");
    s
}

fn ints(j: Option<&Json>) -> Vec<i64> {
    j.and_then(Json::as_arr).unwrap_or(&[]).iter().map(|v| v.as_i64().unwrap_or(0)).collect()
}

fn link(j: Option<&Json>, text: &str) -> String {
    match j.and_then(Json::as_str) {
        Some(q) if q.starts_with('?') => {
            format!("<a class=\"case\" data-q=\"{}\" href=\"{}{}\">{}</a>", esc(q), APP_URL, esc(q), esc(text))
        }
        _ => esc(text),
    }
}

/// summary.html: the same numbers as summary.json, for people.
pub fn html(s: &Json) -> String {
    let g = |k: &str| s.get(k);
    let mut b = String::new();
    b.push_str(
        "<!doctype html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\
        <meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\
        <title>siftlab: what the class got wrong</title><style>",
    );
    b.push_str(STYLE);
    b.push_str("</style></head><body><main>\n<h1>What the class got wrong</h1>\n");
    b.push_str(&format!(
        "<p class=\"facts\">{} students · seed {} · {} calls per task · dataset <code>{}</code> · siftlab {}</p>\n",
        num(g("students")),
        num(g("seed")),
        num(g("n")),
        num(g("dataset")),
        num(g("siftlab"))
    ));
    // Statuses.
    b.push_str("<section><h2>Students</h2><table><thead><tr><th scope=\"col\">status</th><th scope=\"col\">students</th></tr></thead><tbody>");
    let words = [
        ("ok", "marked"),
        ("zero", "scored 0 without a call (the file was not run: see below)"),
        ("refused", "refused (not a submission)"),
        ("failed", "could not be marked"),
    ];
    for (k, w) in words {
        b.push_str(&format!("<tr><td>{w}</td><td>{}</td></tr>", num(g("status").and_then(|x| x.get(k)))));
    }
    b.push_str("</tbody></table>");
    let zero = g("zero_reasons").and_then(Json::as_arr).unwrap_or(&[]);
    if !zero.is_empty() {
        b.push_str("<p>Scored 0: ");
        let parts: Vec<String> =
            zero.iter().map(|z| format!("{} ({})", num(z.get("reason")), num(z.get("students")))).collect();
        b.push_str(&parts.join(", "));
        b.push_str("</p>");
    }
    b.push_str("</section>\n");
    // Totals.
    let t = g("totals");
    b.push_str(&format!(
        "<section><h2>Marks out of 20</h2><p>{} marked · mean {} · median {}</p>",
        num(t.and_then(|t| t.get("marked"))),
        num(t.and_then(|t| t.get("mean"))),
        num(t.and_then(|t| t.get("median")))
    ));
    let labels: Vec<String> = (0..20).map(|i| if i == 19 { "19–20".into() } else { format!("{i}") }).collect();
    b.push_str(&bars(&ints(t.and_then(|t| t.get("histogram"))), &labels, "students per mark out of 20 (bins of 1)"));
    b.push_str("</section>\n");
    // Tasks.
    b.push_str("<section><h2>Tasks</h2><table><thead><tr><th scope=\"col\">task</th><th scope=\"col\">calls correct</th><th scope=\"col\">mean mark / 5</th></tr></thead><tbody>");
    let tasks = g("tasks").and_then(Json::as_arr).unwrap_or(&[]);
    for task in tasks {
        let share = task.get("share_correct").and_then(Json::as_f64).unwrap_or(0.0);
        b.push_str(&format!(
            "<tr><td>{}</td><td>{:.1} % ({} of {})</td><td>{}</td></tr>",
            num(task.get("task")),
            share * 100.0,
            num(task.get("correct")),
            num(task.get("calls")),
            num(task.get("mean_marks"))
        ));
    }
    b.push_str("</tbody></table><div class=\"tasks\">");
    let half: Vec<String> = (0..10).map(|i| format!("{}", i as f64 / 2.0)).collect();
    for task in tasks {
        let name = task.get("task").and_then(Json::as_str).filter(|n| Task::ALL.iter().any(|t| t.name() == *n));
        let name = name.unwrap_or("?");
        b.push_str(&format!("<figure><figcaption>{}</figcaption>", esc(name)));
        b.push_str(&bars(&ints(task.get("histogram")), &half, &format!("students per {name} mark (bins of 0.5)")));
        b.push_str("</figure>");
    }
    b.push_str("</div></section>\n");
    // Mistakes.
    b.push_str("<section><h2>Mistakes, most students first</h2>");
    let mistakes = g("mistakes").and_then(Json::as_arr).unwrap_or(&[]);
    if mistakes.is_empty() {
        b.push_str("<p>No wrong value: every failed case (if any) was a refusal.</p>");
    } else {
        b.push_str("<div class=\"scroll\" tabindex=\"0\" role=\"region\" aria-label=\"the mistakes\"><table class=\"mistakes\"><thead><tr><th scope=\"col\">mistake</th><th scope=\"col\">students</th><th scope=\"col\">cases</th><th scope=\"col\">examples (open in siftlab)</th></tr></thead><tbody>");
        for m in mistakes {
            let examples: Vec<String> = m
                .get("examples")
                .and_then(Json::as_arr)
                .unwrap_or(&[])
                .iter()
                .map(|e| {
                    let who = e.get("student").and_then(Json::as_str).unwrap_or("?");
                    let case = e.get("case").and_then(Json::as_str).unwrap_or("");
                    format!("<li>{}: {}</li>", esc(who), link(e.get("link"), case))
                })
                .collect();
            let tasks: Vec<String> =
                m.get("tasks").and_then(Json::as_arr).unwrap_or(&[]).iter().map(|t| num(Some(t))).collect();
            b.push_str(&format!(
                "<tr><td><code>{}</code> ({})<br>{}</td><td>{}</td><td>{}</td><td><ul>{}</ul></td></tr>",
                num(m.get("code")),
                tasks.join(", "),
                num(m.get("explanation")),
                num(m.get("students")),
                num(m.get("cases")),
                examples.join("")
            ));
        }
        b.push_str("</tbody></table></div>");
    }
    b.push_str("</section>\n");
    // Hardest cases.
    b.push_str("<section><h2>Cases most students failed</h2><table><thead><tr><th scope=\"col\">case</th><th scope=\"col\">failed</th></tr></thead><tbody>");
    for c in g("hardest_cases").and_then(Json::as_arr).unwrap_or(&[]) {
        let case = c.get("case").and_then(Json::as_str).unwrap_or("");
        b.push_str(&format!(
            "<tr><td>{}</td><td>{} of {}</td></tr>",
            link(c.get("link"), case),
            num(c.get("failed")),
            num(c.get("of"))
        ));
    }
    b.push_str("</tbody></table></section>\n");
    b.push_str(&format!(
        "<p class=\"app\"><label>Links open siftlab at <input id=\"app\" value=\"{APP_URL}\" size=\"30\"></label> \
         (<code>www/serve</code>'s address; change it to where your class's app is served).</p>\n"
    ));
    b.push_str("</main><script>");
    b.push_str(SCRIPT);
    b.push_str("</script></body></html>\n");
    b
}

const STYLE: &str = "body{font:16px/1.5 system-ui,sans-serif;color:#1a1a1a;background:#fff;margin:0}\
main{max-width:1100px;margin:0 auto;padding:1rem}h1{font-size:1.6rem}h2{font-size:1.25rem;margin-top:2rem}\
table{border-collapse:collapse;margin:.5rem 0;max-width:100%}th,td{border-bottom:1px solid #c4ccd6;padding:.3rem .6rem;\
text-align:left;vertical-align:top}.mistakes td:first-child{max-width:30rem}ul{margin:0;padding-left:1.1rem}\
.hist{width:100%;max-width:760px;height:auto}.hist .n,.hist .l{font-size:11px;fill:#1a1a1a}\
.tasks{display:grid;grid-template-columns:repeat(auto-fit,minmax(300px,1fr));gap:1rem}figure{margin:0}\
figcaption{font-weight:600}input{max-width:90%}a{color:#0060a0}.facts{color:#333}code{overflow-wrap:anywhere}\
td{overflow-wrap:anywhere}.scroll{overflow-x:auto}@media (max-width:600px){th,td{padding:.2rem .3rem;font-size:14px}}";

/// Points the explorer links at the address typed in the page.
const SCRIPT: &str = "document.getElementById('app').addEventListener('change',function(e){\
var base=e.target.value;document.querySelectorAll('a.case').forEach(function(a){\
a.href=base+a.getAttribute('data-q');});});";

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_and_texts_are_escaped() {
        let s = siftlab_mark::parse_json(
            r#"{"students": 1, "mistakes": [{"code": "rounded", "explanation": "e", "students": 1, "cases": 1,
                "tasks": ["dt"], "examples": [{"student": "<script>alert(1)</script>\"'", "case": "c", "link": "?a=1&b=\"x\""}]}]}"#,
        )
        .unwrap();
        let h = html(&s);
        assert!(!h.contains("<script>alert"), "{h}");
        assert!(h.contains("&lt;script&gt;alert(1)&lt;/script&gt;&quot;&#39;"));
        assert!(h.contains("href=\"http://localhost:8080/?a=1&amp;b=&quot;x&quot;\""));
        // One script, ours; no address but the app's.
        assert_eq!(h.matches("<script>").count(), 1);
        assert!(!h.contains("src=\"http"));
    }
}
