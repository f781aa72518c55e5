//! A class folder is a student's input (issue 51; docs/marking.md, "A whole
//! class"): each attack on the submission tree, the outputs and `--resume`
//! is rebuilt here at test time (links, FIFOs and sparse files do not belong
//! in git) in a class with two ordinary students (the correct file and a
//! broken one), marked with `--jobs 2 -n 1`. Each run must end on its own;
//! the ordinary rows equal marking those files alone; every entry has
//! exactly one row; nothing outside `--out` is written; a key file outside
//! the class shows in no output; no terminal escape is printed raw; the
//! attacker scores no more than its honest code.

#![cfg(not(target_arch = "wasm32"))]

use siftlab_core::json::{self, Json};
use std::collections::BTreeMap;
use std::fs;
use std::os::unix::fs::symlink;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn fixture(name: &str) -> PathBuf {
    repo_root().join("tests/fixtures/mark").join(name).join("vision_tasks.py")
}

/// A fresh folder of this test's own (`create_dir` fails on a name taken).
fn fresh_root() -> PathBuf {
    let nanos = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).unwrap().as_nanos();
    let d = std::env::temp_dir().join(format!("siftlab-class-hostile-{}-{nanos}", std::process::id()));
    fs::create_dir(&d).unwrap();
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

fn put(path: &Path, from: &Path) {
    fs::create_dir_all(path.parent().unwrap()).unwrap();
    fs::copy(from, path).unwrap();
}

/// `siftlab mark ARGS` with a 300 s end put on it from outside (exit 124:
/// the run did not end on its own).
fn siftlab(ds: &Path, args: &[&Path], rest: &[&str]) -> Output {
    let mut c = Command::new("timeout");
    c.args(["-s", "KILL", "300"]).arg(env!("CARGO_BIN_EXE_siftlab"));
    c.args(["--opencv-lanes", "8", "-d"]).arg(ds).arg("mark").args(args).args(rest);
    c.output().expect("cannot start siftlab")
}

const MARK: [&str; 6] = ["--jobs", "2", "-n", "1", "--seed", "5"];

/// Every path under `dir` (links not followed, `skip` left out) with what
/// says it changed: kind, size, mtime, and the bytes of small regular files.
fn snapshot(dir: &Path, skip: &Path, into: &mut BTreeMap<PathBuf, String>) {
    use std::os::unix::fs::MetadataExt;
    for e in fs::read_dir(dir).unwrap().flatten() {
        let p = e.path();
        if p == skip {
            continue;
        }
        let m = fs::symlink_metadata(&p).unwrap();
        let mut what = format!("{:?} {} {}.{}", m.file_type(), m.len(), m.mtime(), m.mtime_nsec());
        if m.file_type().is_symlink() {
            what.push_str(&format!(" -> {:?}", fs::read_link(&p).unwrap()));
        } else if m.is_file() && m.len() < 1 << 20 && !p.ends_with("secret/key.txt") {
            what.push_str(&format!(" {:?}", fs::read(&p).unwrap()));
        }
        into.insert(p.clone(), what);
        if m.is_dir() {
            snapshot(&p, skip, into);
        }
    }
}

/// grades.csv's rows (RFC 4180 as siftlab writes it), the header checked.
fn rows(out: &Path) -> Vec<Vec<String>> {
    let text = fs::read_to_string(out.join("grades.csv")).unwrap();
    let (mut recs, mut rec, mut cur, mut quoted) = (Vec::new(), Vec::new(), String::new(), false);
    let mut it = text.chars().peekable();
    while let Some(c) = it.next() {
        match (quoted, c) {
            (true, '"') if it.peek() == Some(&'"') => {
                cur.push('"');
                it.next();
            }
            (true, '"') => quoted = false,
            (true, c) => cur.push(c),
            (false, '"') => quoted = true,
            (false, ',') => rec.push(std::mem::take(&mut cur)),
            (false, '\r') => {}
            (false, '\n') => {
                rec.push(std::mem::take(&mut cur));
                recs.push(std::mem::take(&mut rec));
            }
            (false, c) => cur.push(c),
        }
    }
    assert_eq!(recs.remove(0).join(","), "student,dt,nn,nndr,matching_info,total,status,reason");
    recs
}

