//! The sandbox `siftlab mark` runs a student's file in (docs/marking.md,
//! "The sandbox"): bubblewrap with its own PID, network, IPC and UTS
//! namespaces, nothing of the host visible but the interpreter's own files
//! (resolved outside first), numpy's package and the harness, read-only; a
//! private /tmp; an empty environment; an unprivileged uid; limits on
//! memory, processes, file size and open files. The process tree is
//! measured here (CPU time, memory) and killed as a whole.

use crate::cgroup::Cgroup;
use siftlab_core::error::{Error, Result};
use std::ffi::OsString;
use std::io::Write;
use std::os::fd::{AsRawFd, FromRawFd, OwnedFd};
use std::os::unix::process::CommandExt;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

/// Which sandbox a harness runs in (docs/marking.md, "Tiers"), named in
/// the report and in results.json.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Tier {
    /// bubblewrap's namespaces (a machine siftlab's teacher runs).
    Bubblewrap,
    /// An unprivileged uid, no new privileges and seccomp (container.rs):
    /// inside a container that forbids namespaces, siftlab running as root.
    Container,
    /// `--no-sandbox`: the file runs with the caller's rights.
    None,
}

impl Tier {
    pub fn name(self) -> &'static str {
        match self {
            Tier::Bubblewrap => "bubblewrap",
            Tier::Container => "container",
            Tier::None => "none",
        }
    }
}

/// Where the harness lives inside the sandbox.
pub const BOX: &str = "/box";
/// Concurrent jobs of one run at most: each takes a uid of the run's block.
pub const MAX_JOBS: u32 = 256;

/// The uid the harness of job `job` takes when siftlab runs as root
/// (RLIMIT_NPROC does not hold for root; the container tier kills every
/// process of it at the end): one no account uses, in a block of MAX_JOBS
/// picked at random once per siftlab process, so two markings on one
/// machine (two classes, the tests) never share a uid and neither can
/// count towards, or kill, the other's processes.
pub fn marking_uid(job: u32) -> u32 {
    static BLOCK: std::sync::OnceLock<u32> = std::sync::OnceLock::new();
    let block = *BLOCK.get_or_init(|| {
        let mut b = [0u8; 4];
        let random = std::fs::File::open("/dev/urandom").and_then(|mut f| std::io::Read::read_exact(&mut f, &mut b));
        let r = if random.is_ok() {
            u32::from_ne_bytes(b)
        } else {
            let nanos =
                std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0, |d| d.subsec_nanos());
            std::process::id() ^ nanos
        };
        // 2^22 blocks above 100000 (under 2^31: every tool reads such a uid).
        100_000 + (r % (1 << 22)) * MAX_JOBS
    });
    block + job % MAX_JOBS
}

/// Limits on the whole sandbox.
pub const MEMORY_BYTES: u64 = 4 << 30;
const ADDRESS_SPACE: u64 = 16 << 30;
pub const PROCESSES: u64 = 64;
const FILE_BYTES: u64 = 64 << 20;
const OPEN_FILES: u64 = 256;
const TMP_BYTES: u64 = 64 << 20;

/// The interpreter, as found outside the sandbox (a pyenv shim resolved
/// to the real binary).
#[derive(Clone, Debug)]
pub struct Python {
    pub exe: PathBuf,
    pub version: String,
    pub numpy: Option<String>,
    /// numpy's parent folder (put on sys.path in the harness).
    pub numpy_parent: Option<PathBuf>,
    /// Read-only binds (source, destination), in order.
    binds: Vec<(PathBuf, PathBuf)>,
    /// Folders hidden under an empty tmpfs (site-packages inside the stdlib).
    hidden: Vec<PathBuf>,
}

const PROBE: &str = r#"
import json, os, sys, sysconfig
out = {"exe": os.path.realpath(sys.executable), "version": sys.version.split()[0],
       "dirs": [], "numpy": None, "numpy_dir": None, "libs": []}
paths = sysconfig.get_paths()
for k in ("stdlib", "platstdlib"):
    if k in paths and os.path.isdir(paths[k]):
        out["dirs"].append(os.path.realpath(paths[k]))
