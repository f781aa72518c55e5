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

use std::collections::{HashMap, HashSet};
use std::fs;
use std::process::{Command, Output};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// Sampling period: fine enough for a bound of seconds, cheap enough (one
/// pass over /proc) not to load the machine it measures.
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
/// or in an uninterruptible (disk) wait; `None` once `root` has ended.
fn tree_busy(root: u32) -> Option<bool> {
    let mut parent: HashMap<u32, u32> = HashMap::new();
    for entry in fs::read_dir("/proc").ok()?.flatten() {
        let Some(pid) = entry.file_name().to_str().and_then(|s| s.parse::<u32>().ok()) else { continue };
        if let Some((_, ppid)) = stat(&format!("/proc/{pid}/stat")) {
            parent.insert(pid, ppid);
        }
    }
    // A zombie root (ended, not yet reaped) has no runnable thread either.
    match stat(&format!("/proc/{root}/stat")) {
        None | Some(('Z', _)) => return None,
        _ => {}
    }
    let mut tree = HashSet::from([root]);
    let mut grew = true;
    while grew {
        grew = false;
        for (&pid, ppid) in &parent {
            if tree.contains(ppid) && tree.insert(pid) {
                grew = true;
            }
        }
    }
    let busy = tree.iter().any(|pid| {
        fs::read_dir(format!("/proc/{pid}/task")).into_iter().flatten().flatten().any(|t| {
            let path = t.path().join("stat");
            matches!(stat(path.to_str().unwrap_or_default()), Some(('R' | 'D', _)))
        })
    });
    Some(busy)
}

/// (state, parent pid) from a /proc stat file; the command name in
/// parentheses may itself hold spaces and parentheses, so it is skipped from
/// its last ')'.
fn stat(path: &str) -> Option<(char, u32)> {
    let s = fs::read_to_string(path).ok()?;
    let mut rest = s[s.rfind(')')? + 1..].split_whitespace();
    let state = rest.next()?.chars().next()?;
    let ppid = rest.next()?.parse().ok()?;
    Some((state, ppid))
}
