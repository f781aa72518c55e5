//! The container tier of `siftlab mark`'s sandbox (docs/marking.md, "Tiers"):
//! where bubblewrap cannot make namespaces (Docker's default profile forbids
//! them: Gradescope, PrairieLearn) but siftlab runs as root. The harness
//! runs as an unprivileged uid of its own, so root keeps the results, the
//! marker and its files out of its reach (it cannot signal, trace or write
//! for siftlab); with no new privileges, a seccomp filter (sandbox.rs's, plus
//! no sockets: there is no network namespace to hide the network), the
//! out-of-memory killer pointed at it first, and at the end every process of
//! that uid killed, so no daemon outlives the marking.

use std::ffi::CString;
use std::path::{Path, PathBuf};

/// What the harness's child does between fork and exec to enter the tier.
pub struct Enter {
    uid: u32,
    filter: Vec<libc::sock_filter>,
}

impl Enter {
    /// For marking uid `uid`; `None` where seccomp's program is unknown
    /// for this architecture (no tier then: the caller says so).
    pub fn new(uid: u32) -> Option<Enter> {
        let arch = crate::seccomp::native()?;
        let bytes = crate::seccomp::program(arch, true);
        let filter = bytes
            .chunks_exact(8)
            .map(|b| libc::sock_filter {
                code: u16::from_ne_bytes([b[0], b[1]]),
                jt: b[2],
                jf: b[3],
                k: u32::from_ne_bytes([b[4], b[5], b[6], b[7]]),
            })
            .collect();
        Some(Enter { uid, filter })
    }

    /// Runs in the child after fork, before exec: only async-signal-safe
    /// calls, nothing allocates. The order matters: the OOM score and the
    /// groups need root; no-new-privs before the filter (the kernel asks
    /// for one of it or CAP_SYS_ADMIN).
    pub fn apply(&self) -> std::io::Result<()> {
        let fail = || Err(std::io::Error::last_os_error());
        // SAFETY: every call below takes plain values or pointers to memory
        // owned by `self` or static, valid for the call.
        unsafe {
            // The kernel's OOM killer picks the student's processes first
            // (siftlab itself may not lower its own score without
            // CAP_SYS_RESOURCE, which containers rarely have).
            let fd = libc::open(c"/proc/self/oom_score_adj".as_ptr(), libc::O_WRONLY | libc::O_CLOEXEC);
            if fd >= 0 {
                libc::write(fd, b"1000".as_ptr().cast(), 4);
                libc::close(fd);
            }
            if libc::setgroups(0, std::ptr::null()) != 0 {
                return fail();
            }
            if libc::setresgid(self.uid, self.uid, self.uid) != 0 || libc::setresuid(self.uid, self.uid, self.uid) != 0
            {
                return fail();
            }
            // Root cannot come back (saved ids too): checked, not assumed.
            if libc::setuid(0) == 0 {
                return Err(std::io::Error::from_raw_os_error(libc::EPERM));
            }
            if libc::prctl(libc::PR_SET_NO_NEW_PRIVS, 1, 0, 0, 0) != 0 {
                return fail();
            }
            let prog = libc::sock_fprog { len: self.filter.len() as u16, filter: self.filter.as_ptr().cast_mut() };
            if libc::prctl(libc::PR_SET_SECCOMP, libc::SECCOMP_MODE_FILTER, &prog as *const libc::sock_fprog) != 0 {
                return fail();
            }
        }
        Ok(())
    }
}

/// The harness's folders in the container tier, under a fresh random
/// folder of root's in /tmp (every user may pass through /tmp; the caller's
/// TMPDIR may be private): `harness/`, a copy of the harness's files the uid
/// may read but not change, and `home/`, owned by the uid, 0700, its HOME,
/// TMPDIR and working folder. Removed with what is in them when dropped.
pub struct Scratch {
    base: PathBuf,
    harness: PathBuf,
    home: PathBuf,
}

impl Scratch {
    pub fn new(uid: u32, harness_files: &Path) -> std::io::Result<Scratch> {
        use std::os::unix::fs::PermissionsExt;
        let tmp = Path::new("/tmp");
        let parent = if tmp.is_dir() { tmp.to_path_buf() } else { std::env::temp_dir() };
        let template = CString::new(parent.join("siftlab-box-XXXXXX").as_os_str().as_encoded_bytes())
            .map_err(|_| std::io::Error::from(std::io::ErrorKind::InvalidInput))?;
        let mut raw = template.into_bytes_with_nul();
        // SAFETY: raw is a NUL-terminated template mkdtemp fills in place.
        if unsafe { libc::mkdtemp(raw.as_mut_ptr().cast()) }.is_null() {
            return Err(std::io::Error::last_os_error());
        }
        raw.pop();
        let base = PathBuf::from(String::from_utf8_lossy(&raw).into_owned());
        let s = Scratch { harness: base.join("harness"), home: base.join("home"), base };
        std::fs::set_permissions(&s.base, std::fs::Permissions::from_mode(0o755))?;
        std::fs::create_dir(&s.harness)?;
        std::fs::set_permissions(&s.harness, std::fs::Permissions::from_mode(0o755))?;
        for e in std::fs::read_dir(harness_files)?.flatten() {
            if e.file_type()?.is_file() {
                let to = s.harness.join(e.file_name());
                std::fs::copy(e.path(), &to)?;
                std::fs::set_permissions(&to, std::fs::Permissions::from_mode(0o644))?;
            }
        }
        std::fs::create_dir(&s.home)?;
        std::fs::set_permissions(&s.home, std::fs::Permissions::from_mode(0o700))?;
        std::os::unix::fs::chown(&s.home, Some(uid), Some(uid))?;
        Ok(s)
    }

