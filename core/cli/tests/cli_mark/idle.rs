//! How long a marking run sat idle: wall time during which none of its
//! processes (siftlab, bubblewrap, the sandboxed interpreter, any thread of
//! them) was running, waiting for a CPU or waiting on the disk.
//!
//! A wall-clock bound on a whole marking depends on what else runs on the
//! machine (on a loaded CI machine the same run takes 2-3 × as long); the
//! idle time does not: a process waiting for a CPU is in state R. What the
//! bound is there to catch, siftlab waiting around after stopping a call
//! (a grace period, a wall-clock backstop instead of the CPU limit, a
//! harness that is never restarted), is idle time.

use std::fs;
use std::process::{Command, Output};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// Sampling period: fine enough for a bound of seconds, cheap enough (a walk
/// of a handful of processes) not to load the machine it measures.
const PERIOD: Duration = Duration::from_millis(100);

/// What one run took.
pub struct Watched {
    pub output: Output,
    pub wall: Duration,
    /// Sampled wall time with no process of the run running or runnable.
    pub idle: Duration,
    pub samples: u32,
}

/// Runs `cmd` to its end, sampling its process tree's states meanwhile.
pub fn run(cmd: &mut Command) -> Watched {
    let t0 = Instant::now();
    let child = cmd
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("cannot start the siftlab binary");
    let root = child.id();
    let done = Arc::new(AtomicBool::new(false));
    let sampler = {
        let done = Arc::clone(&done);
        std::thread::spawn(move || {
            let (mut idle, mut samples) = (Duration::ZERO, 0u32);
            let mut last = Instant::now();
            while !done.load(Ordering::Relaxed) {
                std::thread::sleep(PERIOD);
                let now = Instant::now();
                let busy = tree_busy(root);
                // A tree that has already ended is not idle time of the run.
                match busy {
                    Some(false) => idle += now - last,
                    Some(true) => {}
                    None => break,
                }
                samples += 1;
                last = now;
            }
            (idle, samples)
        })
    };
    let output = child.wait_with_output().expect("cannot wait for the siftlab binary");
    let wall = t0.elapsed();
    done.store(true, Ordering::Relaxed);
    let (idle, samples) = sampler.join().expect("the sampler panicked");
    Watched { output, wall, idle, samples }
}

/// Whether any thread of `root` or of its descendants is running, runnable
/// or in an uninterruptible (disk) wait; `None` once `root` has ended. The
/// tree is walked from `root` down (each thread's `children`, as siftlab's
/// own meter walks it), not found in a scan of all of /proc.
fn tree_busy(root: u32) -> Option<bool> {
    // A zombie root (ended, not yet reaped) has no runnable thread either.
    if matches!(state(&format!("/proc/{root}/stat")), None | Some('Z')) {
        return None;
    }
    let (mut stack, mut busy) = (vec![root], false);
    while let Some(pid) = stack.pop() {
        for task in fs::read_dir(format!("/proc/{pid}/task")).into_iter().flatten().flatten() {
            let path = task.path();
            busy |= matches!(state(&path.join("stat").to_string_lossy()), Some('R' | 'D'));
            let children = fs::read_to_string(path.join("children")).unwrap_or_default();
            stack.extend(children.split_whitespace().filter_map(|c| c.parse::<u32>().ok()));
        }
    }
    Some(busy)
}

/// The state letter of a /proc stat file; the command name before it, in
/// parentheses, may itself hold spaces and parentheses, so it is read from
/// the last ')'.
fn state(path: &str) -> Option<char> {
    let s = fs::read_to_string(path).ok()?;
    s[s.rfind(')')? + 1..].split_whitespace().next()?.chars().next()
}