dyn = os.path.join(paths.get("platstdlib", ""), "lib-dynload")
for p in sys.path:
    if p.endswith(".zip") and os.path.exists(p):
        out["dirs"].append(os.path.realpath(p))
libdir, lib = sysconfig.get_config_var("LIBDIR"), sysconfig.get_config_var("LDLIBRARY")
if libdir and lib and os.path.exists(os.path.join(libdir, lib)):
    out["libs"].append(os.path.join(libdir, lib))
try:
    import numpy
    d = os.path.dirname(os.path.realpath(numpy.__file__))
    out["numpy"], out["numpy_dir"] = numpy.__version__, d
except Exception:
    pass
print(json.dumps(out))
"#;

impl Python {
    /// Asks `python` (outside any sandbox: our probe, no student code) where
    /// its files are, and which shared libraries it and numpy load (ldd).
    pub fn find(python: &OsString) -> Result<Python> {
        let shown = python.to_string_lossy().into_owned();
        let out = Command::new(python).args(["-c", PROBE]).stdin(Stdio::null()).output().map_err(|e| {
            Error::InvalidArgument(if e.kind() == std::io::ErrorKind::NotFound {
                format!(
                    "{shown} not found: siftlab mark runs the student's file with Python 3 (install python3, \
                     or name one with SIFTLAB_PYTHON=/path/to/python3)"
                )
            } else {
                format!("cannot start {shown}: {e}")
            })
        })?;
        let text = String::from_utf8_lossy(&out.stdout);
        let v = siftlab_mark::parse_json(text.trim()).map_err(|_| {
            Error::InvalidArgument(format!(
                "{shown} could not describe itself (Python 3.8 or later is needed): {}",
                siftlab_mark::escaped(String::from_utf8_lossy(&out.stderr).trim(), 400)
            ))
        })?;
        let s = |k: &str| v.get(k).and_then(|x| x.as_str()).map(str::to_string);
        let list = |k: &str| -> Vec<PathBuf> {
            v.get(k)
                .and_then(|x| x.as_arr())
                .unwrap_or(&[])
                .iter()
                .filter_map(|x| x.as_str())
                .map(PathBuf::from)
                .collect()
        };
        let exe = PathBuf::from(s("exe").ok_or_else(|| Error::InvalidArgument(format!("{shown}: no executable")))?);
        let numpy_dir = s("numpy_dir").map(PathBuf::from);
        let mut binds: Vec<(PathBuf, PathBuf)> = Vec::new();
        let mut add = |p: &Path| {
            if let Ok(real) = std::fs::canonicalize(p) {
                // The path as the loader opens it: the folder resolved, the
                // name kept (a library's soname is often a symlink).
                let dest = match (p.parent().and_then(|d| std::fs::canonicalize(d).ok()), p.file_name()) {
                    (Some(d), Some(n)) => d.join(n),
                    _ => real.clone(),
                };
                for d in [real.clone(), dest] {
                    if !binds.iter().any(|(_, b)| *b == d) {
                        binds.push((real.clone(), d));
                    }
                }
            }
        };
        add(&exe);
        let dirs = list("dirs");
        for d in &dirs {
            add(d);
        }
        let mut hidden = Vec::new();
        for d in &dirs {
            for name in ["site-packages", "dist-packages"] {
                let p = d.join(name);
                if p.is_dir() {
                    hidden.push(p);
                }
            }
        }
        // Shared libraries: the interpreter's, its extension modules' and numpy's.
        let mut elf = vec![exe.clone()];
        elf.extend(list("libs"));
        for d in &dirs {
            collect_so(&d.join("lib-dynload"), &mut elf, 1);
        }
        if let Some(n) = &numpy_dir {
            collect_so(n, &mut elf, 6);
            if let Some(libs) = n.parent().map(|p| p.join("numpy.libs")) {
                collect_so(&libs, &mut elf, 1);
            }
        }
        for lib in list("libs").iter().chain(shared_libraries(&elf).iter()) {
            add(lib);
        }
        if let Some(n) = &numpy_dir {
            add(n);
            if let Some(libs) = n.parent().map(|p| p.join("numpy.libs")).filter(|p| p.is_dir()) {
                add(&libs);
            }
        }
        Ok(Python {
            exe,
            version: s("version").unwrap_or_else(|| "?".into()),
            numpy: s("numpy"),
            numpy_parent: numpy_dir.as_ref().and_then(|n| n.parent()).map(Path::to_path_buf),
            binds,
            hidden,
        })
    }

