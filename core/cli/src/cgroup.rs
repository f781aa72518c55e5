//! One cgroup per harness (docs/marking.md, "The sandbox", accounting):
//! the sandbox is measured and limited as a whole, whatever its processes
//! do. A process tree read from /proc misses children the kernel reaped
//! (their CPU time is gone) and memory no process maps (memfd files, tmpfs);
//! the cgroup counts both, caps memory, processes and CPU (one core's worth
//! per job, so one student cannot slow the student beside it), and its
//! processes are killed and the cgroup removed at the end.
//!
//! cgroup v1 (a hierarchy per controller, as on many CI machines) and v2
//! (one unified hierarchy) take the same path: a folder per controller
//! hierarchy (one for v2), limits written before the harness starts, and
//! the harness joins every folder between fork and exec, so nothing it
//! starts is ever outside. Each folder is made under siftlab's own cgroup,
//! so any limit on siftlab still holds.

use std::ffi::CString;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

/// One core's worth of CPU per job: `quota` µs of every `period` µs.
const CPU_PERIOD_US: u64 = 100_000;
const CPU_QUOTA_US: u64 = 100_000;

static SEQ: AtomicU64 = AtomicU64::new(0);

/// A cgroup of one harness; dropping it kills its processes and removes it.
#[derive(Debug)]
pub struct Cgroup {
    v2: bool,
    /// Every folder made (one per v1 hierarchy; one for v2).
    dirs: Vec<PathBuf>,
    memory: PathBuf,
    cpuacct: PathBuf,
    cpu: PathBuf,
    /// `cgroup.procs` of each folder, for the harness to join.
    join: Vec<CString>,
}

/// The controllers siftlab uses.
const CONTROLLERS: [&str; 4] = ["memory", "pids", "cpu", "cpuacct"];

impl Cgroup {
    /// Makes a cgroup for job `job` with the sandbox's limits, or says why
    /// none can be made here (not root, no such controller, v2 without
    /// delegation).
    pub fn create(job: u32, memory_bytes: u64, processes: u64) -> Result<Cgroup, String> {
        let own = std::fs::read_to_string("/proc/self/cgroup").map_err(|e| format!("/proc/self/cgroup: {e}"))?;
        let name = format!("siftlab-{}-{job}-{}", std::process::id(), SEQ.fetch_add(1, Ordering::Relaxed));
        let root = Path::new("/sys/fs/cgroup");
        let g = if root.join("cgroup.controllers").exists() {
            Self::make_v2(root, &own, &name)?
        } else {
            Self::make_v1(root, &own, &name)?
        };
        g.limit(memory_bytes, processes)?;
        Ok(g)
    }

    /// A cgroup with no folder yet (make_v1 adds them one controller at a time).
    fn empty(v2: bool) -> Cgroup {
        Cgroup {
            v2,
            dirs: Vec::new(),
            memory: PathBuf::new(),
            cpuacct: PathBuf::new(),
            cpu: PathBuf::new(),
            join: Vec::new(),
        }
    }

    fn make_v1(root: &Path, own: &str, name: &str) -> Result<Cgroup, String> {
        let mut g = Cgroup::empty(false);
        for c in CONTROLLERS {
            // "4:memory:/a/b" or "1:cpu,cpuacct:/a/b" in /proc/self/cgroup.
            let path = own
                .lines()
                .filter_map(|l| l.split_once(':').and_then(|(_, rest)| rest.split_once(':')))
                .find(|(list, _)| list.split(',').any(|x| x == c))
                .map(|(_, p)| p.trim_start_matches('/').to_string())
                .ok_or_else(|| format!("no cgroup v1 {c} controller"))?;
            let mount = std::fs::canonicalize(root.join(c)).map_err(|_| format!("no {}", root.join(c).display()))?;
            let dir = mount.join(path).join(name);
            if !g.dirs.contains(&dir) {
                if let Err(e) = std::fs::create_dir(&dir) {
                    drop(g);
                    return Err(format!("cannot make {}: {e}", dir.display()));
                }
                g.join.push(cstring(&dir.join("cgroup.procs")));
                g.dirs.push(dir.clone());
            }
            match c {
                "memory" => g.memory = dir,
                "cpu" => g.cpu = dir,
                "cpuacct" => g.cpuacct = dir,
                _ => {}
            }
        }
        Ok(g)
    }

    fn make_v2(root: &Path, own: &str, name: &str) -> Result<Cgroup, String> {
        let path = own
            .lines()
            .find_map(|l| l.strip_prefix("0::"))
            .ok_or_else(|| "no cgroup v2 entry in /proc/self/cgroup".to_string())?;
        let parent = root.join(path.trim_start_matches('/'));
        let have = std::fs::read_to_string(parent.join("cgroup.subtree_control")).unwrap_or_default();
        if !["memory", "pids", "cpu"].iter().all(|c| have.split_whitespace().any(|x| x == *c)) {
            // Enabling controllers for children fails (EBUSY) where the
            // parent holds processes: a delegated, empty parent is needed.
            write(&parent.join("cgroup.subtree_control"), "+memory +pids +cpu")
                .map_err(|e| format!("cgroup v2 controllers not delegated to {}: {e}", parent.display()))?;
        }
        let dir = parent.join(name);
        std::fs::create_dir(&dir).map_err(|e| format!("cannot make {}: {e}", dir.display()))?;
        Ok(Cgroup {
            v2: true,
            dirs: vec![dir.clone()],
            memory: dir.clone(),
            cpuacct: dir.clone(),
            cpu: dir.clone(),
            join: vec![cstring(&dir.join("cgroup.procs"))],
        })
    }