/// Every byte of every file under `dir` but the seal's key (random bytes, never shown).
fn all_bytes(dir: &Path, into: &mut Vec<u8>) {
    for e in fs::read_dir(dir).unwrap().flatten() {
        let m = fs::symlink_metadata(e.path()).unwrap();
        if e.file_name() == ".siftlab-key" {
            continue;
        } else if m.is_dir() {
            all_bytes(&e.path(), into);
        } else {
            into.extend(fs::read(e.path()).unwrap());
        }
    }
}

/// The class's fixed part: its root, dataset, a key file outside the class,
/// and the two ordinary files' rows when marked alone.
struct Fx {
    root: PathBuf,
    ds: PathBuf,
    secret: String,
    key_file: PathBuf,
    alone: BTreeMap<&'static str, Vec<String>>,
}

impl Fx {
    fn new() -> Fx {
        let root = fresh_root();
        let ds = dataset(&root);
        // A Python name: as a vision_tasks.py it would end in a NameError quoting it.
        let secret = format!("HOST_SECRET_{}", std::process::id());
        let key_file = root.join("secret/key.txt");
        fs::create_dir_all(key_file.parent().unwrap()).unwrap();
        fs::write(&key_file, format!("{secret}\n")).unwrap();
        // An access time far back: any read of the file (relatime) moves it.
        assert!(Command::new("touch")
            .args(["-a", "-d", "2000-01-01 00:00:00 UTC"])
            .arg(&key_file)
            .status()
            .unwrap()
            .success());
        let mut alone = BTreeMap::new();
        for (id, fx) in [("good", "good"), ("broken", "nn_none")] {
            let o = siftlab(&ds, &[&fixture(fx)], &["-n", "1", "--seed", "5", "--json"]);
            let j = json::parse(&String::from_utf8_lossy(&o.stdout)).unwrap();
            let Some(Json::Arr(tasks)) = j.get("tasks") else { panic!("{id}: no tasks") };
            let mut row: Vec<String> =
                tasks.iter().map(|t| format!("{:.2}", t.get("marks").and_then(Json::as_f64).unwrap())).collect();
            row.push(format!("{:.2}", j.get("total").and_then(Json::as_f64).unwrap()));
            alone.insert(id, row);
        }
        assert_eq!(alone["good"][4], "20.00");
        assert!(alone["broken"][4] != "20.00", "the broken file must lose marks at -n 1: {:?}", alone["broken"]);
        Fx { root, ds, secret, key_file, alone }
    }

    /// A class folder `name` holding the two ordinary students.
    fn class(&self, name: &str) -> PathBuf {
        let dir = self.root.join(name);
        put(&dir.join("good/vision_tasks.py"), &fixture("good"));
        put(&dir.join("broken/vision_tasks.py"), &fixture("nn_none"));
        dir
    }

