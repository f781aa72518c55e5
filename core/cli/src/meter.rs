//! What a running harness has used (docs/marking.md, "The sandbox", time):
//! from its cgroup where siftlab made one (every process that was ever in
//! it, memory of every kind), else from its process tree in /proc; and how
//! long its threads waited for a CPU, which tells the machine's slowness
//! from the file's own.

use crate::cgroup::{run_delay_seconds, Cgroup};
use crate::sandbox;

/// One reading.
#[derive(Clone, Copy, Debug)]
pub struct Reading {
    /// CPU seconds used so far.
    pub cpu: f64,
    /// Bytes of memory held now.
    pub memory: u64,
    /// Seconds the threads waited on a run queue, less the time the cgroup
    /// was held back by its own CPU quota (that wait is the file's doing).
    pub wait: f64,
    /// Seconds the cgroup was held back by its own quota.
    pub throttled: f64,
}

/// The meter of one harness process.
pub struct Meter {
    pid: u32,
    cgroup: Option<Cgroup>,
    oom0: u64,
}

impl Meter {
    pub fn new(pid: u32, cgroup: Option<Cgroup>) -> Meter {
        let oom0 = cgroup.as_ref().map_or(0, Cgroup::oom_kills);
        Meter { pid, cgroup, oom0 }
    }

    /// What the harness has used; `None` once its first process has ended.
    pub fn read(&self) -> Option<Reading> {
        let (tree_cpu, tree_memory) = sandbox::tree_usage(self.pid)?;
        let Some(g) = &self.cgroup else {
            let wait = tree_threads(self.pid).into_iter().map(run_delay_seconds).sum();
            return Some(Reading { cpu: tree_cpu, memory: tree_memory, wait, throttled: 0.0 });
        };
        let throttled = g.throttled_seconds();
        let wait: f64 = g.threads().into_iter().map(run_delay_seconds).sum();
        Some(Reading {
            cpu: g.cpu_seconds().unwrap_or(tree_cpu),
            memory: g.memory_bytes().unwrap_or(tree_memory).max(tree_memory),
            wait,
            throttled,
        })
    }

    /// Whether the kernel ended a process of the cgroup for its memory.
    pub fn hit_memory_limit(&self) -> bool {
        self.cgroup.as_ref().is_some_and(|g| g.oom_kills() > self.oom0)
    }

    /// SIGKILL to the tree and to everything in the cgroup.
    pub fn kill(&self) {
        sandbox::kill_tree(self.pid);
        if let Some(g) = &self.cgroup {
            g.kill_all();
        }
    }
}

/// Whether a request that reached its wall-clock limit did so waiting for a
/// CPU (the machine's fault) rather than sleeping, blocking or burning its
/// own quota (the file's): most of the time it did not run, it was ready
/// to, and its cgroup was not held back by its own quota.
pub fn machine_fault(start: &Reading, end: &Reading, elapsed: f64, cpu_used: f64) -> bool {
    let not_running = (elapsed - cpu_used).max(0.0);
    let waited = end.wait - start.wait;
    let throttled = end.throttled - start.throttled;
    not_running > 0.0 && throttled < 1.0 && waited >= 0.5 * not_running
}

/// The threads of `pid` and all its descendants.
fn tree_threads(pid: u32) -> Vec<u32> {
    let mut out = Vec::new();
    let mut stack = vec![pid];
    while let Some(p) = stack.pop() {
        if out.len() > 10_000 {
            break;
        }
        if let Ok(tasks) = std::fs::read_dir(format!("/proc/{p}/task")) {
            out.extend(tasks.flatten().filter_map(|t| t.file_name().to_str().and_then(|s| s.parse::<u32>().ok())));
        }
        stack.extend(sandbox::children(p));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn r(wait: f64, throttled: f64) -> Reading {
        Reading { cpu: 0.0, memory: 0, wait, throttled }
    }

    #[test]
    fn only_waiting_for_a_cpu_is_the_machines_fault() {
        // 30 s of wall, 1.5 s of CPU, 27 s ready and not running: the machine.
        assert!(machine_fault(&r(1.0, 0.0), &r(28.0, 0.0), 30.0, 1.5));
        // Asleep: it never waited for a CPU.
        assert!(!machine_fault(&r(1.0, 0.0), &r(1.2, 0.0), 30.0, 0.1));
        // Held back by its own quota (a farm of its own): the file.
        assert!(!machine_fault(&r(0.0, 0.0), &r(200.0, 20.0), 30.0, 9.0));
    }

    #[test]
    fn a_cgroup_counts_the_cpu_of_reaped_children() {
        let Ok(g) = Cgroup::create(7, 1 << 30, 64) else { return }; // not root, no cgroup: nothing to test
        let join = g.join_files();
        let mut cmd = std::process::Command::new("sh");
        // A child that burns CPU and is reaped by the shell's exit: gone
        // from /proc, still in the cgroup's count.
        cmd.args(["-c", "(i=0; while [ $i -lt 200000 ]; do i=$((i+1)); done) & wait"]);
        use std::os::unix::process::CommandExt;
        // SAFETY: as in sandbox.rs: open, write, close only.
        unsafe {
            cmd.pre_exec(move || {
                for f in &join {
                    let fd = libc::open(f.as_ptr(), libc::O_WRONLY);
                    libc::write(fd, b"0".as_ptr().cast(), 1);
                    libc::close(fd);
                }
                Ok(())
            });
        }
        let t = std::time::Instant::now();
        assert!(cmd.status().unwrap().success());
        let cpu = g.cpu_seconds().unwrap();
        assert!(cpu > 0.05 && cpu < t.elapsed().as_secs_f64() * 2.0 + 0.1, "{cpu}");
        assert!(g.threads().is_empty());
    }
}