    /// The harness's files, read-only to the uid.
    pub fn harness(&self) -> &Path {
        &self.harness
    }

    /// The uid's one writable folder.
    pub fn home(&self) -> &Path {
        &self.home
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        // std's remove_dir_all does not follow links the student left inside.
        let _ = std::fs::remove_dir_all(&self.base);
    }
}

/// The live (not zombie) processes whose real, effective or saved uid is
/// `uid`.
pub fn processes_of(uid: u32) -> Vec<u32> {
    let mut out = Vec::new();
    let Ok(rd) = std::fs::read_dir("/proc") else { return out };
    for e in rd.flatten() {
        let Some(pid) = e.file_name().to_str().and_then(|s| s.parse::<u32>().ok()) else { continue };
        let Ok(status) = std::fs::read_to_string(format!("/proc/{pid}/status")) else { continue };
        let field = |name: &str| status.lines().find_map(|l| l.strip_prefix(name)).map(str::trim).unwrap_or("");
        if field("State:").starts_with('Z') {
            continue;
        }
        let ids: Vec<u32> = field("Uid:").split_whitespace().take(3).filter_map(|x| x.parse().ok()).collect();
        if ids.contains(&uid) {
            out.push(pid);
        }
    }
    out
}

/// SIGKILL to every process of `uid`, until none is left (at most about a
/// second): a child takes the uid and calls kill(-1), which the kernel
/// delivers to all of the uid's processes at once, so a fork cannot slip
/// between two kills. False when some survived (the caller then writes no
/// mark).
pub fn kill_uid(uid: u32) -> bool {
    for round in 0..100 {
        if processes_of(uid).is_empty() {
            return true;
        }
        // SAFETY: between fork and _exit the child calls only
        // async-signal-safe functions (setresuid, kill, _exit).
        unsafe {
            let pid = libc::fork();
            if pid == 0 {
                if libc::setresuid(uid, uid, uid) == 0 {
                    libc::kill(-1, libc::SIGKILL);
                }
                libc::_exit(0);
            }
            if pid > 0 {
                let mut status = 0;
                libc::waitpid(pid, &mut status, 0);
            }
        }
        if round > 0 {
            std::thread::sleep(std::time::Duration::from_millis(10));
        }
    }
    processes_of(uid).is_empty()
}

/// Removes what `uid` left where every user may write (/tmp, /var/tmp,
/// /dev/shm and the world-writable folders in them, to a bounded depth):
/// with no mount namespace those are shared, so a file left there could
/// reach the next student or the machine. Call it after `kill_uid`: the uid
/// is this run's alone, so whatever it owns is its litter. Nothing is
/// followed through a link; std's remove_dir_all does not follow them either.
pub fn remove_litter(uid: u32) {
    use std::os::unix::fs::MetadataExt;
    let mut stack: Vec<(PathBuf, usize)> =
        ["/tmp", "/var/tmp", "/dev/shm"].iter().map(|p| (PathBuf::from(p), 0)).collect();
    let mut seen = 0usize;
    while let Some((dir, depth)) = stack.pop() {
        let Ok(rd) = std::fs::read_dir(&dir) else { continue };
        for e in rd.flatten() {
            seen += 1;
            if seen > 200_000 {
                return;
            }
            let path = e.path();
            let Ok(m) = std::fs::symlink_metadata(&path) else { continue };
            if m.uid() == uid {
                let _ = if m.is_dir() { std::fs::remove_dir_all(&path) } else { std::fs::remove_file(&path) };
            } else if m.is_dir() && m.mode() & 0o002 != 0 && depth < 8 {
                // Another's folder the uid could write in: look inside.
                stack.push((path, depth + 1));
            }
        }
    }
}

/// Whether siftlab can use this tier here: it runs as root (to give the
/// harness another uid) on an architecture the filter knows.
pub fn possible() -> bool {
    // SAFETY: geteuid has no preconditions.
    let root = unsafe { libc::geteuid() == 0 };
    root && crate::seccomp::native().is_some()
}