    /// Marks `args` into a fresh `out`, checks what every run must hold,
    /// and returns the rows and the exit status.
    fn mark(&self, name: &str, args: &[&Path], expect: &[(&str, &str, &str)]) -> (Vec<Vec<String>>, Option<i32>) {
        let out = self.root.join(format!("out-{name}"));
        let (mut before, mut after) = (BTreeMap::new(), BTreeMap::new());
        snapshot(&self.root, &out, &mut before);
        let t0 = std::time::Instant::now();
        let o = siftlab(&self.ds, args, &[&["--out", out.to_str().unwrap()][..], &MARK].concat());
        let secs = t0.elapsed().as_secs_f64();
        let err = String::from_utf8_lossy(&o.stderr).into_owned();
        assert_ne!(o.status.code(), Some(124), "{name}: the run did not end on its own in 300 s: {err}");
        eprintln!("{name}: exit {:?} in {secs:.1} s", o.status.code());
        snapshot(&self.root, &out, &mut after);
        assert_eq!(before, after, "{name}: siftlab wrote outside --out: {err}");
        let rows = rows(&out);
        // Every entry exactly one row, with the status and reason expected.
        let got: Vec<(String, String, String)> =
            rows.iter().map(|r| (r[0].clone(), r[6].clone(), r[7].clone())).collect();
        assert_eq!(got.len(), expect.len(), "{name}: {got:?}\n{err}");
        for ((id, status, reason), (want_id, want_status, want_reason)) in got.iter().zip(expect) {
            assert!(
                id == want_id && status == want_status && reason.starts_with(want_reason),
                "{name}: row {id},{status},{reason}; expected {want_id},{want_status},{want_reason}…\n{err}"
            );
        }
        for id in ["good", "broken"] {
            let row = rows.iter().find(|r| r[0] == id).unwrap_or_else(|| panic!("{name}: no {id} row"));
            assert_eq!(row[1..6], self.alone[id][..], "{name}: {id} in the class and alone");
            assert_eq!(row[6], "ok", "{name}: {id}");
        }
        // No host secret and no raw escape in anything siftlab wrote or printed.
        let mut bytes = o.stdout.clone();
        bytes.extend(&o.stderr);
        all_bytes(&out, &mut bytes);
        let text = String::from_utf8_lossy(&bytes);
        assert!(!text.contains(&self.secret), "{name}: the key file's content is in an output");
        assert!(
            !bytes.contains(&0x1b) && !text.contains('\u{202e}'),
            "{name}: a raw escape or bidi override in an output"
        );
        (rows, o.status.code())
    }

    fn total(rows: &[Vec<String>], id: &str) -> f64 {
        rows.iter().find(|r| r[0] == id).unwrap_or_else(|| panic!("no {id} row: {rows:?}"))[5].parse().unwrap()
    }
}

