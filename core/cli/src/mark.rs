//! `siftlab mark vision_tasks.py [-n N] [--seed S] [--json] [--no-sandbox]`:
//! the student's file marked as the lab's automarker marks it
//! (docs/marking.md). This is the native transport of `core::mark::Session`:
//! the harness (`siftlab_mark::HARNESS_FILES`, written to a temporary folder)
//! runs in python3 inside a bubblewrap sandbox (`sandbox.rs`); requests go
//! to its stdin, replies and knn requests come from its stdout, and each
//! request's limit is the CPU time of the whole sandbox plus siftlab's knn
//! answers, with a wall-clock backstop. Exit status: 0 for 20 / 20, 1 for
//! fewer marks, 2 when the file could not be marked at all.

use crate::args::{Cli, MarkArgs};
use crate::common::{open_dataset, sift_params};
use crate::harness_io::{read_lines, FromHarness, TempDir, LINES_QUEUED};
use crate::report_files::{atomic_write, gradescope_json, sha256_hex};
use crate::sandbox::{self, Python, Tier};
use siftlab_core::dataset::Dataset;
use siftlab_core::error::{Error, Result};
use siftlab_core::sift::{detect_and_compute, Features, SiftParams};
use siftlab_mark::{
    escaped, knn_answer_until, parse_line, report_json, report_text, Case, HarnessLine, Limits, Marks, Outcome, Pair,
    Pairs, Session, Status, Step, Task,
};
use std::collections::HashMap;
use std::io::{Read, Write};
use std::process::{Child, Stdio};
use std::sync::mpsc::{sync_channel, Receiver, RecvTimeoutError, SyncSender, TrySendError};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

mod rerun;