    /// The command that runs `harness_dir/siftlab_harness.py` in `tier`,
    /// with the limits set before it starts. With `cgroup`, the harness
    /// joins it before exec (everything it starts is inside); in bubblewrap,
    /// bubblewrap installs the seccomp filter, in the container tier the
    /// child does, after taking the marking uid, with `scratch` (owned by
    /// that uid) as its working folder.
    pub fn command(
        &self,
        harness_dir: &Path,
        tier: Tier,
        job: u32,
        cgroup: Option<&Cgroup>,
        scratch: &Path,
    ) -> Command {
        self.build(harness_dir, tier, job, cgroup, scratch, false)
    }

    /// The command; with `probe`, the same sandbox runs the interpreter's
    /// `-c "import math, json"` instead of the harness.
    fn build(
        &self,
        harness_dir: &Path,
        tier: Tier,
        job: u32,
        cgroup: Option<&Cgroup>,
        scratch: &Path,
        probe: bool,
    ) -> Command {
        let root = is_root();
        let sandbox = tier == Tier::Bubblewrap;
        // The filter's bytes in a pipe bubblewrap reads (`--seccomp FD`);
        // the read end is kept by the command and opened to the child only.
        let seccomp_fd = if sandbox {
            crate::seccomp::native().and_then(|a| pipe_with(&crate::seccomp::program(a, false)))
        } else {
            None
        };
        // The container tier's entry (uid, filter), made before the fork.
        let contained = tier == Tier::Container;
        let enter = if contained { crate::container::Enter::new(marking_uid(job)) } else { None };
        let mut harness_args: Vec<OsString> = vec!["-I".into(), "-S".into(), "-B".into(), "-u".into()];
        let mut cmd = if sandbox {
            let mut c = Command::new("bwrap");
            c.args(["--unshare-pid", "--unshare-net", "--unshare-ipc", "--unshare-uts", "--unshare-cgroup-try"]);
            if root {
                // Root: no user namespace, so the harness can leave uid 0 for
                // its marking uid (RLIMIT_NPROC then counts); that needs these two.
                c.args(["--cap-add", "CAP_SETUID", "--cap-add", "CAP_SETGID"]);
            } else {
                c.args(["--unshare-user", "--cap-drop", "ALL"]);
            }
            c.args(["--die-with-parent", "--new-session", "--clearenv"]);
            c.args(["--setenv", "OPENBLAS_NUM_THREADS", "1", "--setenv", "OMP_NUM_THREADS", "1"]);
            for link in ["/lib", "/lib64", "/lib32", "/libx32", "/bin", "/sbin"] {
                if let Ok(target) = std::fs::read_link(link) {
                    c.arg("--symlink").arg(target).arg(link);
                }
            }
            let mut made: Vec<PathBuf> = Vec::new();
            for (src, dest) in &self.binds {
                for parent in parents(dest) {
                    // Folders on the way (e.g. /root, mode 0700 outside) open
                    // to the marking uid; each made once.
                    if !made.contains(&parent) {
                        c.args(["--perms", "0755", "--dir"]).arg(&parent);
                        made.push(parent);
                    }
                }
                c.arg("--ro-bind").arg(src).arg(dest);
                for h in self.hidden.iter().filter(|h| h.starts_with(dest) && **h != *dest) {
                    // site-packages inside the standard library's folder: hidden.
                    c.args(["--perms", "0755", "--tmpfs"]).arg(h);
                }
            }
            c.args(["--proc", "/proc", "--dev", "/dev"]);
            c.args(["--perms", "1777", "--size", &TMP_BYTES.to_string(), "--tmpfs", "/tmp"]);
            c.arg("--ro-bind").arg(harness_dir).arg(BOX);
            if let Some(fd) = &seccomp_fd {
                c.args(["--seccomp", &fd.as_raw_fd().to_string()]);
            }
            c.args(["--chdir", "/tmp", "--"]);
            c.arg(&self.exe);
            harness_args.push(format!("{BOX}/siftlab_harness.py").into());
            if root {
                harness_args.extend(["--drop-uid".into(), marking_uid(job).to_string().into()]);
            }
            c
        } else {
            let mut c = Command::new(&self.exe);
            c.env_clear();
            c.env("OPENBLAS_NUM_THREADS", "1").env("OMP_NUM_THREADS", "1");
            if tier == Tier::Container {
                // Its one writable folder: no file of siftlab's is there.
                c.current_dir(scratch).env("HOME", scratch).env("TMPDIR", scratch);
            } else {
                c.current_dir(harness_dir);
            }
            harness_args.push(harness_dir.join("siftlab_harness.py").into());
            c
        };
        if let Some(p) = &self.numpy_parent {
            harness_args.push("--path".into());
            harness_args.push(p.into());
        }
        if probe {
            harness_args = ["-I", "-S", "-c", "import math, json"].map(OsString::from).to_vec();
        }
        cmd.args(harness_args);
        let limit_processes = tier != Tier::None;
        let join = cgroup.map(Cgroup::join_files).unwrap_or_default();
        // SAFETY: only async-signal-safe calls (open, write, close, fcntl,
        // setrlimit, setsid) between fork and exec; nothing allocates.
        unsafe {
            cmd.pre_exec(move || {
                for file in &join {
                    // "0": the writing process joins the cgroup.
                    let fd = libc::open(file.as_ptr(), libc::O_WRONLY | libc::O_CLOEXEC);
                    if fd < 0 || libc::write(fd, b"0".as_ptr().cast(), 1) != 1 {
                        return Err(std::io::Error::last_os_error());
                    }
                    libc::close(fd);
                }
                if let Some(fd) = &seccomp_fd {
                    libc::fcntl(fd.as_raw_fd(), libc::F_SETFD, 0);
                }
                let set = |what, n: u64| {
                    let r = libc::rlimit { rlim_cur: n as libc::rlim_t, rlim_max: n as libc::rlim_t };
                    libc::setrlimit(what, &r);
                };
                set(libc::RLIMIT_AS, ADDRESS_SPACE);
                set(libc::RLIMIT_FSIZE, FILE_BYTES);
                set(libc::RLIMIT_NOFILE, OPEN_FILES);
                set(libc::RLIMIT_CORE, 0);
                if limit_processes {
                    set(libc::RLIMIT_NPROC, PROCESSES);
                }
                // Its own session and process group: killed as one even without the sandbox.
                libc::setsid();
                match &enter {
                    Some(e) => e.apply()?,
                    // The container tier without its entry (no filter for this
                    // architecture) must not run the file as root.
                    None if contained => return Err(std::io::Error::from_raw_os_error(libc::EPERM)),
                    None => {}
                }
                Ok(())
            });
        }
        cmd
    }
}