#[test]
fn a_hostile_class() {
    let fx = Fx::new();
    let honest: f64 = fx.alone["broken"][4].parse().unwrap();
    let ok = |id| (id, "ok", "");

    // mallory's file a link to bob's (here: good's) file; a link to the key file.
    let c = fx.class("c-link-peer");
    put(&c.join("mallory/notes.txt"), &fixture("nn_none"));
    symlink("../good/vision_tasks.py", c.join("mallory/vision_tasks.py")).unwrap();
    let (r, code) = fx.mark("link-peer", &[&c], &[ok("broken"), ok("good"), ("mallory", "refused", "symlink")]);
    assert_eq!((code, Fx::total(&r, "mallory")), (Some(1), 0.0));

    let c = fx.class("c-link-key");
    fs::create_dir_all(c.join("mallory")).unwrap();
    symlink(&fx.key_file, c.join("mallory/vision_tasks.py")).unwrap();
    symlink(&fx.key_file, c.join("eve.py")).unwrap();
    let expect = [ok("broken"), ("eve", "refused", "symlink"), ok("good"), ("mallory", "refused", "symlink")];
    assert_eq!(fx.mark("link-key", &[&c], &expect).1, Some(1));

    // A FIFO in place of the file (a bare one and one in a folder).
    let c = fx.class("c-fifo");
    fs::create_dir_all(c.join("mallory")).unwrap();
    for p in [c.join("mallory/vision_tasks.py"), c.join("eve.py")] {
        assert!(Command::new("mkfifo").arg(&p).status().unwrap().success());
    }
    let expect = [
        ok("broken"),
        ("eve", "refused", "special file: a FIFO"),
        ok("good"),
        ("mallory", "refused", "special file: a FIFO"),
    ];
    assert_eq!(fx.mark("fifo", &[&c], &expect).1, Some(1));

    // A link to /dev/zero; a 2 GB sparse file (read no further than the size limit + 1).
    let c = fx.class("c-huge");
    fs::create_dir_all(c.join("mallory")).unwrap();
    symlink("/dev/zero", c.join("mallory/vision_tasks.py")).unwrap();
    fs::File::create(c.join("eve.py")).unwrap().set_len(2 << 30).unwrap();
    let expect = [ok("broken"), ("eve", "zero", "too large"), ok("good"), ("mallory", "refused", "symlink")];
    let (r, code) = fx.mark("huge", &[&c], &expect);
    assert_eq!((code, Fx::total(&r, "eve")), (Some(1), 0.0));
    let report = fs::read_to_string(fx.root.join("out-huge/students/eve/report.txt")).unwrap();
    assert!(report.contains("2147483648 bytes"), "{report}");

    // A folder of links to `.` (the search must not follow them): mallory's
    // own file lies deeper, under a real folder; it is what she scores.
    let c = fx.class("c-loops");
    fs::create_dir_all(c.join("mallory/a/b")).unwrap();
    for i in 0..12 {
        symlink(".", c.join(format!("mallory/a/l{i}"))).unwrap();
        symlink("..", c.join(format!("mallory/a/b/u{i}"))).unwrap();
    }
    put(&c.join("mallory/a/b/c/vision_tasks.py"), &fixture("nn_none"));
    let (r, code) = fx.mark("loops", &[&c], &[ok("broken"), ok("good"), ok("mallory")]);
    assert_eq!(code, Some(0));
    assert!(Fx::total(&r, "mallory") <= honest, "{r:?}");

    // grades.csv.py: its id is grades.csv, its files go under students/.
    let c = fx.class("c-names");
    put(&c.join("grades.csv.py"), &fixture("nn_none"));
    put(&c.join("students.py"), &fixture("nn_none"));
    // Names with terminal escapes, invalid UTF-8 and a bidi override: refused, shown escaped.
    use std::os::unix::ffi::OsStrExt;
    for name in [&b"evil\x1b[2J\x1b[H"[..], b"bad\xff", "rtl\u{202e}yp.py".as_bytes()] {
        put(&c.join(std::ffi::OsStr::from_bytes(name)).join("vision_tasks.py"), &fixture("good"));
    }
    // One id twice (a folder and a file): both rows, each naming the other.
    put(&c.join("dup/vision_tasks.py"), &fixture("good"));
    put(&c.join("dup.py"), &fixture("good"));
    let expect = [
        ("bad\\xff", "refused", "odd name"),
        ok("broken"),
        ("dup", "refused", "duplicate id"),
        ("dup", "refused", "duplicate id"),
        ("evil\\x1b[2J\\x1b[H", "refused", "odd name"),
        ok("good"),
        ("grades.csv", "ok", ""),
        ("rtl\\u202eyp.py", "refused", "odd name"),
        ("students", "ok", ""),
    ];
    let (r, code) = fx.mark("names", &[&c], &expect);
    assert_eq!(code, Some(1));
    assert!(Fx::total(&r, "grades.csv") <= honest && Fx::total(&r, "students") <= honest);
    let dups: Vec<&String> = r.iter().filter(|r| r[0] == "dup").map(|r| &r[7]).collect();
    for (this, other) in [("/dup ", "/dup.py"), ("/dup.py ", "/dup")] {
        assert!(dups.iter().any(|d| d.contains(this) && d.ends_with(other)), "{dups:?}");
    }
    assert!(fx.root.join("out-names/students/grades.csv/report.json").is_file());

    // `subs/*`: a folder inside mallory's submission claims good's id; each
    // argument is one submission, so the claim is mallory's own file.
    let c = fx.class("c-subs");
    put(&c.join("mallory/good/vision_tasks.py"), &fixture("nn_none"));
    let args: Vec<PathBuf> = ["broken", "good", "mallory"].iter().map(|s| c.join(s)).collect();
    let args: Vec<&Path> = args.iter().map(PathBuf::as_path).collect();
    let (r, code) = fx.mark("subs", &args, &[ok("broken"), ok("good"), ok("mallory")]);
    assert_eq!(code, Some(0));
    assert!(Fx::total(&r, "mallory") <= honest);
    // One submission folder (Gradescope's): a link or a FIFO found in it is
    // refused by name, at once, and no results.json claims a mark.
    let g = fx.root.join("gradescope");
    fs::create_dir_all(g.join("sub/lab")).unwrap();
    symlink(&fx.key_file, g.join("sub/vision_tasks.py")).unwrap();
    assert!(Command::new("mkfifo").arg(g.join("sub/lab/vision_tasks.py")).status().unwrap().success());
    for (folder, says) in [(g.join("sub"), "refused (symlink)"), (g.join("sub/lab"), "refused (special file: a FIFO)")]
    {
        let results = g.join("results.json");
        let o = siftlab(&fx.ds, &[&folder], &["-n", "1", "--gradescope", results.to_str().unwrap()]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{err}");
        assert!(err.contains(says) && !err.contains(&fx.secret), "{err}");
        assert!(!results.exists());
    }
    // Nothing outside the submission tree was read: the key file's access time has not moved.
    use std::os::unix::fs::MetadataExt;
    assert_eq!(fs::metadata(&fx.key_file).unwrap().atime(), 946_684_800, "the key file was read");
    let _ = fs::remove_dir_all(&fx.root);
}

#[test]
fn resume_trusts_only_siftlab() {
    let fx = Fx::new();
    let c = fx.class("c-resume");
    put(&c.join("mallory/vision_tasks.py"), &fixture("nn_none"));
    let (first, code) = fx.mark("resume", &[&c], &[("broken", "ok", ""), ("good", "ok", ""), ("mallory", "ok", "")]);
    assert_eq!(code, Some(0));
    let out = fx.root.join("out-resume");
    let key = fs::metadata(out.join(".siftlab-key")).unwrap();
    use std::os::unix::fs::PermissionsExt;
    assert_eq!((key.len(), key.permissions().mode() & 0o777), (32, 0o600));

    // mallory's record forged to 20.00: good's report with her file's SHA-256,
    // good's seal beside it; then broken's report edited with its seal kept.
    let students = out.join("students");
    let real = fs::read_to_string(students.join("mallory/report.json")).unwrap();
    let sha = |t: &str| t.split("\"sha256\": \"").nth(1).unwrap()[..64].to_string();
    let forged = fs::read_to_string(students.join("good/report.json"))
        .unwrap()
        .replace(&sha(&fs::read_to_string(students.join("good/report.json")).unwrap()), &sha(&real));
    fs::write(students.join("mallory/report.json"), forged.replace("\"good\"", "\"mallory\"")).unwrap();
    fs::copy(students.join("good/report.seal"), students.join("mallory/report.seal")).unwrap();
    let broken = fs::read_to_string(students.join("broken/report.json")).unwrap();
    fs::write(students.join("broken/report.json"), broken.replacen("\"status\": \"ok\"", "\"status\": \"ok\" ", 1))
        .unwrap();
    fs::remove_file(out.join("grades.csv")).unwrap();

    let o = siftlab(&fx.ds, &[&c], &[&["--out", out.to_str().unwrap(), "--resume"][..], &MARK].concat());
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(0), "{err}");
    assert!(err.contains("good: 20.00 (ok), kept from an earlier run"), "{err}");
    assert_eq!(err.matches("kept from an earlier run").count(), 1, "only good's record is siftlab's: {err}");
    assert_eq!(rows(&out), first, "the forged records were marked anew");

    // A key others can read is no secret: --resume refuses to trust it.
    fs::set_permissions(out.join(".siftlab-key"), fs::Permissions::from_mode(0o644)).unwrap();
    let o = siftlab(&fx.ds, &[&c], &[&["--out", out.to_str().unwrap(), "--resume"][..], &MARK].concat());
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains(".siftlab-key: owned by uid") && err.contains("not yours with 0600"), "{err}");

    // A student's folder as --out (where a planted report.json would be
    // read), or the class inside --out: refused before anything is written.
    let mut before = BTreeMap::new();
    snapshot(&fx.root, Path::new("/nonexistent"), &mut before);
    for (out, says) in [(c.join("mallory/out"), "--out is inside the submission"), (fx.root.clone(), "inside --out")] {
        let o = siftlab(&fx.ds, &[&c], &[&["--out", out.to_str().unwrap(), "--resume"][..], &MARK].concat());
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{err}");
        assert!(err.contains(says) && err.contains("choose an --out folder outside every submission"), "{err}");
    }
    let mut after = BTreeMap::new();
    snapshot(&fx.root, Path::new("/nonexistent"), &mut after);
    assert_eq!(before, after, "a refused --out wrote something");
    let _ = fs::remove_dir_all(&fx.root);
}