    fn limit(&self, memory_bytes: u64, processes: u64) -> Result<(), String> {
        let m = memory_bytes.to_string();
        if self.v2 {
            write(&self.memory.join("memory.max"), &m)?;
            // No swap either: memory over the limit is not pushed out.
            let _ = write(&self.memory.join("memory.swap.max"), "0");
            write(&self.memory.join("pids.max"), &processes.to_string())?;
            write(&self.cpu.join("cpu.max"), &format!("{CPU_QUOTA_US} {CPU_PERIOD_US}"))?;
        } else {
            write(&self.memory.join("memory.limit_in_bytes"), &m)?;
            let _ = write(&self.memory.join("memory.memsw.limit_in_bytes"), &m);
            let pids = self.dirs.iter().find(|d| d.join("pids.max").exists()).ok_or("no pids.max")?;
            write(&pids.join("pids.max"), &processes.to_string())?;
            write(&self.cpu.join("cpu.cfs_period_us"), &CPU_PERIOD_US.to_string())?;
            write(&self.cpu.join("cpu.cfs_quota_us"), &CPU_QUOTA_US.to_string())?;
        }
        Ok(())
    }

    /// The `cgroup.procs` files the harness writes "0" to between fork and
    /// exec (a write of its own pid, which needs no allocation there).
    pub fn join_files(&self) -> Vec<CString> {
        self.join.clone()
    }

    /// CPU seconds used by every process that was ever in the cgroup.
    pub fn cpu_seconds(&self) -> Option<f64> {
        if self.v2 {
            stat_field(&self.cpuacct.join("cpu.stat"), "usage_usec").map(|us| us as f64 * 1e-6)
        } else {
            read_u64(&self.cpuacct.join("cpuacct.usage")).map(|ns| ns as f64 * 1e-9)
        }
    }

    /// Memory charged to the cgroup now (resident, page cache, shared
    /// memory, tmpfs).
    pub fn memory_bytes(&self) -> Option<u64> {
        read_u64(&self.memory.join(if self.v2 { "memory.current" } else { "memory.usage_in_bytes" }))
    }

    /// Processes the kernel killed for going over the memory limit.
    pub fn oom_kills(&self) -> u64 {
        let file = if self.v2 { "memory.events" } else { "memory.oom_control" };
        stat_field(&self.memory.join(file), "oom_kill").unwrap_or(0)
    }

    /// Seconds the cgroup was held back by its own CPU quota.
    pub fn throttled_seconds(&self) -> f64 {
        if self.v2 {
            stat_field(&self.cpu.join("cpu.stat"), "throttled_usec").map_or(0.0, |us| us as f64 * 1e-6)
        } else {
            stat_field(&self.cpu.join("cpu.stat"), "throttled_time").map_or(0.0, |ns| ns as f64 * 1e-9)
        }
    }

    /// Removes the empty cgroups of siftlab runs that ended without removing
    /// theirs (killed, or their processes slow to leave): `siftlab-<pid>-*`
    /// beside this one's, `<pid>` no longer running.
    fn remove_stale(&self) {
        for d in &self.dirs {
            let Ok(entries) = d.parent().map_or_else(|| std::fs::read_dir("/nonexistent"), std::fs::read_dir) else {
                continue;
            };
            for e in entries.flatten().take(10_000) {
                let name = e.file_name().to_string_lossy().into_owned();
                let Some(pid) = name.strip_prefix("siftlab-").and_then(|r| r.split('-').next()) else { continue };
                let Ok(pid) = pid.parse::<u32>() else { continue };
                if pid != std::process::id() && !Path::new(&format!("/proc/{pid}")).exists() {
                    // Fails (EBUSY) while a process is still in it: then it stays.
                    let _ = std::fs::remove_dir(e.path());
                }
            }
        }
    }

    /// SIGKILL to every process in the cgroup, until none is left (a fork
    /// racing the kill is caught by the next round; pids.max bounds them).
    pub fn kill_all(&self) {
        // A cgroup whose first folder could not be made (a container's
        // read-only /sys) holds nothing.
        let Some(first) = self.dirs.first() else { return };
        let procs = first.join("cgroup.procs");
        let kill = first.join("cgroup.kill");
        if self.v2 && write(&kill, "1").is_ok() {
            return;
        }
        for _ in 0..50 {
            let pids: Vec<i32> = std::fs::read_to_string(&procs)
                .unwrap_or_default()
                .split_whitespace()
                .filter_map(|x| x.parse().ok())
                .collect();
            if pids.is_empty() {
                return;
            }
            for p in pids {
                // SAFETY: kill has no memory preconditions; an ended pid is ESRCH.
                unsafe {
                    libc::kill(p, libc::SIGKILL);
                }
            }
            std::thread::sleep(Duration::from_millis(5));
        }
    }
}