/// Whether `tier` can run the interpreter here (a real run of it through
/// the sandbox); `Err` says why not.
pub fn check(python: &Python, harness_dir: &Path, tier: Tier) -> std::result::Result<(), String> {
    let scratch = match tier {
        Tier::Container => Some(
            crate::container::Scratch::new(marking_uid(0), harness_dir)
                .map_err(|e| format!("cannot make its folder: {e}"))?,
        ),
        _ => None,
    };
    let (harness, home) = scratch.as_ref().map_or((harness_dir, harness_dir), |s| (s.harness(), s.home()));
    let mut c = python.build(harness, tier, 0, None, home, true);
    match c.stdin(Stdio::null()).stdout(Stdio::null()).stderr(Stdio::piped()).output() {
        Ok(o) if o.status.success() => Ok(()),
        Ok(o) => Err(siftlab_mark::escaped(String::from_utf8_lossy(&o.stderr).trim(), 300)),
        Err(e) if tier == Tier::Bubblewrap && e.kind() == std::io::ErrorKind::NotFound => {
            Err("bwrap (bubblewrap) is not installed: apt install bubblewrap".into())
        }
        Err(e) if tier == Tier::Bubblewrap => Err(format!("cannot run bwrap: {e}")),
        Err(e) if e.kind() == std::io::ErrorKind::PermissionDenied => Err(format!(
            "the marking uid cannot run {} ({e}): it must be where every user may run it (not under /root); \
             set SIFTLAB_PYTHON to such a python3",
            python.exe.display()
        )),
        Err(e) => Err(format!("cannot start the interpreter as uid {}: {e}", marking_uid(0))),
    }
}