/// A load or pair request the running harness took: id, line, limit, op, frame
/// (what a re-run gives a fresh harness first: `rerun`).
type Setup = (u64, String, f64, &'static str, Option<u32>);

/// How often a waiting request's CPU time and memory are read.
const POLL: Duration = Duration::from_millis(50);
/// Characters of a crashed harness's stderr kept for the report.
const STDERR_TAIL: usize = 2000;

/// Runs `mark` on one file and returns the exit status.
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

/// Marks one file and prints the report (text, or JSON with `--json`);
/// with `--gradescope`, also writes Gradescope's results.json.
pub fn run(cli: &Cli, a: &MarkArgs) -> Result<Marks> {
    let [arg] = a.files.as_slice() else {
        return Err(Error::InvalidArgument(format!(
            "{} submissions given: mark one file, or a class with --out DIR",
            a.files.len()
        )));
    };
    if a.jobs.is_some() || a.resume || a.shard.is_some() {
        return Err(Error::InvalidArgument("--jobs, --resume and --shard go with --out DIR (a class)".into()));
    }
    let started = Instant::now();
    // A folder (Gradescope's /autograder/submission): its first vision_tasks.py.
    let file = crate::submissions::single(arg)?;
    let n = a.n as usize;
    let Some(file) = file else {
        let marks = Marks::new(a.seed, n, Vec::new());
        eprintln!("siftlab: {} scores 0: no vision_tasks.py in it", arg.display());
        let text = format!("{}: 0.00 / 20\nscores 0: no vision_tasks.py was found in the submission\n", arg.display());
        write_platform_results(a, &marks, &text, true, "not run", started, &[])?;
        return Ok(marks);
    };
    let name = file.file_name().map_or_else(|| file.display().to_string(), |n| n.to_string_lossy().into_owned());
    let src = crate::submissions::read_single(arg, &file)?;
    let mut tier = "not run";
    let mut pictures = Vec::new();
    let marks = match crate::submissions::checked(&src) {
        Err(rejection) => {
            eprintln!("siftlab: {name} scores 0: {rejection}");
            Marks::rejected(a.seed, n, rejection)
        }
        Ok(source) => {
            let ds = open_dataset(cli)?;
            let frames = frame_ids(&ds)?;
            let runner = Runner::new(a.no_sandbox)?;
            tier = runner.tier.name();
            eprintln!(
                "marking {name}: {n} calls per task, seed {}, frames 1 to {} of {}",
                a.seed,
                frames.len(),
                ds.root().display()
            );
            // SIFT of each frame the cases use, once, as a class marking does.
            let (pairs, _) = frame_pairs(&ds, &sift_params(cli), &siftlab_mark::plan(a.seed, n, &frames), false)?;
            let session = Session::new(source, a.seed, n, &frames, Limits::default());
            let marks = runner.mark(session, &pairs, 0, true)?;
            if a.prairielearn.is_some() {
                pictures = crate::pictures::first_wrong(&marks, &ds, &pairs);
            }
            marks
        }
    };
    let text = format!("{}: {:.2} / 20\n{}", escaped(&name, 200), marks.total, report_text(&marks));
    let mut out = std::io::stdout().lock();
    if a.json {
        let _ = writeln!(out, "{}", report_json(&marks));
    } else {
        let _ = write!(out, "{text}");
    }
    let _ = out.flush();
    write_platform_results(a, &marks, &text, false, tier, started, &pictures)?;
    Ok(marks)
}

/// `--gradescope` and `--prairielearn`: each platform's results.json, written
/// whole (a temporary file and a rename), after the marking is over.
fn write_platform_results(
    a: &MarkArgs,
    marks: &Marks,
    text: &str,
    none_found: bool,
    tier: &str,
    started: Instant,
    pictures: &[crate::pictures::Picture],
) -> Result<()> {
    if let Some(g) = &a.gradescope {
        atomic_write(g, gradescope_json(marks, text, none_found, tier, started.elapsed().as_secs_f64()).as_bytes())?;
    }
    if let Some(p) = &a.prairielearn {
        atomic_write(p, crate::report_files::prairielearn_json(marks, text, none_found, tier, pictures).as_bytes())?;
    }
    Ok(())
}

/// The pairs the cases use, SIFT of each frame once, and (with
/// `fingerprint`) a SHA-256 over the frames' pixels, for `--resume`.
pub(crate) fn frame_pairs(
    ds: &Dataset,
    params: &SiftParams,
    cases: &[Case],
    fingerprint: bool,
) -> Result<(Vec<Pair>, String)> {
    let ids: std::collections::BTreeSet<u32> = cases.iter().map(Case::frame).collect();
    let mut frames: HashMap<u32, Features> = HashMap::new();
    let mut digests = Vec::new();
    for &f in &ids {
        for g in [f - 1, f] {
            if let std::collections::hash_map::Entry::Vacant(e) = frames.entry(g) {
                let img = ds.load_frame(g as usize)?;
                if fingerprint {
                    let mut bytes = format!("{g}:{}x{}:", img.width(), img.height()).into_bytes();
                    bytes.extend_from_slice(img.data());
                    digests.extend_from_slice(sha256_hex(&bytes).as_bytes());
                }
                e.insert(detect_and_compute(&img, params));
            }
        }
    }
    let pairs = ids.iter().map(|&f| Pair { id: f, prev: frames[&(f - 1)].clone(), cur: frames[&f].clone() }).collect();
    Ok((pairs, if fingerprint { sha256_hex(&digests) } else { String::new() }))
}

/// The pairs of a plan, computed beforehand (shared by a class's jobs).
struct Shared<'a>(&'a [Pair]);

impl Pairs for Shared<'_> {
    fn pair(&mut self, frame: u32) -> Result<&Pair> {
        self.0
            .iter()
            .find(|p| p.id == frame)
            .ok_or_else(|| Error::InvalidArgument(format!("frame pair {frame} was not computed")))
    }
}