impl Drop for Cgroup {
    fn drop(&mut self) {
        self.kill_all();
        // A killed process leaves the cgroup once it is reaped: wait a little.
        let deadline = Instant::now() + Duration::from_secs(5);
        for d in self.dirs.iter().rev() {
            while std::fs::remove_dir(d).is_err() && d.exists() && Instant::now() < deadline {
                self.kill_all();
                std::thread::sleep(Duration::from_millis(10));
            }
        }
    }
}

/// The CPU count of the cgroup siftlab itself runs in, read-only: what a
/// container's processes have used where siftlab cannot make a cgroup of
/// its own (Docker's read-only /sys). The container tier marks one student
/// at a time, so that count less siftlab's own CPU is the student's, reaped
/// children included (a process tree from /proc loses them).
#[derive(Clone, Debug)]
pub struct Enclosing {
    file: PathBuf,
    v2: bool,
}

impl Enclosing {
    /// siftlab's own cgroup's CPU file, if it can be read here. In a
    /// container the hierarchy is often mounted at the container's own
    /// cgroup, so /proc/self/cgroup's path is not below the mount: then the
    /// mount's root is that cgroup.
    pub fn find() -> Option<Enclosing> {
        let own = std::fs::read_to_string("/proc/self/cgroup").ok()?;
        let root = Path::new("/sys/fs/cgroup");
        let (mount, path, file, v2) = if root.join("cgroup.controllers").exists() {
            let path = own.lines().find_map(|l| l.strip_prefix("0::"))?;
            (root.to_path_buf(), path, "cpu.stat", true)
        } else {
            let path = own
                .lines()
                .filter_map(|l| l.split_once(':').and_then(|(_, rest)| rest.split_once(':')))
                .find(|(list, _)| list.split(',').any(|x| x == "cpuacct"))
                .map(|(_, p)| p)?;
            (std::fs::canonicalize(root.join("cpuacct")).ok()?, path, "cpuacct.usage", false)
        };
        [mount.join(path.trim_start_matches('/')), mount]
            .into_iter()
            .map(|d| Enclosing { file: d.join(file), v2 })
            .find(|e| e.usage().is_some())
    }

    /// CPU seconds every process of the cgroup has used, reaped ones included.
    fn usage(&self) -> Option<f64> {
        if self.v2 {
            stat_field(&self.file, "usage_usec").map(|us| us as f64 * 1e-6)
        } else {
            read_u64(&self.file).map(|ns| ns as f64 * 1e-9)
        }
    }

    /// CPU seconds of the cgroup's processes other than siftlab's own.
    pub fn others_cpu_seconds(&self) -> Option<f64> {
        let mut ts = libc::timespec { tv_sec: 0, tv_nsec: 0 };
        // SAFETY: ts is a valid timespec to write.
        unsafe {
            libc::clock_gettime(libc::CLOCK_PROCESS_CPUTIME_ID, &mut ts);
        }
        let own = ts.tv_sec as f64 + ts.tv_nsec as f64 * 1e-9;
        Some(self.usage()? - own)
    }

    pub fn file(&self) -> &Path {
        &self.file
    }
}

/// Whether this machine lets siftlab make a cgroup (one made and removed);
/// if not, says why on stderr and what is measured instead.
pub fn usable_or_say_why(memory_bytes: u64, processes: u64) -> bool {
    match Cgroup::create(u32::MAX, memory_bytes, processes) {
        Ok(g) => {
            g.remove_stale();
            true
        }
        Err(why) => {
            eprintln!(
                "siftlab: no cgroup for the sandboxes ({why}): CPU time and memory are read per process \
                 tree, which misses children the kernel reaped and memory no process maps (run as root \
                 with cgroup v1 or a delegated cgroup v2 for the full accounting)"
            );
            false
        }
    }
}

fn write(path: &Path, value: &str) -> Result<(), String> {
    std::fs::write(path, value).map_err(|e| format!("cannot write {} to {}: {e}", value, path.display()))
}

fn read_u64(path: &Path) -> Option<u64> {
    std::fs::read_to_string(path).ok()?.trim().parse().ok()
}

/// `key N` from a flat keyed file (cpu.stat, memory.events, oom_control).
fn stat_field(path: &Path, key: &str) -> Option<u64> {
    let text = std::fs::read_to_string(path).ok()?;
    text.lines().find_map(|l| l.strip_prefix(key).and_then(|v| v.strip_prefix(' ')).and_then(|v| v.trim().parse().ok()))
}

fn cstring(p: &Path) -> CString {
    use std::os::unix::ffi::OsStrExt;
    CString::new(p.as_os_str().as_bytes()).unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// make_v1 drops a half-made cgroup when its first folder cannot be
    /// made (a container's read-only /sys): that once indexed dirs[0] and
    /// panicked, ending the marking before any mark.
    #[test]
    fn a_cgroup_with_no_folder_is_dropped_quietly() {
        let g = Cgroup::empty(false);
        g.kill_all();
        drop(g);
    }
}