/// A pipe holding `bytes` (written whole, write end closed): its read end.
fn pipe_with(bytes: &[u8]) -> Option<OwnedFd> {
    let mut fds = [0; 2];
    // SAFETY: fds is a valid array of two ints; the fds are owned below.
    if unsafe { libc::pipe2(fds.as_mut_ptr(), libc::O_CLOEXEC) } != 0 {
        return None;
    }
    // SAFETY: pipe2 returned two open descriptors that nothing else owns.
    let (r, w) = unsafe { (OwnedFd::from_raw_fd(fds[0]), OwnedFd::from_raw_fd(fds[1])) };
    // The program is a few hundred bytes: under any pipe's buffer.
    std::fs::File::from(w).write_all(bytes).ok()?;
    Some(r)
}

fn is_root() -> bool {
    // SAFETY: getuid has no preconditions.
    unsafe { libc::getuid() == 0 }
}

/// The folders above `p` (not `/`), outermost first.
fn parents(p: &Path) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = p.ancestors().skip(1).filter(|a| a.parent().is_some()).map(Path::to_path_buf).collect();
    v.reverse();
    v
}

fn collect_so(dir: &Path, out: &mut Vec<PathBuf>, depth: usize) {
    let Ok(rd) = std::fs::read_dir(dir) else { return };
    for e in rd.flatten() {
        let p = e.path();
        if p.is_dir() && depth > 1 {
            collect_so(&p, out, depth - 1);
        } else if p.file_name().and_then(|n| n.to_str()).is_some_and(|n| n.contains(".so")) {
            out.push(p);
        }
    }
}

/// The libraries `ldd` names for `files` (the dynamic loader included).
fn shared_libraries(files: &[PathBuf]) -> Vec<PathBuf> {
    let mut libs: Vec<PathBuf> = Vec::new();
    for chunk in files.chunks(64) {
        let Ok(out) = Command::new("ldd").args(chunk).stderr(Stdio::null()).output() else { continue };
        for line in String::from_utf8_lossy(&out.stdout).lines() {
            let path = match line.split_once("=>") {
                Some((_, rest)) => rest.split_whitespace().next(),
                None => line.split_whitespace().next().filter(|p| p.starts_with('/')),
            };
            if let Some(p) = path.filter(|p| p.starts_with('/')) {
                let p = PathBuf::from(p);
                if !libs.contains(&p) {
                    libs.push(p);
                }
            }
        }
    }
    libs
}

/// The strongest sandbox that works here: bubblewrap; where it cannot
/// make namespaces (a container) and siftlab runs as root, the container
/// tier. `SIFTLAB_SANDBOX=container` picks the container tier (as the
/// platforms' simulations and tests do on a machine with bubblewrap).
pub(crate) fn pick_tier(python: &Python, dir: &std::path::Path) -> Result<Tier> {
    #[cfg(not(target_os = "linux"))]
    return Err(Error::InvalidArgument(
        "no sandbox on this system (siftlab mark sandboxes with bubblewrap, on Linux): \
         pass --no-sandbox to check your own file with your own rights"
            .into(),
    ));
    let forced = std::env::var("SIFTLAB_SANDBOX").ok();
    let bwrap = match forced.as_deref() {
        Some("container") => Err("SIFTLAB_SANDBOX=container".to_string()),
        Some("bubblewrap") | None => check(python, dir, Tier::Bubblewrap),
        Some(other) => {
            return Err(Error::InvalidArgument(format!(
                "SIFTLAB_SANDBOX={}: use bubblewrap or container (or unset it: the strongest that works)",
                siftlab_mark::escaped(other, 40)
            )))
        }
    };
    let Err(why) = bwrap else { return Ok(Tier::Bubblewrap) };
    if forced.as_deref() != Some("bubblewrap") && crate::container::possible() {
        return match check(python, dir, Tier::Container) {
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
