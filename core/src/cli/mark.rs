//! `siftlab mark vision_tasks.py [-n N] [--seed S] [--json]`: the student's
//! file marked as the lab's automarker marks it (docs/marking.md). The file
//! runs in `python3 siftlab_harness.py` (the three `www/py` files, written to
//! a temporary folder), which asks siftlab for every `knnMatch` on its
//! stdout; `core::mark` draws the cases, computes the reference values,
//! judges the replies and writes the report. Exit status: 0 for 20 / 20,
//! 1 for fewer marks, 2 when the file could not be marked at all.

use super::args::{Cli, MarkArgs};
use super::common::{open_dataset, sift_params};
use crate::dataset::Dataset;
use crate::error::{Error, Result};
use crate::mark::{
    call_message, check_source, failed_call, judge, knn_answer, load_message, pair_message, parse_json, parse_line,
    plan, reference, report_json, report_text, Case, CaseResult, Diagnosis, ErrorKind, HarnessLine, Marks, Pair,
    Rejection, Reply, Task,
};
use crate::sift::{detect_and_compute, Features, SiftParams};
use std::collections::{HashMap, HashSet};
use std::io::{BufRead, BufReader, Read, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc::{channel, Receiver, RecvTimeoutError, Sender};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// The harness and the shims it loads, as the app serves them.
const FILES: [(&str, &str); 3] = [
    ("siftlab_harness.py", include_str!("../../../www/py/siftlab_harness.py")),
    ("cv2.py", include_str!("../../../www/py/cv2.py")),
    ("vision_tasks_base.py", include_str!("../../../www/py/vision_tasks_base.py")),
];

/// The lab's limits: 10 s per call, 300 s per task.
const CALL_LIMIT: Duration = Duration::from_secs(10);
const TASK_LIMIT: Duration = Duration::from_secs(300);
/// Python's start (and numpy's import) and the loading of the file: what
/// the reference marker allows (tests/scripts/mark_reference.py).
const START_LIMIT: Duration = Duration::from_secs(60);
/// A pair message is the harness's own work (a few hundred KB to decode).
const PAIR_LIMIT: Duration = Duration::from_secs(60);

/// Runs `mark` and returns the exit status.
pub fn main(cli: &Cli, a: &MarkArgs) -> i32 {
    match run(cli, a) {
        Ok(m) if m.full() => 0,
        Ok(_) => 1,
        Err(e) => {
            eprintln!("siftlab: error: {e}");
            2
        }
    }
}

/// Marks the file and prints the report (text, or JSON with `--json`).
pub fn run(cli: &Cli, a: &MarkArgs) -> Result<Marks> {
    let name = a.file.file_name().map_or_else(|| a.file.display().to_string(), |n| n.to_string_lossy().into_owned());
    let n = a.n as usize;
    let bytes =
        std::fs::read(&a.file).map_err(|e| Error::InvalidArgument(format!("cannot read {}: {e}", a.file.display())))?;
    let marks = match check_source(&bytes) {
        Err(rejection) => {
            eprintln!("siftlab: {name} scores 0: {rejection}");
            Marks::rejected(a.seed, n, rejection)
        }
        Ok(source) => {
            let ds = open_dataset(cli)?;
            let frames = frame_ids(&ds)?;
            eprintln!(
                "marking {name}: {n} calls per task, seed {}, frames 1 to {} of {}",
                a.seed,
                frames.len(),
                ds.root().display()
            );
            let mut m = Marker::new(ds, sift_params(cli))?;
            m.mark(source, &plan(a.seed, n, &frames), a.seed, n)?
        }
    };
    let mut out = std::io::stdout().lock();
    if a.json {
        let _ = writeln!(out, "{}", report_json(&marks));
    } else {
        let _ = writeln!(out, "{name}: {:.2} / 20", marks.total);
        let _ = write!(out, "{}", report_text(&marks));
    }
    let _ = out.flush();
    Ok(marks)
}

/// FRAME_IDs 1.. whose frame and previous frame are in the dataset.
fn frame_ids(ds: &Dataset) -> Result<Vec<u32>> {
    let count = ds.frame_count() as u32;
    if count < 2 {
        return Err(Error::Dataset(format!(
            "{} has {count} frame(s) in {}/ from 000000.png on: marking needs at least two",
            ds.root().display(),
            ds.sequence().frame_dir()
        )));
    }
    Ok((1..count).collect())
}

/// The features of each frame (SIFT once per frame), the pairs built from
/// them, and the harness process.
struct Marker {
    ds: Dataset,
    params: SiftParams,
    frames: HashMap<u32, Features>,
    pairs: Vec<Pair>,
    dir: TempDir,
    harness: Option<Harness>,
    /// Whether Python's version was printed.
    announced: bool,
}

impl Marker {
    fn new(ds: Dataset, params: SiftParams) -> Result<Marker> {
        let dir = TempDir::new()?;
        for (file, text) in FILES {
            let path = dir.0.join(file);
            std::fs::write(&path, text)
                .map_err(|e| Error::InvalidArgument(format!("cannot write {}: {e}", path.display())))?;
        }
        Ok(Marker { ds, params, frames: HashMap::new(), pairs: Vec::new(), dir, harness: None, announced: false })
    }

    /// The pair of FRAME_ID `frame` (computed on first use), by its index.
    fn pair(&mut self, frame: u32) -> Result<usize> {
        if let Some(i) = self.pairs.iter().position(|p| p.id == frame) {
            return Ok(i);
        }
        for f in [frame - 1, frame] {
            if !self.frames.contains_key(&f) {
                let img = self.ds.load_frame(f as usize)?;
                self.frames.insert(f, detect_and_compute(&img, &self.params));
            }
        }
        let (prev, cur) = (self.frames[&(frame - 1)].clone(), self.frames[&frame].clone());
        self.pairs.push(Pair { id: frame, prev, cur });
        Ok(self.pairs.len() - 1)
    }

    /// A running harness with the file loaded (started again after a
    /// time-out or a crash); a load that fails is the file's rejection.
    fn start(&mut self, source: &str) -> Result<std::result::Result<(), Rejection>> {
        if self.harness.is_none() {
            let mut h = Harness::start(&self.dir.0)?;
            if !self.announced {
                eprintln!("python: {}", h.version);
                self.announced = true;
            }
            h.send(&load_message(source));
            match h.wait(START_LIMIT, &self.pairs)? {
                Waited::Reply(Reply::Ok { .. }) => {}
                Waited::Reply(Reply::Error { message, kind: ErrorKind::Protocol }) => {
                    return Err(Error::InvalidArgument(format!("the harness refused the file: {message}")));
                }
                Waited::Reply(Reply::Error { message, kind }) => return Ok(Err(Rejection::Load { kind, message })),
                Waited::Timeout => {
                    h.kill();
                    return Ok(Err(Rejection::LoadTimeout { seconds: START_LIMIT.as_secs_f64() }));
                }
                Waited::Ended(why) => {
                    return Err(Error::InvalidArgument(format!("python3 ended while loading the file: {why}")));
                }
            }
            self.harness = Some(h);
        }
        Ok(Ok(()))
    }

    fn mark(&mut self, source: &str, cases: &[Case], seed: u64, n: usize) -> Result<Marks> {
        if let Err(r) = self.start(source)? {
            eprintln!("siftlab: the file scores 0: {r}");
            return Ok(Marks::rejected(seed, n, r));
        }
        let mut results = Vec::with_capacity(cases.len());
        for task in Task::ALL {
            let (t0, mut spent) = (Instant::now(), Duration::ZERO);
            for case in cases.iter().filter(|c| c.task() == task) {
                let r = self.mark_case(source, case, &mut spent)?;
                results.push(r);
            }
            let of: Vec<&CaseResult> = results.iter().filter(|r| r.case.task() == task).collect();
            let correct = of.iter().filter(|r| r.status == crate::mark::Status::Correct).count();
            eprintln!(
                "{}: {correct} of {} correct ({:.1} s, calls {:.1} s)",
                task.name(),
                of.len(),
                t0.elapsed().as_secs_f64(),
                spent.as_secs_f64()
            );
        }
        if let Some(h) = self.harness.take() {
            h.close();
        }
        Ok(Marks::new(seed, n, results))
    }

    fn mark_case(&mut self, source: &str, case: &Case, spent: &mut Duration) -> Result<CaseResult> {
        let i = self.pair(case.frame())?;
        let expected = reference(case, &self.pairs[i].prev, &self.pairs[i].cur)?;
        if *spent >= TASK_LIMIT {
            let d = Diagnosis::TaskTimeLimit { seconds: TASK_LIMIT.as_secs_f64() };
            return Ok(failed_call(case, &expected, d, 0.0));
        }
        if let Err(r) = self.start(source)? {
            // Loaded before; failing now (it reads a file that changed?) is
            // no mark of the student's.
            return Err(Error::InvalidArgument(format!("the file failed to load again: {r}")));
        }
        let Some(h) = self.harness.as_mut() else {
            return Err(Error::InvalidArgument("the harness is not running".into()));
        };
        let id = case.frame();
        if !h.sent.contains(&id) {
            let p = &self.pairs[i];
            h.send(&pair_message(p.id, &p.prev, &p.cur));
            match h.wait(PAIR_LIMIT, &self.pairs)? {
                Waited::Reply(Reply::Ok { .. }) => {}
                other => return Err(Error::InvalidArgument(format!("the harness did not take pair {id}: {other:?}"))),
            }
            h.sent.insert(id);
        }
        let limit = CALL_LIMIT.min(TASK_LIMIT - *spent);
        h.send(&call_message(case, id, &expected));
        let t0 = Instant::now();
        let waited = h.wait(limit, &self.pairs)?;
        let took = t0.elapsed();
        *spent += took;
        let (prev, cur) = (&self.pairs[i].prev, &self.pairs[i].cur);
        Ok(match waited {
            Waited::Reply(Reply::Error { message, kind: ErrorKind::Protocol }) => {
                return Err(Error::InvalidArgument(format!("the harness refused a call: {message}")));
            }
            Waited::Reply(reply) => judge(case, &expected, &reply, prev, cur, took.as_secs_f64()),
            Waited::Timeout => {
                if let Some(h) = self.harness.take() {
                    h.kill();
                }
                let d = Diagnosis::Timeout { seconds: limit.as_secs_f64() };
                failed_call(case, &expected, d, took.as_secs_f64())
            }
            Waited::Ended(why) => {
                self.harness = None;
                failed_call(case, &expected, Diagnosis::Crashed(why), took.as_secs_f64())
            }
        })
    }
}

/// How waiting for a reply ended.
#[derive(Debug)]
enum Waited {
    Reply(Reply),
    Timeout,
    /// The process closed its stdout (it ended): its status and stderr.
    Ended(String),
}

/// `python3 siftlab_harness.py`: requests and knn answers go in through a
/// writer thread (a long write never blocks the time-outs), lines come out
/// through a reader thread.
struct Harness {
    child: Child,
    to_child: Option<Sender<Vec<u8>>>,
    lines: Receiver<String>,
    stderr: Arc<Mutex<Vec<u8>>>,
    /// Pairs this process holds.
    sent: HashSet<u32>,
    /// "Python 3.11.7, numpy 1.26.4", from the harness's hello.
    version: String,
}

impl Harness {
    fn start(dir: &Path) -> Result<Harness> {
        let python = std::env::var_os("SIFTLAB_PYTHON").unwrap_or_else(|| "python3".into());
        let mut child = Command::new(&python)
            .arg("siftlab_harness.py")
            .current_dir(dir)
            .env("PYTHONDONTWRITEBYTECODE", "1")
            .env("PYTHONUNBUFFERED", "1")
            .env("PYTHONIOENCODING", "utf-8")
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .map_err(|e| {
                let python = python.to_string_lossy();
                Error::InvalidArgument(if e.kind() == std::io::ErrorKind::NotFound {
                    format!(
                        "{python} not found: siftlab mark runs the student's file with Python 3 (install python3, \
                         or name one with SIFTLAB_PYTHON=/path/to/python3)"
                    )
                } else {
                    format!("cannot start {python}: {e}")
                })
            })?;
        let (Some(mut stdin), Some(stdout), Some(mut stderr)) =
            (child.stdin.take(), child.stdout.take(), child.stderr.take())
        else {
            return Err(Error::InvalidArgument("python3's pipes are missing".into()));
        };
        let (to_child, requests) = channel::<Vec<u8>>();
        std::thread::spawn(move || {
            for mut msg in requests {
                msg.push(b'\n');
                if stdin.write_all(&msg).and_then(|_| stdin.flush()).is_err() {
                    break;
                }
            }
        });
        let (tx, lines) = channel::<String>();
        std::thread::spawn(move || {
            let mut r = BufReader::with_capacity(1 << 20, stdout);
            let mut line = String::new();
            loop {
                line.clear();
                match r.read_line(&mut line) {
                    Ok(0) | Err(_) => break,
                    Ok(_) => {
                        if tx.send(line.trim_end_matches(['\n', '\r']).to_string()).is_err() {
                            break;
                        }
                    }
                }
            }
        });
        let tail = Arc::new(Mutex::new(Vec::new()));
        let keep = Arc::clone(&tail);
        std::thread::spawn(move || {
            let mut buf = [0u8; 4096];
            while let Ok(k) = stderr.read(&mut buf) {
                if k == 0 {
                    break;
                }
                if let Ok(mut t) = keep.lock() {
                    t.extend_from_slice(&buf[..k]);
                    let excess = t.len().saturating_sub(4000);
                    t.drain(..excess);
                }
            }
        });
        let mut h = Harness {
            child,
            to_child: Some(to_child),
            lines,
            stderr: tail,
            sent: HashSet::new(),
            version: String::new(),
        };
        let python = python.to_string_lossy();
        h.send("{\"op\": \"hello\"}");
        let line = match h.lines.recv_timeout(START_LIMIT) {
            Ok(line) => line,
            Err(RecvTimeoutError::Timeout) => {
                h.kill();
                return Err(Error::InvalidArgument(format!(
                    "{python} did not answer within {} s",
                    START_LIMIT.as_secs()
                )));
            }
            Err(RecvTimeoutError::Disconnected) => {
                return Err(Error::InvalidArgument(format!(
                    "{python} could not run siftlab's harness (Python 3.8 or later is needed): {}",
                    h.ended()
                )))
            }
        };
        let hello = parse_json(&line).ok().filter(|v| v.get("ok").is_some());
        let Some(hello) = hello else {
            h.kill();
            return Err(Error::InvalidArgument(format!("the harness did not start: {line}")));
        };
        let field = |k: &str| hello.get(k).and_then(|v| v.as_str()).map(str::to_string);
        h.version = format!(
            "{python} (Python {}, {})",
            field("python").unwrap_or_else(|| "?".into()),
            field("numpy").map_or("no numpy".into(), |v| format!("numpy {v}"))
        );
        Ok(h)
    }

    fn send(&self, msg: &str) {
        if let Some(tx) = &self.to_child {
            let _ = tx.send(msg.as_bytes().to_vec());
        }
    }

    /// Reads lines until a reply, answering knn requests from `pairs`,
    /// for at most `limit` (the answers' time included).
    fn wait(&mut self, limit: Duration, pairs: &[Pair]) -> Result<Waited> {
        let deadline = Instant::now() + limit;
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            match self.lines.recv_timeout(left) {
                Ok(line) => {
                    // The harness writes nothing else to stdout; a student's
                    // raw write to the file descriptor is skipped.
                    if !line.starts_with('{') {
                        continue;
                    }
                    match parse_line(&line)? {
                        HarnessLine::Knn => self.send(&knn_answer(&line, pairs)),
                        HarnessLine::Reply(r) => return Ok(Waited::Reply(r)),
                    }
                }
                Err(RecvTimeoutError::Timeout) => return Ok(Waited::Timeout),
                Err(RecvTimeoutError::Disconnected) => return Ok(Waited::Ended(self.ended())),
            }
        }
    }

    /// The exit status and the end of stderr of a process that ended.
    fn ended(&mut self) -> String {
        self.to_child = None;
        let status = self.child.wait().map_or_else(|e| e.to_string(), |s| s.to_string());
        // The stderr thread may still be reading the last bytes.
        std::thread::sleep(Duration::from_millis(50));
        let tail = self.stderr.lock().map(|t| String::from_utf8_lossy(&t).trim().to_string()).unwrap_or_default();
        if tail.is_empty() {
            status
        } else {
            format!("{status}; stderr: {tail}")
        }
    }

    /// Stops the process (a time-out): kill, then reap it.
    fn kill(self) {
        drop(self);
    }

    /// Ends the process normally: stdin closed, it returns.
    fn close(mut self) {
        self.to_child = None;
        let deadline = Instant::now() + Duration::from_secs(5);
        while Instant::now() < deadline {
            if let Ok(Some(_)) = self.child.try_wait() {
                return;
            }
            std::thread::sleep(Duration::from_millis(20));
        }
        self.kill();
    }
}

impl Drop for Harness {
    /// A process still running (an error ended the marking, a time-out) is
    /// killed and reaped; one that ended is only reaped.
    fn drop(&mut self) {
        self.to_child = None;
        if let Ok(None) = self.child.try_wait() {
            let _ = self.child.kill();
        }
        let _ = self.child.wait();
    }
}

/// A folder under the system's temporary directory, removed when dropped.
struct TempDir(PathBuf);

impl TempDir {
    fn new() -> Result<TempDir> {
        let nanos = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0, |d| d.subsec_nanos());
        let dir = std::env::temp_dir().join(format!("siftlab-mark-{}-{nanos}", std::process::id()));
        std::fs::create_dir_all(&dir)
            .map_err(|e| Error::InvalidArgument(format!("cannot create {}: {e}", dir.display())))?;
        Ok(TempDir(dir))
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}
