//! Marking a whole class (docs/marking.md, "A whole class"):
//! `siftlab mark SUBMISSIONS... --out DIR [--jobs N] [--resume] [--shard I/K]`,
//! `siftlab mark --merge DIR... --out DIR` and
//! `siftlab mark SUBMISSION --gradescope RESULTS_JSON`.
//!
//! Every student gets the same cases (one seed): the frames' SIFT is computed
//! once per run and shared by the jobs; each job marks one student at a time
//! in a sandbox of its own (its own uid, so one student's processes never
//! count against another's limit). Each student's files are written
//! atomically when that student is done, under `DIR/students/<id>/`;
//! grades.csv at the end, a row for every entry found (refusals included).

use crate::args::{Cli, MarkArgs};
use crate::mark::{frame_ids, frame_pairs};
use crate::report_files::{atomic_write, gradescope_json, student_dir, Row, Status};
use crate::seal::{check_apart, Seal, SEAL_FILE};
use crate::submissions::{checked, discover, read_submission, Entry, Student};
use crate::transport::Runner;
use siftlab_core::error::{Error, Result};
use siftlab_mark::{escaped, parse_json, plan, report_json, report_text, Json, Marks, Pair, MAX_SOURCE_BYTES};
use std::collections::BTreeMap;
use std::io::IsTerminal;
use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::mpsc::channel;
use std::time::Instant;

/// `I/K` as (I, K), 1 ≤ I ≤ K.
fn parse_shard(text: &str) -> Result<(usize, usize)> {
    let bad = || Error::InvalidArgument(format!("--shard {text}: write it I/K with 1 <= I <= K, e.g. 2/3"));
    let (i, k) = text.split_once('/').ok_or_else(bad)?;
    let (i, k): (usize, usize) = (i.trim().parse().map_err(|_| bad())?, k.trim().parse().map_err(|_| bad())?);
    if i == 0 || k == 0 || i > k {
        return Err(bad());
    }
    Ok((i, k))
}

/// What a run records of itself in each report.json, for `--resume`.
struct RunKey {
    seed: u64,
    n: usize,
    dataset: String,
    frames: Vec<u32>,
}

/// `siftlab mark SUBMISSIONS... --out DIR`: exit 0 when every entry is
/// marked, 1 when some failed or were refused, 2 when the class cannot be
/// marked at all.
pub fn run(cli: &Cli, a: &MarkArgs, out: &Path) -> i32 {
    match run_class(cli, a, out) {
        Ok(rows) if rows.iter().all(Row::marked) => 0,
        Ok(_) => 1,
        Err(e) => {
            eprintln!("siftlab: error: {e}");
            2
        }
    }
}