/// FRAME_IDs 1.. whose frame and previous frame are in the dataset.
pub(crate) fn frame_ids(ds: &Dataset) -> Result<Vec<u32>> {
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

/// The strongest sandbox that works here: bubblewrap; where it cannot
/// make namespaces (a container) and siftlab runs as root, the container
/// tier. `SIFTLAB_SANDBOX=container` picks the container tier (as the
/// platforms' simulations and tests do on a machine with bubblewrap).
fn pick_tier(python: &Python, dir: &std::path::Path) -> Result<Tier> {
    #[cfg(not(target_os = "linux"))]
    return Err(Error::InvalidArgument(
        "no sandbox on this system (siftlab mark sandboxes with bubblewrap, on Linux): \
         pass --no-sandbox to check your own file with your own rights"
            .into(),
    ));
    let forced = std::env::var("SIFTLAB_SANDBOX").ok();
    let bwrap = match forced.as_deref() {
        Some("container") => Err("SIFTLAB_SANDBOX=container".to_string()),
        Some("bubblewrap") | None => sandbox::check(python, dir, Tier::Bubblewrap),
        Some(other) => {
            return Err(Error::InvalidArgument(format!(
                "SIFTLAB_SANDBOX={}: use bubblewrap or container (or unset it: the strongest that works)",
                escaped(other, 40)
            )))
        }
    };
    let Err(why) = bwrap else { return Ok(Tier::Bubblewrap) };
    if forced.as_deref() != Some("bubblewrap") && crate::container::possible() {
        return match sandbox::check(python, dir, Tier::Container) {
            Ok(()) => Ok(Tier::Container),
            Err(e) => Err(Error::InvalidArgument(format!(
                "no usable sandbox here: bubblewrap: {why}; the container tier: {e}. Pass --no-sandbox only \
                 to check your own file"
            ))),
        };
    }
    Err(Error::InvalidArgument(format!(
        "no usable sandbox here ({why}): siftlab mark runs student files in bubblewrap (apt install \
         bubblewrap; user namespaces must be allowed) or, as root inside a container (Gradescope, \
         PrairieLearn), as a uid of their own. Pass --no-sandbox only to check your own file"
    )))
}

/// Starts harness processes: the interpreter found outside, the harness
/// files, sandboxed or (with `--no-sandbox`) not.
pub(crate) struct Runner {
    python: Python,
    dir: TempDir,
    pub(crate) tier: Tier,
    /// Each harness gets a cgroup of its own (crate::cgroup).
    cgroups: bool,
}

impl Runner {
    pub(crate) fn new(no_sandbox: bool) -> Result<Runner> {
        let exe = std::env::var_os("SIFTLAB_PYTHON").unwrap_or_else(|| "python3".into());
        let python = Python::find(&exe)?;
        let dir = TempDir::new()?;
        for (file, text) in siftlab_mark::HARNESS_FILES {
            let path = dir.0.join(file);
            std::fs::write(&path, text)
                .map_err(|e| Error::InvalidArgument(format!("cannot write {}: {e}", path.display())))?;
        }
        let tier = if no_sandbox {
            eprintln!(
                "siftlab: --no-sandbox: the file runs with your own rights (your files, network, processes); \
                 use it only to check your own file"
            );
            Tier::None
        } else {
            pick_tier(&python, &dir.0)?
        };
        let cgroups = crate::cgroup::usable_or_say_why(sandbox::MEMORY_BYTES, sandbox::PROCESSES);
        Ok(Runner { python, dir, tier, cgroups })
    }

    /// Marks `source` on pairs computed beforehand (those of the plan of
    /// `seed`, `n`, `frames`), printing nothing; `job` picks the sandbox's uid
    /// (one per concurrent job).
    pub(crate) fn mark_quietly(
        &self,
        source: &str,
        seed: u64,
        n: usize,
        frames: &[u32],
        pairs: &[Pair],
        job: u32,
    ) -> Result<Marks> {
        let session = Session::new(source, seed, n, frames, Limits::default());
        self.mark(session, pairs, job, false)
    }

    /// Marks one student. A panic while marking (a fault of siftlab's that
    /// a reply reached) ends only this marking, as an error: the harness is
    /// ended by its `Drop` on the way out, and a class marks the next student.
    fn mark(&self, session: Session, pairs: &[Pair], job: u32, verbose: bool) -> Result<Marks> {
        let marking = std::panic::AssertUnwindSafe(|| self.mark_unguarded(session, pairs, job, verbose));
        let marks = std::panic::catch_unwind(marking).unwrap_or_else(|panic| {
            let why = panic
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| panic.downcast_ref::<String>().cloned())
                .unwrap_or_default();
            Err(Error::InvalidArgument(format!(
                "siftlab failed while marking this file (a fault of siftlab's, please report it): {}",
                escaped(&why, 300)
            )))
        });
        // The container tier's last word: no process of the marking uid may
        // exist when the mark is written (one that does could write after it),
        // and nothing it left where every user may write outlives it.
        let uid = sandbox::marking_uid(job);
        if self.tier == Tier::Container {
            if !crate::container::kill_uid(uid) {
                return Err(Error::InvalidArgument(format!(
                    "a process of the marking uid {uid} survived SIGKILL (pids {:?}): no mark is written; \
                     run the marking again",
                    crate::container::processes_of(uid)
                )));
            }
            crate::container::remove_litter(uid);
        }
        marks
    }

    fn mark_unguarded(&self, mut session: Session, pairs: &[Pair], job: u32, verbose: bool) -> Result<Marks> {
        if verbose {
            eprintln!(
                "python: {} (Python {}, {}), {}",
                self.python.exe.display(),
                self.python.version,
                self.python.numpy.as_ref().map_or("no numpy".into(), |v| format!("numpy {v}")),
                match self.tier {
                    Tier::Bubblewrap => "sandboxed (bubblewrap)",
                    Tier::Container => "sandboxed (container tier: its own uid, seccomp)",
                    Tier::None => "NOT sandboxed",
                }
            );
        }
        let mut harness: Option<Harness> = None;
        // The load and pairs the running harness has taken, to rebuild it
        // for a request re-run after the machine's slowness.
        let mut setup: Vec<Setup> = Vec::new();
        let mut task = None;
        let mut task_started = Instant::now();
        loop {
            let current = session.current().map(|c| c.task());
            if current != task {
                if let (Some(t), true) = (task, verbose) {
                    report_task(&session, t, task_started);
                }
                task = current;
                task_started = Instant::now();
            }
            match session.next(&mut Shared(pairs))? {
                Step::Start => {
                    drop(harness.take());
                    setup.clear();
                    harness = Some(Harness::start(&self.python, &self.dir.0, self.tier, job, self.cgroups)?);
                    session.started();
                }
                Step::Send { id, line, limit, op, pair } => {
                    let Some(h) = harness.as_mut() else {
                        return Err(Error::InvalidArgument("no harness is running".into()));
                    };
                    let mut outcome = h.request(&line, id, limit, pairs, &mut session.stray_lines, op);
                    if let Some(why) = h.slow.take() {
                        drop(harness.take());
                        // Only the load and the pair this request needs are given again.
                        let frame = pair.or(session.current().map(Case::frame));
                        let needed: Vec<Setup> =
                            setup.iter().filter(|s| s.3 == "load" || s.4 == frame).cloned().collect();
                        (harness, outcome) = self.rerun(&needed, (id, &line, limit, op), pairs, job, &why, outcome)?;
                        session.stray_lines += harness.as_ref().map_or(0, |h| h.stray);
                    }
                    if op != "call" && matches!(outcome, Outcome::Reply(..)) {
                        setup.push((id, line.clone(), limit, op, pair));
                    }
                    if !matches!(outcome, Outcome::Reply(..)) {
                        drop(harness.take());
                    }
                    session.outcome(outcome, &mut Shared(pairs))?;
                }
                Step::Done(marks) => {
                    if let Some(h) = harness.take() {
                        h.close();
                    }
                    if let (Some(r), true) = (&marks.rejection, verbose) {
                        eprintln!("siftlab: the file scores 0: {r}");
                    }
                    if session.stray_lines > 0 && verbose {
                        eprintln!(
                            "siftlab: {} line(s) from the file's process were no reply and were dropped",
                            session.stray_lines
                        );
                    }
                    return Ok(marks);
                }
            }
        }
    }
}

