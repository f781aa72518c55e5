//! The sandbox's accounting and seccomp filter, end to end (docs/marking.md,
//! "The sandbox"): `siftlab mark` on the hostile fixtures that hide CPU time
//! in children the kernel reaps and memory in memfd files, and on a file
//! that tries the calls the filter denies. The accounting tests need a
//! cgroup (root, cgroup v1 or a delegated v2); where siftlab says it has
//! none, they check that it said so and stop.

#![cfg(target_os = "linux")]

use siftlab_core::json::{self, Json};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// `siftlab -d DEMO mark FILE -n 1 --json`.
fn mark(file: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_siftlab"))
        .current_dir(repo_root())
        .arg("-d")
        .arg(repo_root().join("www/demo/MyKITTI"))
        .arg("mark")
        .arg(file)
        .args(["-n", "1", "--seed", "0", "--json"])
        .output()
        .expect("cannot start the siftlab binary")
}

fn hostile(name: &str) -> PathBuf {
    repo_root().join("tests/fixtures/mark/hostile").join(name).join("vision_tasks.py")
}

fn text(o: &Output) -> (String, String) {
    (String::from_utf8_lossy(&o.stdout).into_owned(), String::from_utf8_lossy(&o.stderr).into_owned())
}

/// (task, diagnosis, message) of each case that is not correct.
fn failures(o: &Output) -> Vec<(String, String, String)> {
    let (out, err) = text(o);
    let r = json::parse(&out).unwrap_or_else(|e| panic!("not JSON ({e}):\n{out}\n{err}"));
    r.get("cases")
        .and_then(Json::as_arr)
        .unwrap()
        .iter()
        .filter(|c| c.get("status").and_then(Json::as_str) != Some("correct"))
        .map(|c| {
            let s = |k: &str| c.get(k).and_then(Json::as_str).unwrap_or("").to_string();
            (s("task"), s("diagnosis"), format!("{c:?}"))
        })
        .collect()
}

/// Whether siftlab marked without a cgroup (it says so on stderr).
fn no_cgroup(o: &Output) -> bool {
    let (_, err) = text(o);
    if err.contains("no cgroup for the sandboxes") {
        eprintln!("no cgroup here: the accounting test only checks siftlab said so");
        return true;
    }
    false
}

#[test]
fn cpu_of_reaped_children_counts() {
    // 15 s of CPU in children reaped by the kernel: dt is over 10 s.
    let o = mark(&hostile("reaped_cpu"));
    if no_cgroup(&o) {
        return;
    }
    let f = failures(&o);
    assert_eq!(f.iter().map(|(t, d, _)| (t.as_str(), d.as_str())).collect::<Vec<_>>(), [("dt", "timeout")], "{f:?}");
}

#[test]
fn memory_in_memfd_files_counts() {
    let o = mark(&hostile("memfd_hold"));
    if no_cgroup(&o) {
        return;
    }
    let f = failures(&o);
    assert_eq!(f.len(), 1, "{f:?}");
    assert_eq!(f[0].0, "nndr");
    assert!(f[0].2.contains("over 4 GB of memory"), "{f:?}");
}

#[test]
fn the_seccomp_filter_denies_namespaces_tracing_and_mounts() {
    // Raw syscalls through ctypes; the load's error carries each result as
    // name=return/errno (1 EPERM, 38 ENOSYS).
    let numbers = if cfg!(target_arch = "x86_64") {
        "{'unshare': (272, (0x10000000,)), 'setns': (308, (0, 0)), 'ptrace': (101, (0, 0, 0, 0)), \
         'keyctl': (250, (0, 0)), 'bpf': (321, (0, 0, 0)), 'mount': (165, (0, 0, 0, 0, 0)), \
         'perf_event_open': (298, (0, 0, 0, 0, 0)), 'clone_newuser': (56, (0x10000000 | 17, 0, 0, 0, 0)), \
         'clone3': (435, (0, 0)), 'x32': (39 | 0x40000000, ()), 'getppid': (110, ())}"
    } else if cfg!(target_arch = "aarch64") {
        "{'unshare': (97, (0x10000000,)), 'setns': (268, (0, 0)), 'ptrace': (117, (0, 0, 0, 0)), \
         'keyctl': (219, (0, 0)), 'bpf': (280, (0, 0, 0)), 'mount': (40, (0, 0, 0, 0, 0)), \
         'perf_event_open': (241, (0, 0, 0, 0, 0)), 'clone_newuser': (220, (0x10000000 | 17, 0, 0, 0, 0)), \
         'clone3': (435, (0, 0)), 'getppid': (173, ())}"
    } else {
        return;
    };
    let source = format!(
        "import ctypes, os, threading\n\
         libc = ctypes.CDLL(None, use_errno=True)\n\
         res = []\n\
         for name, (nr, args) in sorted({numbers}.items()):\n\
         \x20   r = libc.syscall(nr, *args)\n\
         \x20   res.append('%s=%d/%d' % (name, r, ctypes.get_errno()))\n\
         pid = os.fork()\n\
         if pid == 0:\n\
         \x20   os._exit(0)\n\
         os.waitpid(pid, 0)\n\
         t = threading.Thread(target=lambda: None)\n\
         t.start()\n\
         t.join()\n\
         raise RuntimeError(' '.join(res) + ' fork+thread ok')\n"
    );
    let dir = std::env::temp_dir().join(format!("siftlab-cli-sandbox-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("vision_tasks.py");
    std::fs::write(&file, source).unwrap();
    let o = mark(&file);
    let _ = std::fs::remove_dir_all(&dir);
    let (out, err) = text(&o);
    for want in [
        "unshare=-1/1",
        "setns=-1/1",
        "ptrace=-1/1",
        "keyctl=-1/1",
        "bpf=-1/1",
        "mount=-1/1",
        "perf_event_open=-1/1",
        "clone_newuser=-1/1",
        "clone3=-1/38",
        "fork+thread ok",
    ] {
        assert!(out.contains(want), "{want} missing:\n{out}\n{err}");
    }
    if cfg!(target_arch = "x86_64") {
        assert!(out.contains("x32=-1/1"), "{out}");
    }
    // An allowed call still runs (getppid inside the sandbox's PID namespace).
    assert!(!out.contains("getppid=-1"), "{out}");
}
