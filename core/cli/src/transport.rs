//! The native transport of `siftlab_mark::Session` for `siftlab mark`: the
//! harness (`siftlab_mark::HARNESS_FILES`, written to a temporary folder)
//! runs in python3 inside the sandbox (`sandbox.rs`: bubblewrap, or the
//! container tier); requests go to its stdin, replies and knn requests come
//! from its stdout, and each request's limit is the CPU time of the whole
//! sandbox plus siftlab's knn answers, with a wall-clock backstop. A harness
//! that times out or crashes is replaced (`rerun`) and the call re-sent.

use crate::harness_io::{read_lines, FromHarness, TempDir, LINES_QUEUED};
use crate::sandbox::{self, Python, Tier};
use siftlab_core::error::{Error, Result};
use siftlab_mark::{
    escaped, knn_answer_until, parse_line, Case, HarnessLine, Limits, Marks, Outcome, Pair, Pairs, Session, Status,
    Step, Task,
};
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

/// Starts harness processes: the interpreter found outside, the harness
/// files, sandboxed or (with `--no-sandbox`) not.
pub(crate) struct Runner {
    python: Python,
    dir: TempDir,
    pub(crate) tier: Tier,
    /// Each harness gets a cgroup of its own (crate::cgroup).
    cgroups: bool,
    /// The container's CPU count, where the container tier has no cgroup of its own.
    enclosing: Option<crate::cgroup::Enclosing>,
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
            sandbox::pick_tier(&python, &dir.0)?
        };
        let cgroups = crate::cgroup::usable_or_say_why(sandbox::MEMORY_BYTES, sandbox::PROCESSES);
        // In a container (Gradescope, PrairieLearn) /sys is read-only: the
        // container's own cgroup still counts the CPU of children the
        // kernel reaped, which a process tree loses (fixtures reaped_cpu,
        // cpu_farm).
        let enclosing = (tier == Tier::Container && !cgroups).then(crate::cgroup::Enclosing::find).flatten();
        if let Some(e) = &enclosing {
            eprintln!(
                "siftlab: in the container tier CPU time is read from the container's cgroup instead ({}, less \
                 siftlab's own): children the kernel reaped are counted; memory stays per process tree",
                e.file().display()
            );
        }
        Ok(Runner { python, dir, tier, cgroups, enclosing })
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
    pub(crate) fn mark(&self, session: Session, pairs: &[Pair], job: u32, verbose: bool) -> Result<Marks> {
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
                    harness = Some(Harness::start(
                        &self.python,
                        &self.dir.0,
                        self.tier,
                        job,
                        self.cgroups,
                        self.enclosing.clone(),
                    )?);
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
    fn start(
        python: &Python,
        dir: &std::path::Path,
        tier: Tier,
        job: u32,
        cgroup: bool,
        enclosing: Option<crate::cgroup::Enclosing>,
    ) -> Result<Harness> {
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
        let meter = crate::meter::Meter::new(pid, cgroup, enclosing);
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
                        let c0 = crate::meter::thread_cpu();
                        let answer = knn_answer_until(&l, pairs, &mut || {
                            sandbox_cpu + host + (crate::meter::thread_cpu() - c0) <= limit && t0.elapsed() <= wall
                        });
                        host += crate::meter::thread_cpu() - c0;
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
