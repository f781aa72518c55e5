//! `siftlab mark SUBMISSIONS... --out DIR`: a class folder of 41+ submissions
//! built from the marking fixtures (correct, broken, every hostile file,
//! non-ASCII, empty, folders, bare files, a nested file, a folder with none),
//! on frames 0-3 of the demo, one call per task (docs/marking.md, "A whole
//! class").
//!
//! The whole class is marked once, with two jobs, so every hostile file runs
//! beside ordinary students. What does not need the whole class runs on a
//! sub-class of 12 that holds one student of each kind and the hostile files
//! that reach for their neighbours (processes, network, equality): with one
//! job its rows must equal the same students' rows of the two-job class run
//! (so the job count and the class around a student change no row); `--resume`
//! after a `kill -9` halfway, three shards merged and Gradescope's fields are
//! checked on it too. Each file but the hostile ones outside the sub-class,
//! marked alone, gives its row's total.
//! (The whole class four times over took 423 s on a 2-core machine; this
//! takes about a third: docs/testing.md.)

#![cfg(not(target_arch = "wasm32"))]

use siftlab_core::json;

use json::Json;
use std::collections::BTreeMap;
use std::fs;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn scratch() -> PathBuf {
    let nanos = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0, |d| d.as_nanos());
    let d = std::env::temp_dir().join(format!("siftlab-cli-class-{}-{nanos}", std::process::id()));
    fs::create_dir_all(&d).unwrap();
    d
}

/// Frames 0-3 of the demo (FRAME_IDs 1-3).
fn dataset(root: &Path) -> PathBuf {
    let dir = root.join("MyKITTI");
    fs::create_dir_all(dir.join("gray/00/image_0")).unwrap();
    for i in 0..4 {
        let f = format!("gray/00/image_0/{i:06}.png");
        fs::copy(repo_root().join("www/demo/MyKITTI").join(&f), dir.join(&f)).unwrap();
    }
    dir
}

/// The students of the sub-class: one of each kind (correct, three broken,
/// refused by the lab's rules, bare files, nested, none found) and the
/// hostile files that reach for other students (a fork bomb, the network,
/// objects equal to everything).
const SUB: [&str; 12] = [
    "s_good",
    "s_inverted",
    "s_round",
    "s_empty",
    "z_syntax",
    "h_always_equal",
    "h_fork_bomb",
    "h_network",
    "bare_good",
    "bare_empty",
    "nested",
    "no_file",
];

/// A class folder at `dir` of the students `keep` accepts: (student id, the
/// file marked or None).
/// The fixtures with one common mistake each, in the class twice.
const MISTAKES: [&str; 9] = ["le", "k100", "inverted", "round", "empty", "nn_none", "nn_zero", "wrong_type", "float64"];

fn class(dir: &Path, keep: impl Fn(&str) -> bool) -> Vec<(String, Option<PathBuf>)> {
    let fixtures = repo_root().join("tests/fixtures/mark");
    let mut students = Vec::new();
    let mut folder = |id: &str, from: &Path| {
        if !keep(id) {
            return;
        }
        let d = dir.join(id);
        fs::create_dir_all(&d).unwrap();
        fs::copy(from, d.join("vision_tasks.py")).unwrap();
        students.push((id.to_string(), Some(d.join("vision_tasks.py"))));
    };
    for v in ["good", "le", "k100", "inverted", "round", "empty", "nn_none", "nn_zero", "wrong_type", "float64"] {
        folder(&format!("s_{v}"), &fixtures.join(v).join("vision_tasks.py"));
    }
    // Each common mistake twice (the class summary counts students per mistake).
    for v in MISTAKES {
        folder(&format!("t_{v}"), &fixtures.join(v).join("vision_tasks.py"));
    }
    for v in ["syntax", "nonascii", "imports"] {
        folder(&format!("z_{v}"), &fixtures.join(v).join("vision_tasks.py"));
    }
    let mut hostile: Vec<String> = fs::read_dir(fixtures.join("hostile"))
        .unwrap()
        .flatten()
        .filter(|e| e.path().is_dir())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    hostile.sort();
    for h in &hostile {
        folder(&format!("h_{h}"), &fixtures.join("hostile").join(h).join("vision_tasks.py"));
    }
    fs::create_dir_all(dir).unwrap();
    // Bare files <id>.py.
    for id in ["bare_good", "bare_good2"].into_iter().filter(|id| keep(id)) {
        fs::copy(fixtures.join("good/vision_tasks.py"), dir.join(format!("{id}.py"))).unwrap();
        students.push((id.to_string(), Some(dir.join(format!("{id}.py")))));
    }
    if keep("bare_empty") {
        fs::write(dir.join("bare_empty.py"), b"").unwrap();
        students.push(("bare_empty".into(), Some(dir.join("bare_empty.py"))));
    }
    // Nested: the shallowest vision_tasks.py wins over a deeper one; __MACOSX is ignored.
    if keep("nested") {
        let nested = dir.join("nested");
        fs::create_dir_all(nested.join("lab4/deeper")).unwrap();
        fs::create_dir_all(nested.join("__MACOSX")).unwrap();
        fs::copy(fixtures.join("good/vision_tasks.py"), nested.join("lab4/vision_tasks.py")).unwrap();
        fs::copy(fixtures.join("syntax/vision_tasks.py"), nested.join("lab4/deeper/vision_tasks.py")).unwrap();
        fs::copy(fixtures.join("syntax/vision_tasks.py"), nested.join("__MACOSX/vision_tasks.py")).unwrap();
        students.push(("nested".into(), Some(nested.join("lab4/vision_tasks.py"))));
    }
    // A folder with none; a dot-folder, ignored.
    if keep("no_file") {
        fs::create_dir_all(dir.join("no_file/notes")).unwrap();
        students.push(("no_file".into(), None));
    }
    fs::create_dir_all(dir.join(".git")).unwrap();
    students.sort();
    students
}