fn run_class(cli: &Cli, a: &MarkArgs, out: &Path) -> Result<Vec<Row>> {
    check_apart(out, &a.files)?;
    let mut entries = discover(&a.files);
    if let Some(s) = &a.shard {
        let (i, k) = parse_shard(s)?;
        entries = entries.into_iter().enumerate().filter(|(j, _)| j % k == i - 1).map(|(_, e)| e).collect();
    }
    let mut rows: BTreeMap<(Vec<u8>, Vec<u8>), Row> = BTreeMap::new();
    let mut students = Vec::new();
    for e in entries {
        match e {
            Entry::Student(s) => students.push(s),
            Entry::Refused(r) => {
                eprintln!("siftlab: refused {}: {}", r.name, r.reason);
                let row = Row::refused(&r.name, &r.reason);
                rows.insert(row.key(), row);
            }
        }
    }
    std::fs::create_dir_all(out.join("students"))
        .map_err(|e| Error::InvalidArgument(format!("cannot create {}: {e}", out.display())))?;
    let seal = Seal::open(out)?;
    let n = a.n as usize;
    let ds = crate::common::open_dataset(cli)?;
    let frames = frame_ids(&ds)?;
    let cases = plan(a.seed, n, &frames);
    let t0 = Instant::now();
    let (pairs, dataset) = frame_pairs(&ds, &crate::common::sift_params(cli), &cases, true)?;
    drop(cases);
    let key = RunKey { seed: a.seed, n, dataset, frames };
    let runner = Runner::new(a.no_sandbox)?;
    let jobs = a.jobs.map_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()), |j| j as usize);
    if jobs > crate::sandbox::MAX_JOBS as usize {
        return Err(Error::InvalidArgument(format!(
            "--jobs {jobs}: at most {} students are marked at once",
            crate::sandbox::MAX_JOBS
        )));
    }
    // The container tier hides no shared folder (/tmp): two students marked at
    // once could pass answers through one. One at a time, each one's litter
    // removed before the next (container.rs).
    let jobs = if runner.tier == crate::sandbox::Tier::Container && jobs > 1 {
        eprintln!("siftlab: the container tier marks one student at a time (no private /tmp without namespaces)");
        1
    } else {
        jobs
    };
    eprintln!(
        "marking {} student(s) into {}: {n} calls per task, seed {}, {} job(s); SIFT of {} frame pair(s) in {:.1} s",
        students.len(),
        out.display(),
        a.seed,
        jobs,
        pairs.len(),
        t0.elapsed().as_secs_f64()
    );
    let mut todo = Vec::new();
    for s in students {
        match a.resume.then(|| resumed(out, &s, &key, &seal)).flatten() {
            Some(row) => {
                eprintln!("{}: {:.2} ({}), kept from an earlier run", row.student, row.total, row.status_text());
                rows.insert(row.key(), row);
            }
            None => todo.push(s),
        }
    }
    let next = AtomicUsize::new(0);
    let (tx, rx) = channel::<Row>();
    let total = todo.len();
    let started = Instant::now();
    let terminal = std::io::stderr().is_terminal();
    std::thread::scope(|scope| {
        for job in 0..jobs.min(total.max(1)) {
            let (tx, next, todo, runner, pairs, key, seal) = (tx.clone(), &next, &todo, &runner, &pairs, &key, &seal);
            scope.spawn(move || loop {
                let i = next.fetch_add(1, Ordering::SeqCst);
                let Some(s) = todo.get(i) else { break };
                let row = mark_student(s, out, runner, pairs, (key, seal), job as u32);
                if tx.send(row).is_err() {
                    break;
                }
            });
        }
        drop(tx);
        for (done, row) in rx.iter().enumerate() {
            let done = done + 1;
            let mut line = format!("[{done}/{total}] {}: {:.2} ({})", row.student, row.total, row.status_text());
            if terminal && done < total {
                let left = started.elapsed().as_secs_f64() / done as f64 * (total - done) as f64;
                line.push_str(&format!(", about {} left", minutes(left)));
            }
            eprintln!("{line}");
            rows.insert(row.key(), row);
        }
    });
    let rows: Vec<Row> = rows.into_values().collect();
    atomic_write(&out.join("grades.csv"), Row::csv(&rows).as_bytes())?;
    // The lecturer's picture of the class (a shard's is of its slice).
    crate::summary::write(&[out], out)?;
    let failed = rows.iter().filter(|r| r.status == Status::Failed).count();
    let refused = rows.iter().filter(|r| r.status == Status::Refused).count();
    eprintln!(
        "grades: {} ({} row(s), {failed} failed, {refused} refused) in {:.1} s; summary.html beside it",
        out.join("grades.csv").display(),
        rows.len(),
        t0.elapsed().as_secs_f64()
    );
    Ok(rows)
}

fn minutes(secs: f64) -> String {
    let s = secs.round() as u64;
    if s >= 60 {
        format!("{}m{:02}s", s / 60, s % 60)
    } else {
        format!("{s}s")
    }
}

/// The row of a report.json this `--out`'s key sealed for this student,
/// written by a run with the same key, for the same file, by this siftlab.
fn resumed(out: &Path, s: &Student, key: &RunKey, seal: &Seal) -> Option<Row> {
    let bytes = seal.verified(&s.id, &student_dir(out, &s.id))?;
    let j = parse_json(std::str::from_utf8(&bytes).ok()?).ok()?;
    let str_of = |k: &str| j.get(k).and_then(Json::as_str).map(str::to_string);
    let sha = match &s.file {
        Some(f) => Some(crate::report_files::sha256_hex(&read_submission(f, MAX_SOURCE_BYTES, false).ok()?.bytes)),
        None => None,
    };
    let same = j.get("seed").and_then(Json::as_i64).map(|v| v as u64) == Some(key.seed)
        && j.get("cases_per_task").and_then(Json::as_i64) == Some(key.n as i64)
        && str_of("dataset").as_deref() == Some(key.dataset.as_str())
        && str_of("sha256") == Some(sha.unwrap_or_default())
        && str_of("siftlab").as_deref() == Some(env!("CARGO_PKG_VERSION"));
    let row = Row::from_report(&s.id, &j)?;
    (same && row.status != Status::Failed).then_some(row)
}

