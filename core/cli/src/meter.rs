//! What a running harness has used (docs/marking.md, "The sandbox", time):
//! from its cgroup where siftlab made one (every process that was ever in
//! it, memory of every kind); in the container tier without one, CPU from
//! the container's own cgroup less siftlab's; else from its process tree
//! in /proc; and how
//! long its threads waited for a CPU, which tells the machine's slowness
//! from the file's own.

use crate::cgroup::{Cgroup, Enclosing};

/// One reading.
#[derive(Clone, Copy, Debug)]
pub struct Reading {
    /// CPU seconds used so far.
    pub cpu: f64,
    /// Bytes of memory held now.
    pub memory: u64,
    /// Seconds the harness process's threads waited on a run queue.
    pub wait: f64,
    /// Seconds the harness process's threads ran.
    pub run: f64,
    /// Seconds the cgroup was held back by its own quota.
    pub throttled: f64,
}

/// The meter of one harness process.
pub struct Meter {
    pid: u32,
    cgroup: Option<Cgroup>,
    /// The container's cgroup, where siftlab has none of its own for the harness.
    enclosing: Option<Enclosing>,
    oom0: u64,
    /// The harness's interpreter: below bubblewrap's processes, once found.
    harness: std::cell::Cell<Option<u32>>,
}

impl Meter {
    /// `enclosing`: the CPU count of the container siftlab runs in, used
    /// when `cgroup` is `None` (only the container tier passes one: it marks
    /// one student at a time, so nothing else of siftlab's runs there).
    pub fn new(pid: u32, cgroup: Option<Cgroup>, enclosing: Option<Enclosing>) -> Meter {
        let oom0 = cgroup.as_ref().map_or(0, Cgroup::oom_kills);
        let enclosing = if cgroup.is_some() { None } else { enclosing };
        Meter { pid, cgroup, enclosing, oom0, harness: std::cell::Cell::new(None) }
    }

    /// What the harness has used; `None` once its first process has ended.
    pub fn read(&self) -> Option<Reading> {
        let (tree_cpu, tree_memory) = tree_usage(self.pid)?;
        let (run, wait) = process_schedstat(self.harness_pid());
        let Some(g) = &self.cgroup else {
            // A child that burns CPU and is reaped outside the tree is gone
            // from /proc but not from the container's count.
            let cpu = self.enclosing.as_ref().and_then(Enclosing::others_cpu_seconds).unwrap_or(tree_cpu);
            return Some(Reading { cpu, memory: tree_memory, wait, run, throttled: 0.0 });
        };
        Some(Reading {
            cpu: g.cpu_seconds().unwrap_or(tree_cpu),
            memory: g.memory_bytes().unwrap_or(tree_memory).max(tree_memory),
            wait,
            run,
            throttled: g.throttled_seconds(),
        })
    }

    /// The harness's interpreter: the first process below the started one
    /// that is not bubblewrap (the started one itself without a sandbox).
    fn harness_pid(&self) -> u32 {
        if let Some(p) = self.harness.get() {
            return p;
        }
        let mut p = self.pid;
        for _ in 0..4 {
            let comm = std::fs::read_to_string(format!("/proc/{p}/comm")).unwrap_or_default();
            if comm.trim() != "bwrap" {
                self.harness.set(Some(p));
                return p;
            }
            match children(p).first() {
                Some(&c) => p = c,
                None => break,
            }
        }
        p
    }

    /// Whether the kernel ended a process of the cgroup for its memory.
    pub fn hit_memory_limit(&self) -> bool {
        self.cgroup.as_ref().is_some_and(|g| g.oom_kills() > self.oom0)
    }

    /// SIGKILL to the tree and to everything in the cgroup.
    pub fn kill(&self) {
        kill_tree(self.pid);
        if let Some(g) = &self.cgroup {
            g.kill_all();
        }
    }
}

/// Whether a request that reached its wall-clock limit did so waiting for a
/// CPU (the machine's fault) rather than sleeping, blocking or crowding
/// itself out (the file's): the harness's own threads spent most of the
/// time they did not run ready to run, that wait is not explained by the
/// CPU the sandbox's other processes took meanwhile, and the sandbox was
/// not held back by its own quota. `cpu_used`: the sandbox's CPU seconds.
pub fn machine_fault(start: &Reading, end: &Reading, elapsed: f64, cpu_used: f64) -> bool {
    let main_cpu = (end.run - start.run).max(0.0);
    let not_running = (elapsed - main_cpu).max(0.0);
    let throttled = end.throttled - start.throttled;
    not_running > 0.0 && throttled < 1.0 && machine_wait(start, end, cpu_used) >= 0.5 * not_running
}

/// Seconds the harness's threads waited for a CPU that the sandbox's other
/// processes did not take meanwhile (none while it was held back by its own
/// quota): the wait that is the machine's.
pub fn machine_wait(start: &Reading, end: &Reading, cpu_used: f64) -> f64 {
    let main_cpu = (end.run - start.run).max(0.0);
    let others = (cpu_used - main_cpu).max(0.0);
    if end.throttled - start.throttled >= 1.0 {
        return 0.0;
    }
    (end.wait - start.wait - others).max(0.0)
}

/// Seconds run and seconds waited on a run queue by all threads of `pid`.
fn process_schedstat(pid: u32) -> (f64, f64) {
    let (mut run, mut wait) = (0.0, 0.0);
    if let Ok(tasks) = std::fs::read_dir(format!("/proc/{pid}/task")) {
        for t in tasks.flatten().take(10_000) {
            let text = std::fs::read_to_string(t.path().join("schedstat")).unwrap_or_default();
            let mut f = text.split_whitespace().map(|x| x.parse::<u64>().unwrap_or(0) as f64 * 1e-9);
            run += f.next().unwrap_or(0.0);
            wait += f.next().unwrap_or(0.0);
        }
    }
    (run, wait)
}