fn report_task(session: &Session, task: Task, started: Instant) {
    let of: Vec<_> = session.results().iter().filter(|r| r.case.task() == task).collect();
    let correct = of.iter().filter(|r| r.status == Status::Correct).count();
    eprintln!(
        "{}: {correct} of {} correct ({:.1} s, calls {:.1} s of CPU)",
        task.name(),
        of.len(),
        started.elapsed().as_secs_f64(),
        session.spent(task)
    );
}

/// The harness process: requests go in through a writer thread (a long
/// write never blocks the limits), lines come out through a reader thread.
struct Harness {
    child: Child,
    meter: crate::meter::Meter,
    /// Set when the last request hit its wall-clock limit waiting for a CPU.
    slow: Option<String>,
    /// Stray lines of a re-run's setup requests.
    stray: usize,
    /// A re-run's harness: the wall-clock limits leave out waits for a CPU.
    patient: bool,
    /// At most one message waits for the writer: a harness that stops
    /// reading its stdin cannot make siftlab queue answers.
    to_child: Option<SyncSender<Vec<u8>>>,
    lines: Receiver<FromHarness>,
    stderr: Arc<Mutex<Vec<u8>>>,
    /// The container tier's uid (every process of it is killed with the
    /// harness) and private folder (removed after).
    uid: Option<u32>,
    _scratch: Option<crate::container::Scratch>,
}