/// Marks one student and writes its files (its seal first, report.json
/// last: a report.json there is a student done); the row for grades.csv.
fn mark_student(
    s: &Student,
    out: &Path,
    runner: &Runner,
    pairs: &[Pair],
    (key, seal): (&RunKey, &Seal),
    job: u32,
) -> Row {
    let dir = student_dir(out, &s.id);
    let started = std::time::Instant::now();
    // Read as the tree was found: no link followed, no FIFO waited on, at
    // most the size limit + 1 bytes; else the entry is refused, unmarked.
    let source = match &s.file {
        None => None,
        Some(file) => match read_submission(file, MAX_SOURCE_BYTES, false) {
            Ok(src) => Some(src),
            Err(reason) => return Row::refused(&s.id, &reason),
        },
    };
    let result = (|| -> Result<(Marks, Status, String, String)> {
        let Some(src) = &source else {
            return Ok((Marks::new(key.seed, key.n, Vec::new()), Status::Zero, "none found".into(), String::new()));
        };
        let sha = crate::report_files::sha256_hex(&src.bytes);
        let marks = match checked(src) {
            Err(r) => Marks::rejected(key.seed, key.n, r),
            Ok(source) => runner.mark_quietly(source, key.seed, key.n, &key.frames, pairs, job)?,
        };
        let (status, reason) = match &marks.rejection {
            Some(r) => (Status::Zero, crate::report_files::zero_reason(r)),
            None => (Status::Ok, String::new()),
        };
        Ok((marks, status, reason, sha))
    })();
    let (marks, status, reason, sha) = match result {
        Ok(v) => v,
        Err(e) => {
            (Marks::new(key.seed, key.n, Vec::new()), Status::Failed, escaped(&e.to_string(), 300), String::new())
        }
    };
    let row = Row::of(&s.id, &marks, status, &reason);
    // Where the file ran ("not run": refused, or none found, before any run).
    let tier = if s.file.is_some() && marks.rejection.is_none() { runner.tier.name() } else { "not run" };
    let head = format!(
        "{{\"student\": {}, \"status\": \"{}\", \"reason\": {}, \"sha256\": \"{sha}\", \"dataset\": \"{}\", \"siftlab\": \"{}\", \"sandbox\": \"{}\", ",
        Json::Str(s.id.clone()).to_json(),
        status.name(),
        Json::Str(reason.clone()).to_json(),
        key.dataset,
        env!("CARGO_PKG_VERSION"),
        tier
    );
    let report = report_json(&marks);
    let json = format!("{head}{}\n", report.strip_prefix('{').unwrap_or(&report));
    let mut text = format!("{}: {:.2} / 20\n", s.id, marks.total);
    match status {
        Status::Zero if s.file.is_none() => text.push_str("scores 0: no vision_tasks.py was found in the submission\n"),
        Status::Failed => text.push_str(&format!("could not be marked: {reason}\n")),
        _ => text.push_str(&report_text(&marks)),
    }
    let files = [
        (SEAL_FILE, seal.tag(&s.id, json.as_bytes())),
        ("report.txt", text.clone()),
        ("results.json", gradescope_json(&marks, &text, s.file.is_none(), tier, started.elapsed().as_secs_f64())),
        ("report.json", json),
    ];
    let written = std::fs::create_dir_all(&dir)
        .map_err(|e| Error::InvalidArgument(format!("cannot create {}: {e}", dir.display())))
        .and_then(|_| files.iter().try_for_each(|(name, body)| atomic_write(&dir.join(name), body.as_bytes())));
    match written {
        Ok(()) => row,
        Err(e) => Row::of(&s.id, &marks, Status::Failed, &escaped(&e.to_string(), 300)),
    }
}

/// `siftlab mark --merge DIR... --out DIR`: the shards' grades.csv as one.
pub fn merge(a: &MarkArgs, out: &Path) -> i32 {
    let run = || -> Result<Vec<Row>> {
        let mut rows: BTreeMap<(Vec<u8>, Vec<u8>), Row> = BTreeMap::new();
        for dir in &a.files {
            let path = dir.join("grades.csv");
            let text = std::fs::read_to_string(&path)
                .map_err(|e| Error::InvalidArgument(format!("cannot read {}: {e}", path.display())))?;
            for row in Row::parse_csv(&text).map_err(|e| Error::InvalidArgument(format!("{}: {e}", path.display())))? {
                if let Some(old) = rows.get(&row.key()) {
                    if *old != row {
                        return Err(Error::InvalidArgument(format!(
                            "{} is in two shards with different marks",
                            row.student
                        )));
                    }
                }
                rows.insert(row.key(), row);
            }
        }
        let rows: Vec<Row> = rows.into_values().collect();
        std::fs::create_dir_all(out)
            .map_err(|e| Error::InvalidArgument(format!("cannot create {}: {e}", out.display())))?;
        atomic_write(&out.join("grades.csv"), Row::csv(&rows).as_bytes())?;
        let shards: Vec<&Path> = a.files.iter().map(|d| d.as_path()).collect();
        crate::summary::write(&shards, out)?;
        eprintln!("grades: {} ({} student(s))", out.join("grades.csv").display(), rows.len());
        Ok(rows)
    };
    match run() {
        Ok(rows) if rows.iter().all(Row::marked) => 0,
        Ok(_) => 1,
        Err(e) => {
            eprintln!("siftlab: error: {e}");
            2
        }
    }
}