fn siftlab(args: &[&str], ds: &Path) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_siftlab"));
    c.args(["--opencv-lanes", "8", "-d"]).arg(ds).arg("mark").args(args);
    c
}

fn run(c: &mut Command) -> Output {
    c.output().expect("cannot start siftlab")
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

/// grades.csv's rows by student id (the header checked).
fn rows(grades: &str) -> BTreeMap<String, String> {
    let mut lines = grades.lines();
    assert_eq!(lines.next(), Some("student,dt,nn,nndr,matching_info,total,status,reason"), "{grades}");
    lines.map(|l| (l.split(',').next().unwrap_or_default().to_string(), l.to_string())).collect()
}

/// summary.json against a count made here from grades.csv and each
/// student's report.json: statuses, calls per task, and per diagnosis code
/// the students and cases, in the ranking's order (most students, then
/// most cases, then the code).
fn class_summary_counts(out: &Path, rows: &BTreeMap<String, String>) {
    let s = json::parse(&fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let int = |j: Option<&Json>| j.and_then(Json::as_i64).unwrap_or(-1);
    assert_eq!(int(s.get("students")), rows.len() as i64);
    let mut status: BTreeMap<String, i64> = BTreeMap::new();
    let mut codes: BTreeMap<String, (std::collections::BTreeSet<String>, i64)> = BTreeMap::new();
    let mut calls = [0i64; 4];
    let tasks = ["dt", "nn", "nndr", "matching_info"];
    for (id, row) in rows {
        // The ids here have no comma: the 7th field is the status.
        let st = row.split(',').nth(6).unwrap().to_string();
        *status.entry(st.clone()).or_default() += 1;
        if st != "ok" && st != "zero" {
            continue;
        }
        let r = json::parse(&fs::read_to_string(student_out(out, id).join("report.json")).unwrap()).unwrap();
        for c in r.get("cases").and_then(Json::as_arr).unwrap_or(&[]) {
            let task = c.get("task").and_then(Json::as_str).unwrap();
            calls[tasks.iter().position(|t| *t == task).unwrap()] += 1;
            if let Some(code) = c.get("diagnosis").and_then(Json::as_str) {
                let e = codes.entry(code.to_string()).or_default();
                e.0.insert(id.clone());
                e.1 += 1;
            }
        }
    }
    for (st, n) in &status {
        assert_eq!(int(s.get("status").and_then(|x| x.get(st))), *n, "status {st}");
    }
    for (i, t) in s.get("tasks").and_then(Json::as_arr).unwrap().iter().enumerate() {
        assert_eq!(int(t.get("calls")), calls[i], "{}", tasks[i]);
    }
    let mut want: Vec<(String, i64, i64)> = codes.into_iter().map(|(c, (who, n))| (c, who.len() as i64, n)).collect();
    want.sort_by(|a, b| (b.1, b.2).cmp(&(a.1, a.2)).then_with(|| a.0.cmp(&b.0)));
    let got: Vec<(String, i64, i64)> = s
        .get("mistakes")
        .and_then(Json::as_arr)
        .unwrap()
        .iter()
        .map(|m| {
            (m.get("code").and_then(Json::as_str).unwrap().to_string(), int(m.get("students")), int(m.get("cases")))
        })
        .collect();
    assert_eq!(got, want);
    assert!(got.len() >= 3 && got[0].1 >= 2, "a class of common mistakes shows them: {got:?}");
    let html = fs::read_to_string(out.join("summary.html")).unwrap();
    assert!(html.contains(&format!("<code>{}</code>", got[0].0)));
}

/// The folder of a student's own files in a class's output.
fn student_out(out: &Path, id: &str) -> PathBuf {
    out.join("students").join(id)
}

#[test]
fn a_whole_class() {
    let root = scratch();
    let ds = dataset(&root);
    let o = |name: &str| root.join(name).to_str().unwrap().to_string();

    // The whole class, two jobs.
    let all = root.join("class");
    let students = class(&all, |_| true);
    assert!(students.len() >= 40, "{}", students.len());
    let t0 = Instant::now();
    let two =
        run(&mut siftlab(&[all.to_str().unwrap(), "--out", &o("jobs2"), "--jobs", "2", "-n", "1", "--seed", "5"], &ds));
    let two_s = t0.elapsed().as_secs_f64();
    assert_eq!(two.status.code(), Some(0), "{}", text(&two.stderr));
    let whole = rows(&fs::read_to_string(root.join("jobs2/grades.csv")).unwrap());
    assert_eq!(whole.len(), students.len(), "{whole:?}");
    let row = |id: &str| whole.get(id).unwrap_or_else(|| panic!("{id}: {whole:?}")).as_str();
    assert!(row("s_good").ends_with(",20.00,ok,"), "{}", row("s_good"));
    assert!(row("nested").ends_with(",20.00,ok,"), "the shallowest file: {}", row("nested"));
    assert!(row("no_file").ends_with(",0.00,zero,none found"), "{}", row("no_file"));
    assert!(row("z_syntax").ends_with(",0.00,zero,syntax"));
    assert!(row("z_nonascii").ends_with(",0.00,zero,not ASCII"));
    assert!(row("z_imports").ends_with(",0.00,zero,import"));
    assert!(row("bare_empty").ends_with(",0.00,zero,empty"));
    class_summary_counts(&root.join("jobs2"), &whole);
    eprintln!(
        "class of {}: --jobs 2 {two_s:.1} s ({:.0} submissions/hour)",
        students.len(),
        students.len() as f64 * 3600.0 / two_s
    );

    // The sub-class, one job: each row the whole class's.
    let sub_dir = root.join("sub");
    let sub = class(&sub_dir, |id| SUB.contains(&id));
    assert_eq!(sub.len(), SUB.len());
    let d = sub_dir.to_str().unwrap();
    let one = run(&mut siftlab(&[d, "--out", &o("jobs1"), "--jobs", "1", "-n", "1", "--seed", "5"], &ds));
    assert_eq!(one.status.code(), Some(0), "{}", text(&one.stderr));
    let grades = fs::read_to_string(root.join("jobs1/grades.csv")).unwrap();
    let got = rows(&grades);
    let mut ids: Vec<&str> = got.keys().map(String::as_str).collect();
    ids.sort();
    let mut want = SUB.to_vec();
    want.sort();
    assert_eq!(ids, want);
    for (id, r) in &got {
        assert_eq!(r, row(id), "{id}: one job in the sub-class vs two jobs in the whole class");
    }

    // Each file alone: its total is its row's (every file but the hostile
    // ones outside the sub-class, which tests/security/hostile_check.py marks
    // alone).
    for (id, file) in &students {
        let Some(file) = file else { continue };
        if id.starts_with("h_") && !SUB.contains(&id.as_str()) {
            continue;
        }
        // A second copy of a mistake's file: the same row as the first.
        if let Some(v) = id.strip_prefix("t_") {
            let same = |r: &str| r.split_once(',').map(|x| x.1.to_string());
            assert_eq!(same(row(id)), same(row(&format!("s_{v}"))), "{id}");
            continue;
        }
        let alone = run(&mut siftlab(&[file.to_str().unwrap(), "-n", "1", "--seed", "5", "--json"], &ds));
        let j = json::parse(&text(&alone.stdout)).unwrap_or_else(|e| panic!("{id}: {e}: {}", text(&alone.stderr)));
        let total = j.get("total").and_then(Json::as_f64).unwrap_or_else(|| panic!("{id}: no total"));
        assert!(row(id).contains(&format!(",{total:.2},")), "{id} alone {total:.2}, in the class {}", row(id));
    }

    // --resume after kill -9 halfway: the same grades.csv.
    let out = o("resumed");
    let mut child = siftlab(&[d, "--out", &out, "--jobs", "2", "-n", "1", "--seed", "5"], &ds)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let deadline = Instant::now() + Duration::from_secs(600);
    let done = |p: &Path| sub.iter().filter(|(id, _)| student_out(p, id).join("report.json").exists()).count();
    while done(Path::new(&out)) < sub.len() / 2 && Instant::now() < deadline {
        std::thread::sleep(Duration::from_millis(100));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    let kept = done(Path::new(&out));
    assert!(kept >= sub.len() / 2 && kept < sub.len(), "{kept} done at the kill");
    assert!(!Path::new(&out).join("grades.csv").exists());
    let again = run(&mut siftlab(&[d, "--out", &out, "--resume", "-n", "1", "--seed", "5"], &ds));
    assert_eq!(again.status.code(), Some(0), "{}", text(&again.stderr));
    let err = text(&again.stderr);
    assert_eq!(err.matches("kept from an earlier run").count(), kept, "{err}");
    assert_eq!(fs::read_to_string(Path::new(&out).join("grades.csv")).unwrap(), grades);

    // Three shards as separate processes, merged.
    let shards: Vec<_> = (1..=3)
        .map(|i| {
            let shard = format!("{i}/3");
            let out = o(&format!("shard{i}"));
            siftlab(&[d, "--out", &out, "--shard", &shard, "--jobs", "1", "-n", "1", "--seed", "5"], &ds)
                .stderr(Stdio::piped())
                .spawn()
                .unwrap()
        })
        .collect();
    for s in shards {
        let out = s.wait_with_output().unwrap();
        assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    }
    let merged = run(&mut siftlab(&["--merge", &o("shard1"), &o("shard2"), &o("shard3"), "--out", &o("merged")], &ds));
    assert_eq!(merged.status.code(), Some(0), "{}", text(&merged.stderr));
    assert_eq!(fs::read_to_string(root.join("merged/grades.csv")).unwrap(), grades);
    // The shards' summary is the one-run class's; --summary rebuilds it.
    let summary_of = |d: &str| fs::read_to_string(root.join(d).join("summary.json")).unwrap();
    assert_eq!(summary_of("merged"), summary_of("jobs1"));
    fs::remove_file(root.join("jobs1/summary.json")).unwrap();
    let again = run(&mut siftlab(&["--summary", &o("jobs1")], &ds));
    assert_eq!(again.status.code(), Some(0), "{}", text(&again.stderr));
    assert_eq!(summary_of("jobs1"), summary_of("merged"));

    // Gradescope's results.json: the fields the autograder format asks for.
    for id in ["s_inverted", "z_syntax", "no_file"] {
        let dir = student_out(&root.join("jobs1"), id);
        let r = fs::read_to_string(dir.join("results.json")).unwrap();
        let j = json::parse(&r).unwrap();
        for k in ["score", "max_score", "output", "tests"] {
            assert!(j.get(k).is_some(), "{id}: no {k}: {r}");
        }
        let Some(Json::Arr(tests)) = j.get("tests") else { panic!("{r}") };
        let names: Vec<String> = tests
            .iter()
            .map(|t| match t.get("name") {
                Some(Json::Str(s)) => s.clone(),
                _ => panic!("{r}"),
            })
            .collect();
        assert_eq!(names, ["dt", "nn", "nndr", "matching_info"]);
        for t in tests {
            for k in ["name", "score", "max_score", "output", "visibility"] {
                assert!(t.get(k).is_some(), "{id}: a test without {k}: {r}");
            }
        }
        assert!(fs::read_to_string(dir.join("report.txt")).unwrap().starts_with(id));
    }
    let _ = fs::remove_dir_all(&root);
}