impl Harness {
    fn start(python: &Python, dir: &std::path::Path, tier: Tier, job: u32, cgroup: bool) -> Result<Harness> {
        let cgroup = if cgroup {
            let g = crate::cgroup::Cgroup::create(job, sandbox::MEMORY_BYTES, sandbox::PROCESSES);
            Some(g.map_err(|e| Error::InvalidArgument(format!("cannot make the sandbox's cgroup: {e}")))?)
        } else {
            None
        };
        // The container tier's private folder, owned by the marking uid.
        let scratch = match tier {
            Tier::Container => Some(
                crate::container::Scratch::new(sandbox::marking_uid(job), dir)
                    .map_err(|e| Error::InvalidArgument(format!("cannot make the sandbox's folder: {e}")))?,
            ),
            _ => None,
        };
        let mut child = python
            .command(
                scratch.as_ref().map_or(dir, |s| s.harness()),
                tier,
                job,
                cgroup.as_ref(),
                scratch.as_ref().map_or(dir, |s| s.home()),
            )
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .map_err(|e| Error::InvalidArgument(format!("cannot start the harness: {e}")))?;
        let (Some(mut stdin), Some(stdout), Some(mut stderr)) =
            (child.stdin.take(), child.stdout.take(), child.stderr.take())
        else {
            return Err(Error::InvalidArgument("the harness's pipes are missing".into()));
        };
        let (to_child, requests) = sync_channel::<Vec<u8>>(1);
        std::thread::spawn(move || {
            for mut msg in requests {
                msg.push(b'\n');
                if stdin.write_all(&msg).and_then(|_| stdin.flush()).is_err() {
                    break;
                }
            }
        });
        let (tx, lines) = sync_channel::<FromHarness>(LINES_QUEUED);
        std::thread::spawn(move || read_lines(stdout, tx));
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
                    let excess = t.len().saturating_sub(4 * STDERR_TAIL);
                    t.drain(..excess);
                }
            }
        });
        let pid = child.id();
        let meter = crate::meter::Meter::new(pid, cgroup);
        Ok(Harness {
            child,
            meter,
            slow: None,
            stray: 0,
            patient: false,
            to_child: Some(to_child),
            lines,
            stderr: tail,
            uid: scratch.is_some().then_some(sandbox::marking_uid(job)),
            _scratch: scratch,
        })
    }

    /// Sends request `id` and waits for its reply, answering knn requests;
    /// a call's time is the sandbox's CPU time plus the knn answers' (counted
    /// while they are computed), with a wall-clock backstop; harness work the
    /// file can patch (`op` load or pair) is timed by the wall clock, as the
    /// lab times a load.
    fn request(&mut self, line: &str, id: u64, limit: f64, pairs: &[Pair], stray: &mut usize, op: &str) -> Outcome {
        let Some(start) = self.meter.read() else {
            return Outcome::Crashed(self.ended(), 0.0);
        };
        let cpu0 = start.cpu;
        if let Some(tx) = &self.to_child {
            if let Err(TrySendError::Full(_)) = tx.try_send(line.as_bytes().to_vec()) {
                // Messages of earlier requests still unread: the harness
                // stopped reading (an honest one reads every answer).
                self.kill();
                return Outcome::Crashed("the harness stopped reading siftlab's messages".into(), 0.0);
            }
        }
        let t0 = Instant::now();
        let by_wall = op != "call";
        let wall =
            Duration::try_from_secs_f64(if by_wall { limit } else { limit * Limits::default().wall_factor }.max(0.0))
                .unwrap_or(Duration::MAX);
        // The time charged: wall time for harness work, CPU time for a call.
        let charged = |cpu: f64| if by_wall { t0.elapsed().as_secs_f64().max(cpu) } else { cpu };
        let mut host = 0.0;
        let mut used = 0.0;
        loop {
            match self.lines.recv_timeout(POLL) {
                Ok(FromHarness::Line(l)) => match parse_line(&l, id) {
                    HarnessLine::Knn => {
                        // The harness waits for the answer: its CPU so far,
                        // plus siftlab's as it works, is the call's time.
                        let sandbox_cpu = self.meter.read().map_or(used - host, |r| r.cpu - cpu0);
                        let c0 = sandbox::thread_cpu();
                        let answer = knn_answer_until(&l, pairs, &mut || {
                            sandbox_cpu + host + (sandbox::thread_cpu() - c0) <= limit && t0.elapsed() <= wall
                        });
                        host += sandbox::thread_cpu() - c0;
                        used = used.max(sandbox_cpu + host);
                        let Some(answer) = answer else {
                            self.kill();
                            return Outcome::Timeout(used.max(limit.min(t0.elapsed().as_secs_f64())));
                        };
                        if let Some(tx) = &self.to_child {
                            // Full: the harness has not read the last answer
                            // (an honest one always has): this one is dropped.
                            if let Err(TrySendError::Full(_)) = tx.try_send(answer.into_bytes()) {
                                *stray += 1;
                            }
                        }
                    }
                    HarnessLine::Reply(_) => {
                        let cpu = self.meter.read().map_or(used, |r| r.cpu - cpu0 + host);
                        return Outcome::Reply(l, charged(cpu.max(used)));
                    }
                    HarnessLine::Stray(_) => *stray += 1,
                },
                Ok(FromHarness::TooLong) => *stray += 1,
                Err(RecvTimeoutError::Timeout) => {}
                Err(RecvTimeoutError::Disconnected) => {
                    if self.meter.hit_memory_limit() {
                        self.kill();
                        return Outcome::Crashed(self.over_memory(), charged(used));
                    }
                    return Outcome::Crashed(self.ended(), charged(used));
                }
            }
            let last = match self.meter.read() {
                Some(r) => r,
                None if self.meter.hit_memory_limit() => {
                    self.kill();
                    return Outcome::Crashed(self.over_memory(), charged(used));
                }
                None => return Outcome::Crashed(self.ended(), charged(used)),
            };
            used = last.cpu - cpu0 + host;
            if last.memory > sandbox::MEMORY_BYTES || self.meter.hit_memory_limit() {
                self.kill();
                return Outcome::Crashed(self.over_memory(), charged(used));
            }
            let elapsed = t0.elapsed().as_secs_f64();
            // A re-run (`patient`) does not count the time it waited for a
            // CPU, up to 4 × its wall-clock limit in all.
            let waited = if self.patient { crate::meter::machine_wait(&start, &last, used - host) } else { 0.0 };
            let over_wall = elapsed - waited > wall.as_secs_f64() || elapsed > 4.0 * wall.as_secs_f64();
            if used > limit || over_wall {
                if used <= limit && crate::meter::machine_fault(&start, &last, elapsed, used - host) {
                    self.slow = Some(format!(
                        "reached its {:.0} s of wall time having run {:.1} s of CPU and waited {:.1} s for one",
                        wall.as_secs_f64(),
                        used,
                        last.wait - start.wait
                    ));
                }
                self.kill();
                return Outcome::Timeout(if by_wall { limit } else { used.max(limit.min(elapsed)) });
            }
        }
    }

    fn over_memory(&self) -> String {
        format!("it used over {} GB of memory", sandbox::MEMORY_BYTES >> 30)
    }

    /// The exit status and the end of stderr of a process that ended.
    fn ended(&mut self) -> String {
        self.to_child = None;
        let status = self.child.wait().map_or_else(|e| e.to_string(), |s| s.to_string());
        // The stderr thread may still be reading the last bytes.
        std::thread::sleep(Duration::from_millis(50));
        let tail = self.stderr.lock().map(|t| String::from_utf8_lossy(&t).trim().to_string()).unwrap_or_default();
        self.meter.kill();
        if tail.is_empty() {
            status
        } else {
            let skip = tail.chars().count().saturating_sub(STDERR_TAIL);
            let tail: String = tail.chars().skip(skip).collect();
            format!("{status}; stderr: {}", escaped(&tail, STDERR_TAIL))
        }
    }

    /// Ends the sandbox: every process in it (in the container tier, every
    /// process of its uid: a daemon left by `setsid` is no longer its child).
    fn kill(&mut self) {
        self.to_child = None;
        self.meter.kill();
        let _ = self.child.kill();
        let _ = self.child.wait();
        if let Some(uid) = self.uid {
            crate::container::kill_uid(uid);
            crate::container::remove_litter(uid);
        }
    }

    /// Ends the process normally (stdin closed, it returns), then makes
    /// sure nothing it started is left.
    fn close(mut self) {
        self.to_child = None;
        let deadline = Instant::now() + Duration::from_secs(5);
        while Instant::now() < deadline {
            if let Ok(Some(_)) = self.child.try_wait() {
                break;
            }
            std::thread::sleep(Duration::from_millis(20));
        }
        self.kill();
    }
}

impl Drop for Harness {
    fn drop(&mut self) {
        self.kill();
    }
}
