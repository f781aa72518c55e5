//! `siftlab mark SUBMISSIONS... --out DIR`: a class folder of 45 submissions
//! built from the marking fixtures (correct, broken, hostile, non-ASCII,
//! empty, folders, bare files, a nested file, a folder with none), marked
//! with one job and with two; each student's row equals marking that file
//! alone; `--resume` after a `kill -9` halfway gives the same grades.csv;
//! three shards run as separate processes and merged give it too; every
//! results.json has Gradescope's fields. On frames 0-3 of the demo, one call
//! per task (docs/marking.md, "A whole class").

#![cfg(not(target_arch = "wasm32"))]

use siftlab_core::json;

use json::Json;
use std::fs;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn scratch() -> PathBuf {
    let d = std::env::temp_dir().join(format!("siftlab-cli-class-{}", std::process::id()));
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

/// The class folder: (student id, the file marked or None).
fn class(root: &Path) -> (PathBuf, Vec<(String, Option<PathBuf>)>) {
    let dir = root.join("class");
    let fixtures = repo_root().join("tests/fixtures/mark");
    let mut students = Vec::new();
    let mut folder = |id: &str, from: &Path| {
        let d = dir.join(id);
        fs::create_dir_all(&d).unwrap();
        fs::copy(from, d.join("vision_tasks.py")).unwrap();
        students.push((id.to_string(), Some(d.join("vision_tasks.py"))));
    };
    for v in ["good", "le", "k100", "inverted", "round", "empty", "nn_none", "nn_zero", "wrong_type", "float64"] {
        folder(&format!("s_{v}"), &fixtures.join(v).join("vision_tasks.py"));
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
    // Bare files <id>.py.
    for id in ["bare_good", "bare_good2"] {
        fs::copy(fixtures.join("good/vision_tasks.py"), dir.join(format!("{id}.py"))).unwrap();
        students.push((id.to_string(), Some(dir.join(format!("{id}.py")))));
    }
    fs::write(dir.join("bare_empty.py"), b"").unwrap();
    students.push(("bare_empty".into(), Some(dir.join("bare_empty.py"))));
    // Nested: the shallowest vision_tasks.py wins over a deeper one; __MACOSX is ignored.
    let nested = dir.join("nested");
    fs::create_dir_all(nested.join("lab4/deeper")).unwrap();
    fs::create_dir_all(nested.join("__MACOSX")).unwrap();
    fs::copy(fixtures.join("good/vision_tasks.py"), nested.join("lab4/vision_tasks.py")).unwrap();
    fs::copy(fixtures.join("syntax/vision_tasks.py"), nested.join("lab4/deeper/vision_tasks.py")).unwrap();
    fs::copy(fixtures.join("syntax/vision_tasks.py"), nested.join("__MACOSX/vision_tasks.py")).unwrap();
    students.push(("nested".into(), Some(nested.join("lab4/vision_tasks.py"))));
    // A folder with none; a dot-folder, ignored.
    fs::create_dir_all(dir.join("no_file/notes")).unwrap();
    students.push(("no_file".into(), None));
    fs::create_dir_all(dir.join(".git")).unwrap();
    students.sort();
    (dir, students)
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

#[test]
fn a_whole_class() {
    let root = scratch();
    let ds = dataset(&root);
    let (dir, students) = class(&root);
    assert!(students.len() >= 40, "{}", students.len());
    let (d, o) = (dir.to_str().unwrap(), |name: &str| root.join(name).to_str().unwrap().to_string());
    let t0 = Instant::now();
    let one = run(&mut siftlab(&[d, "--out", &o("jobs1"), "--jobs", "1", "-n", "1", "--seed", "5"], &ds));
    let one_s = t0.elapsed().as_secs_f64();
    assert_eq!(one.status.code(), Some(0), "{}", text(&one.stderr));
    let grades = fs::read_to_string(root.join("jobs1/grades.csv")).unwrap();
    let lines: Vec<&str> = grades.lines().collect();
    assert_eq!(lines[0], "student,dt,nn,nndr,matching_info,total,status,reason");
    assert_eq!(lines.len(), students.len() + 1, "{grades}");
    let row =
        |id: &str| lines.iter().find(|l| l.starts_with(&format!("{id},"))).unwrap_or_else(|| panic!("{id}: {grades}"));
    assert!(row("s_good").ends_with(",20.00,ok,"), "{}", row("s_good"));
    assert!(row("nested").ends_with(",20.00,ok,"), "the shallowest file: {}", row("nested"));
    assert!(row("no_file").ends_with(",0.00,zero,none found"), "{}", row("no_file"));
    assert!(row("z_syntax").ends_with(",0.00,zero,syntax"));
    assert!(row("z_nonascii").ends_with(",0.00,zero,not ASCII"));
    assert!(row("z_imports").ends_with(",0.00,zero,import"));
    assert!(row("bare_empty").ends_with(",0.00,zero,empty"));

    // Two jobs: the same file.
    let t0 = Instant::now();
    let two = run(&mut siftlab(&[d, "--out", &o("jobs2"), "--jobs", "2", "-n", "1", "--seed", "5"], &ds));
    let two_s = t0.elapsed().as_secs_f64();
    assert_eq!(two.status.code(), Some(0), "{}", text(&two.stderr));
    assert_eq!(fs::read_to_string(root.join("jobs2/grades.csv")).unwrap(), grades);
    eprintln!(
        "class of {}: --jobs 1 {one_s:.1} s ({:.0} submissions/hour), --jobs 2 {two_s:.1} s ({:.0}/hour)",
        students.len(),
        students.len() as f64 * 3600.0 / one_s,
        students.len() as f64 * 3600.0 / two_s
    );

    // Each file alone (the non-hostile ones and a few hostile ones; the
    // checker marks every hostile file alone): its total is its row's.
    for (id, file) in &students {
        let Some(file) = file else { continue };
        if id.starts_with("h_")
            && !["h_always_equal", "h_network", "h_fork_bomb", "h_ansi_escapes"].contains(&id.as_str())
        {
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
    let done = |p: &Path| {
        fs::read_dir(p.join("students")).map(|r| r.flatten().filter(|e| e.path().join("report.json").exists()).count())
    };
    while done(Path::new(&out)).unwrap_or(0) < students.len() / 2 && Instant::now() < deadline {
        std::thread::sleep(Duration::from_millis(200));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    let kept = done(Path::new(&out)).unwrap();
    assert!(kept >= students.len() / 2 && kept < students.len(), "{kept} done at the kill");
    assert!(!Path::new(&out).join("grades.csv").exists());
    let again = run(&mut siftlab(&[d, "--out", &out, "--resume", "-n", "1", "--seed", "5"], &ds));
    assert_eq!(again.status.code(), Some(0), "{}", text(&again.stderr));
    let err = text(&again.stderr);
    assert_eq!(err.matches("kept from an earlier run").count(), kept, "{err}");
    assert_eq!(fs::read_to_string(Path::new(&out).join("grades.csv")).unwrap(), grades);

    // Three shards as separate processes, merged.
    let shards: Vec<_> = (1..=3)
        .map(|i| {
            siftlab(
                &[
                    d,
                    "--out",
                    &o(&format!("shard{i}")),
                    "--shard",
                    &format!("{i}/3"),
                    "--jobs",
                    "1",
                    "-n",
                    "1",
                    "--seed",
                    "5",
                ],
                &ds,
            )
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

    // Gradescope's results.json: the fields the autograder format asks for.
    for id in ["s_inverted", "z_syntax", "no_file"] {
        let r = fs::read_to_string(root.join("jobs1/students").join(id).join("results.json")).unwrap();
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
        assert!(fs::read_to_string(root.join("jobs1/students").join(id).join("report.txt")).unwrap().starts_with(id));
    }
    let _ = fs::remove_dir_all(&root);
}