/// CPU seconds and resident bytes of a process and all its descendants
/// (what they have used so far, reaped children included).
pub fn tree_usage(pid: u32) -> Option<(f64, u64)> {
    // SAFETY: sysconf has no preconditions.
    let (tick, page) = unsafe { (libc::sysconf(libc::_SC_CLK_TCK) as f64, libc::sysconf(libc::_SC_PAGESIZE) as u64) };
    let mut stack = vec![pid];
    let (mut ticks, mut rss, mut seen) = (0u64, 0u64, 0usize);
    while let Some(p) = stack.pop() {
        seen += 1;
        if seen > 10_000 {
            break;
        }
        let Ok(stat) = std::fs::read_to_string(format!("/proc/{p}/stat")) else { continue };
        // Fields after the command name, which may hold spaces and ')'.
        let Some(rest) = stat.rfind(')').map(|i| &stat[i + 2..]) else { continue };
        let f: Vec<&str> = rest.split_whitespace().collect();
        // utime, stime, cutime, cstime are fields 14–17 of stat (11–14 here); rss is 24 (21).
        let n = |i: usize| f.get(i).and_then(|x| x.parse::<u64>().ok()).unwrap_or(0);
        ticks += n(11) + n(12) + n(13) + n(14);
        rss += n(21) * page;
        stack.extend(children(p));
    }
    (seen > 0).then_some((ticks as f64 / tick, rss))
}

/// The direct children of `pid`, over all its threads.
pub fn children(pid: u32) -> Vec<u32> {
    let mut out = Vec::new();
    if let Ok(tasks) = std::fs::read_dir(format!("/proc/{pid}/task")) {
        for t in tasks.flatten() {
            if let Ok(c) = std::fs::read_to_string(t.path().join("children")) {
                out.extend(c.split_whitespace().filter_map(|x| x.parse::<u32>().ok()));
            }
        }
    }
    out
}

/// SIGKILL to `pid`, its process group and every descendant.
pub fn kill_tree(pid: u32) {
    let mut all = vec![pid];
    let mut i = 0;
    while i < all.len() && all.len() < 10_000 {
        let c = children(all[i]);
        all.extend(c);
        i += 1;
    }
    for p in all.iter().rev() {
        // SAFETY: kill has no memory preconditions; a pid that ended is ESRCH.
        unsafe {
            libc::kill(*p as libc::pid_t, libc::SIGKILL);
        }
    }
    // SAFETY: as above; the group is the one setsid made for the child.
    unsafe {
        libc::kill(-(pid as libc::pid_t), libc::SIGKILL);
    }
}

/// CPU seconds the calling thread has used (the knn answers siftlab
/// computes count towards the call, as OpenCV's knnMatch counts in the lab).
pub fn thread_cpu() -> f64 {
    let mut ts = libc::timespec { tv_sec: 0, tv_nsec: 0 };
    // SAFETY: ts is a valid timespec to write.
    unsafe {
        libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut ts);
    }
    ts.tv_sec as f64 + ts.tv_nsec as f64 * 1e-9
}

#[cfg(test)]
mod tests {
    use super::*;

    fn r(run: f64, wait: f64, throttled: f64) -> Reading {
        Reading { cpu: 0.0, memory: 0, wait, run, throttled }
    }

    #[test]
    fn only_waiting_for_a_cpu_is_the_machines_fault() {
        // 30 s of wall, 1.5 s of CPU, 27 s ready and not running: the machine.
        assert!(machine_fault(&r(0.0, 1.0, 0.0), &r(1.5, 28.0, 0.0), 30.0, 1.5));
        // Asleep: it never waited for a CPU.
        assert!(!machine_fault(&r(0.0, 1.0, 0.0), &r(0.1, 1.2, 0.0), 30.0, 0.1));
        // Held back by its own quota (a farm of its own): the file.
        assert!(!machine_fault(&r(0.0, 0.0, 0.0), &r(1.0, 25.0, 20.0), 30.0, 9.0));
        // Waiting behind its own children (they took the CPU): the file.
        assert!(!machine_fault(&r(0.0, 0.0, 0.0), &r(1.0, 20.0, 0.0), 30.0, 9.9));
    }

    /// The container tier's count where siftlab has no cgroup of its own:
    /// a child's CPU stays in the enclosing cgroup's count once it is
    /// reaped (here by this test, so not in this process's own CPU).
    #[test]
    fn the_enclosing_cgroup_counts_a_reaped_child() {
        let Some(e) = Enclosing::find() else { return }; // no readable cgroup here: nothing to test
        let children_cpu = || {
            let mut ru: libc::rusage = unsafe { std::mem::zeroed() };
            // SAFETY: ru is a valid rusage to write.
            unsafe {
                libc::getrusage(libc::RUSAGE_CHILDREN, &mut ru);
            }
            ru.ru_utime.tv_sec as f64 + ru.ru_utime.tv_usec as f64 * 1e-6
        };
        let (before, reaped0) = (e.others_cpu_seconds().unwrap(), children_cpu());
        let status = std::process::Command::new("sh")
            .args(["-c", "i=0; while [ $i -lt 300000 ]; do i=$((i+1)); done"])
            .status()
            .unwrap();
        assert!(status.success());
        let child = children_cpu() - reaped0;
        let grew = e.others_cpu_seconds().unwrap() - before;
        // Other processes of the cgroup only add to it (this machine's other work).
        assert!(child > 0.05, "the child burnt {child} s");
        assert!(grew >= 0.9 * child, "grew {grew} s for a {child} s child");
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
    }
}
