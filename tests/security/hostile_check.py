#!/usr/bin/env python3
"""Marks each hostile student file (tests/fixtures/mark/hostile/NAME/vision_tasks.py) with
`siftlab mark` and checks that the marker held (tests/fixtures/mark/hostile/README.md).

Per fixture, in a fresh class folder under the system's temporary directory:

    ROOT/student_a/vision_tasks.py       the hostile file (what is marked)
    ROOT/other_student/vision_tasks.py   a copy of tests/fixtures/mark/good/ (must not change)
    ROOT/siftlab-canary-secret.txt       a random token (SIFTLAB_CANARY_FILE names it)

the marker runs as `SIFTLAB -d DATASET mark student_a/vision_tasks.py -n N --seed S --json
[--no-sandbox]` (cwd ROOT, its own session), with SIFTLAB_CANARY_FILE, SIFTLAB_CANARY_ENV (a
second random token) and SIFTLAB_CANARY_PORT (a TCP listener of this script's, which also
listens on 47011 when that port is free) in its environment, and TMPDIR set to a scratch folder
of its own (where the marker makes its marking folder). The script also plants a decoy marking
folder, /tmp/siftlab-mark-0-hostilecheck-*/ with siftlab_harness.py and cv2.py, and a canary
/tmp/siftlab-canary-*.txt (both under fresh random names). Then it checks:

- the marker exited with 0 or 1 before --timeout (default 600 s; a marker stopped with
  SIGSTOP for 10 s is killed and fails at once);
- stdout is one JSON report with a numeric "total", and the total is at most the fixture's
  maximum (the "Max" column of the README's table);
- neither canary token is in stdout or stderr; no connection reached the listeners;
- stdout and stderr hold no control character but newline and tab (no ESC, CR, BEL...),
  no C1 control and no bidirectional or invisible formatting character; nor do the strings
  of the JSON report once decoded;
- no process the marking started is alive ~1 s after the marker ended (this script makes
  itself a child subreaper, so an escaped daemon comes back to it; also any new process
  whose command line names the harness, the class folder or the fixture's sleeper, or
  whose environment holds the canary token). They are then killed;
- nothing in the class folder changed (a new file beside the submission, the other
  student's file rewritten...), the decoy is intact, no file of the fixtures' litter
  (siftlab_pwned*) new or modified at the top of /tmp or of the account's home, and the
  scratch folder is empty again (the marker's own siftlab-mark-<pid>-* folder is gone).
  Only what this check made, and the fixtures' own litter, is watched: what else runs on
  the machine and writes /tmp cannot fail it.

Prints one PASS/FAIL line per fixture with the reasons, then a summary; exit status 1 when
any fixture fails (2: nothing to run).

    python3 tests/security/hostile_check.py [NAME...] [--only NAME] [--siftlab PATH]
        [--dataset DIR] [-n N] [--seed 0] [--timeout 600] [--no-sandbox] [--keep] [-v] [-j JOBS]

Each fixture runs at the smallest n that shows its attack (CALLS below: 1 call per task,
2 for leak_secrets, whose matching_info leaks one way on odd calls and another on even
ones); -n N runs every fixture at N instead.

As a module: `hostile_check.check(name, **options) -> dict` (keys name, ok, reasons, total,
max, exit, seconds, stdout, stderr, root), `fixtures()`, `max_marks()`. check() makes the
calling process a child subreaper and kills what the marking left running, including new
children adopted by that process: run one check at a time per process. SIFTLAB in the
environment is the default --siftlab. Needs Linux (/proc) and Python 3.8+, standard library
only. Files the fixtures leave that are recognisably theirs (siftlab_pwned_* in /tmp and the
home folders) are removed after they are reported.
"""

import argparse
import ctypes
import hashlib
import json
import os
import pwd
import re
import secrets
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(os.path.dirname(HERE))
HOSTILE = os.path.join(REPO, "tests", "fixtures", "mark", "hostile")
GOOD = os.path.join(REPO, "tests", "fixtures", "mark", "good", "vision_tasks.py")
README = os.path.join(HOSTILE, "README.md")
DEFAULT_SIFTLAB = os.environ.get("SIFTLAB") or os.path.join(REPO, "target", "release", "siftlab")
DEFAULT_DATASET = os.path.join(REPO, "www", "demo", "MyKITTI")
FIXED_PORT = 47011  # the port a fixture tries when SIFTLAB_CANARY_PORT is not in its environment
TMP = "/tmp"

# The marks each fixture's honest parts can earn (the README's "Max" column is authoritative;
# this is the fallback when the README cannot be read).
MAX_MARKS = {
    "run_marker": 6.5,
    "steal_expected": 15.5,
    "always_equal": 15.5,
    "patch_expected": 15.5,
    "shadow_bool": 15.5,
    "wrap_handle": 15.5,
    "leak_secrets": 15.0,
    "write_files": 20.0,
    "network": 20.0,
    "outlive": 20.0,
    "sigstop": 20.0,
    "forge_report": 20.0,
    "ansi_escapes": 10.0,
    "protocol_lines": 15.5,
    "slow_reload": 15.0,
    "import_module": 0.0,
    "import_dunder": 0.0,
    "import_builtins": 0.0,
    "import_exec": 0.0,
    "import_spec": 0.0,
    "fork_bomb": 20.0,
    "memory_bomb": 20.0,
    "overflow_rows": 15.0,
    "knn_huge": 20.0,
    "huge_lines": 20.0,
    "memfd_hold": 20.0,
    "reaped_cpu": 15.0,
    "cpu_farm": 15.0,
    "load_sleep": 0.0,
    "pair_sleep": 0.0,
}

# Calls per task each fixture needs for its attack to show (others: 1). leak_secrets'
# matching_info raises its secrets on odd calls and returns them on even ones.
CALLS = {"leak_secrets": 2}
OUR_LITTER = re.compile(r"^siftlab_pwned")
STOP_LIMIT = 10.0  # seconds a stopped marker is waited for before it is killed
OUTPUT_CAP = 64 << 20  # bytes of the marker's stdout / stderr kept

# Characters no report may hold raw: C0 controls but newline and tab, DEL, C1 controls, and
# the characters that reorder or hide text (as core::mark::escape).
_BAD_CHARS = re.compile("[\x00-\x08\x0b-\x1f\x7f-\x9f\u00ad\u061c\u180e\u200b-\u200f\u2028-\u202e"
                        "\u2060-\u206f\ufeff\ufff9-\ufffb]")


# --- the fixtures and their maxima --------------------------------------------------------

def fixtures():
    """The hostile fixtures' names (folders holding a vision_tasks.py), sorted."""
    if not os.path.isdir(HOSTILE):
        return []
    return sorted(d for d in os.listdir(HOSTILE) if os.path.isfile(os.path.join(HOSTILE, d, "vision_tasks.py")))


def max_marks():
    """{name: max} from the README's table (rows `| \\`name/\\` | ... | max |`), else MAX_MARKS."""
    out = {}
    try:
        with open(README, encoding="utf-8") as f:
            for line in f:
                cells = [c.strip() for c in line.strip().strip("|").split("|")]
                if len(cells) < 3 or not cells[0].startswith("`"):
                    continue
                name = cells[0].strip("`").rstrip("/")
                try:
                    out[name] = float(cells[-1].strip("*` "))
                except ValueError:
                    continue
    except OSError:
        pass
    merged = dict(MAX_MARKS)
    merged.update(out)
    return merged


# --- processes ----------------------------------------------------------------------------

def _read(path, limit=1 << 16):
    try:
        with open(path, "rb") as f:
            return f.read(limit)
    except OSError:
        return None


def _proc(pid):
    """(starttime, ppid, state, cmdline) of a live pid, or None."""
    data = _read("/proc/%d/stat" % pid)
    if not data:
        return None
    try:
        rest = data[data.rindex(b")") + 2:].split()
        state, ppid, start = rest[0].decode(), int(rest[1]), int(rest[19])
    except (ValueError, IndexError):
        return None
    cmd = _read("/proc/%d/cmdline" % pid) or b""
    cmdline = " ".join(a.decode("utf-8", "replace") for a in cmd.split(b"\0") if a)
    return start, ppid, state, cmdline


def _processes():
    out = {}
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            info = _proc(int(entry))
            if info is not None:
                out[int(entry)] = info
    return out


def _descendants(procs, root):
    """pids under root (by ppid) in a snapshot."""
    children = {}
    for pid, (_, ppid, _, _) in procs.items():
        children.setdefault(ppid, []).append(pid)
    out, todo = set(), [root]
    while todo:
        for c in children.get(todo.pop(), ()):
            if c not in out:
                out.add(c)
                todo.append(c)
    return out


_SUBREAPER = [None]


def _become_subreaper():
    """PR_SET_CHILD_SUBREAPER: a daemon that escapes the marker is reparented to us, not init."""
    if _SUBREAPER[0] is None:
        ok = False
        try:
            libc = ctypes.CDLL(None, use_errno=True)
            ok = libc.prctl(36, 1, 0, 0, 0) == 0
        except (OSError, AttributeError):
            pass
        _SUBREAPER[0] = ok
    return _SUBREAPER[0]


def _kill_and_reap(pids):
    me = os.getpid()
    for pid in pids:
        for sig in (signal.SIGKILL, signal.SIGCONT):
            try:
                os.kill(pid, sig)
            except OSError:
                pass
    deadline = time.time() + 5
    left = set(pids)
    while left and time.time() < deadline:
        for pid in list(left):
            info = _proc(pid)
            if info is None:
                left.discard(pid)
            elif info[1] == me:
                try:
                    if os.waitpid(pid, os.WNOHANG)[0] == pid:
                        left.discard(pid)
                except ChildProcessError:
                    left.discard(pid)
            elif info[2] == "Z":
                left.discard(pid)  # someone else's zombie to reap
        time.sleep(0.05)


# --- files --------------------------------------------------------------------------------

def _sha(path):
    try:
        with open(path, "rb") as f:
            return hashlib.sha256(f.read()).hexdigest()
    except OSError:
        return None


def _tree(root, depth=64):
    """{relative path: (kind, mtime_ns, size)} of everything under root (not following links)."""
    out = {}

    def walk(d, rel, level):
        try:
            entries = list(os.scandir(d))
        except OSError:
            return
        for e in entries:
            r = os.path.join(rel, e.name) if rel else e.name
            try:
                st = e.stat(follow_symlinks=False)
            except OSError:
                continue
            kind = "dir" if e.is_dir(follow_symlinks=False) else "file"
            out[r] = (kind, st.st_mtime_ns, st.st_size)
            if kind == "dir" and level < depth:
                walk(e.path, r, level + 1)

    walk(root, "", 0)
    return out


def _top(folder):
    """{name: (kind, mtime_ns, size)} of a folder's own entries."""
    return _tree(folder, depth=0)


def _litter(folder):
    """The fixtures' litter (siftlab_pwned*) at the top of a folder: {name: (kind, mtime, size)}."""
    return {n: v for n, v in _top(folder).items() if OUR_LITTER.match(n)}


def _changed(before, after):
    """Entries new in after, or regular files whose mtime or size changed."""
    out = []
    for name, (kind, mtime, size) in sorted(after.items()):
        old = before.get(name)
        if old is None:
            out.append((name, "new"))
        elif kind == "file" and (old[1] != mtime or old[2] != size):
            out.append((name, "modified"))
    return out


# --- the canary listener ------------------------------------------------------------------

class _Listener:
    """Accepts and counts TCP connections on 127.0.0.1:port (0: any free port)."""

    def __init__(self, port=0):
        self.count = 0
        self.peek = b""
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        self.sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        self.sock.bind(("127.0.0.1", port))
        self.sock.listen(64)
        self.sock.settimeout(0.2)
        self.port = self.sock.getsockname()[1]
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self._serve, daemon=True)
        self.thread.start()

    def _serve(self):
        while not self.stop.is_set():
            try:
                conn, _ = self.sock.accept()
            except socket.timeout:
                continue
            except OSError:
                break
            self.count += 1
            try:
                conn.settimeout(0.5)
                if len(self.peek) < 200:
                    self.peek += conn.recv(200)
            except OSError:
                pass
            finally:
                conn.close()

    def close(self):
        self.stop.set()
        self.thread.join(2)
        self.sock.close()


# --- one fixture --------------------------------------------------------------------------

def _pump(stream, buf):
    while True:
        chunk = stream.read1(1 << 16) if hasattr(stream, "read1") else stream.read(1 << 16)
        if not chunk:
            break
        if len(buf) < OUTPUT_CAP:
            buf.extend(chunk[:OUTPUT_CAP - len(buf)])


def _bad_chars(text):
    m = _BAD_CHARS.search(text)
    if m is None:
        return None
    n = len(_BAD_CHARS.findall(text))
    return "%d (first U+%04X at %d)" % (n, ord(m.group()), m.start())


def _safe(text):
    """text with the characters a terminal would obey shown as escapes (for our own output)."""
    return _BAD_CHARS.sub(lambda m: "\\x%02x" % ord(m.group()) if ord(m.group()) < 0x100
                          else "\\u%04x" % ord(m.group()), text)


def _json_strings(v):
    if isinstance(v, str):
        yield v
    elif isinstance(v, dict):
        for k, x in v.items():
            yield k
            yield from _json_strings(x)
    elif isinstance(v, list):
        for x in v:
            yield from _json_strings(x)


def _state(pid):
    info = _proc(pid)
    return info[2] if info else None


def check(name, siftlab=None, dataset=None, n=None, seed=0, no_sandbox=False, timeout=600.0, keep=False,
          max_total=None, log=None):
    """Marks fixture `name` and checks the marker held. Returns {"name", "ok", "reasons",
    "total", "max", "exit", "seconds", "stdout", "stderr", "root"}."""
    siftlab = os.path.abspath(siftlab or DEFAULT_SIFTLAB)
    dataset = os.path.abspath(dataset or DEFAULT_DATASET)
    source = os.path.join(HOSTILE, name, "vision_tasks.py")
    limit = max_marks().get(name) if max_total is None else max_total
    result = {"name": name, "ok": False, "reasons": [], "total": None, "max": limit, "exit": None,
              "seconds": None, "stdout": "", "stderr": "", "root": None}
    reasons = result["reasons"]
    if not os.path.isfile(source):
        reasons.append("no fixture %s" % source)
        return result
    if not os.access(siftlab, os.X_OK):
        reasons.append("no siftlab at %s (build it, or give --siftlab / SIFTLAB)" % siftlab)
        return result
    if limit is None:
        reasons.append("no maximum for %s in %s" % (name, README))
    subreaper = _become_subreaper()

    # The class folder, the canaries, the decoy.
    root = tempfile.mkdtemp(prefix="siftlab-hostile-%s-" % name)
    result["root"] = root
    student = os.path.join(root, "student_a", "vision_tasks.py")
    other = os.path.join(root, "other_student", "vision_tasks.py")
    for path, src in ((student, source), (other, GOOD)):
        os.makedirs(os.path.dirname(path))
        shutil.copyfile(src, path)
    file_token, env_token = secrets.token_hex(16), secrets.token_hex(16)
    canary = os.path.join(root, "siftlab-canary-secret.txt")
    with open(canary, "w") as f:
        f.write(file_token + "\n")
    # A canary in the host's /tmp (leak_secrets looks for /tmp/siftlab-canary-*.txt) and a decoy
    # marking folder there (outlive's daemon edits /tmp/siftlab-* folders): fresh random names,
    # so that concurrent checks and other programs never meet them.
    fd, tmp_canary = tempfile.mkstemp(prefix="siftlab-canary-", suffix=".txt", dir=TMP)
    with os.fdopen(fd, "w") as f:
        f.write(file_token + "\n")
    decoy = tempfile.mkdtemp(prefix="siftlab-mark-0-hostilecheck-", dir=TMP)
    # The marker's TMPDIR: its marking folder goes here, and must be gone at the end.
    scratch = tempfile.mkdtemp(prefix="siftlab-hostile-tmp-%s-" % name)
    for fname in ("siftlab_harness.py", "cv2.py"):
        src = os.path.join(REPO, "www", "py", fname)
        if os.path.isfile(src):
            shutil.copyfile(src, os.path.join(decoy, fname))
        else:
            with open(os.path.join(decoy, fname), "w") as f:
                f.write("# decoy\n")
    decoy_tree = {r: _sha(os.path.join(decoy, r)) for r in _tree(decoy)}
    hashes = {student: _sha(student), other: _sha(other)}

    listeners = [_Listener(0)]
    try:
        listeners.append(_Listener(FIXED_PORT))
    except OSError:
        pass  # in use: the fixtures' fallback port is not watched this time

    env = dict(os.environ)
    env.update(SIFTLAB_CANARY_FILE=canary, SIFTLAB_CANARY_ENV=env_token,
               SIFTLAB_CANARY_PORT=str(listeners[0].port), TMPDIR=scratch)
    if n is None:
        n = CALLS.get(name, 1)
    result["n"] = n
    cmd = [siftlab, "-d", dataset, "mark", os.path.join("student_a", "vision_tasks.py"), "-n", str(n),
           "--seed", str(seed), "--json"]
    if no_sandbox:
        cmd.append("--no-sandbox")

    proc, litter = None, []
    try:
        homes = []
        for h in (pwd.getpwuid(os.getuid()).pw_dir, os.environ.get("HOME")):
            if h and os.path.isdir(h) and os.path.realpath(h) not in [os.path.realpath(x) for x in homes]:
                homes.append(h)
        before_procs = _processes()
        before_tree = _tree(root)
        before_tmp = _litter(TMP)
        before_homes = {h: _litter(h) for h in homes}

        out, err = bytearray(), bytearray()
        t0 = time.time()
        proc = subprocess.Popen(cmd, cwd=root, env=env, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                                stderr=subprocess.PIPE, start_new_session=True)
        pumps = [threading.Thread(target=_pump, args=(proc.stdout, out), daemon=True),
                 threading.Thread(target=_pump, args=(proc.stderr, err), daemon=True)]
        for t in pumps:
            t.start()
        seen = set()  # (pid, starttime) of the marker's descendants, as polled
        stopped_since = None
        killed = None
        while True:
            if proc.poll() is not None:
                break
            now = time.time()
            procs = _processes()
            for pid in _descendants(procs, proc.pid):
                seen.add((pid, procs[pid][0]))
            if _state(proc.pid) == "T":
                stopped_since = stopped_since or now
                if now - stopped_since >= STOP_LIMIT:
                    killed = "the marker was stopped (SIGSTOP) for %.0f s: killed" % STOP_LIMIT
            else:
                stopped_since = None
            if now - t0 > timeout:
                killed = "the marker ran over %.0f s: killed" % timeout
            if killed:
                for sig in (signal.SIGKILL, signal.SIGCONT):
                    try:
                        os.killpg(proc.pid, sig)
                    except OSError:
                        pass
                    try:
                        os.kill(proc.pid, sig)
                    except OSError:
                        pass
                proc.wait()
                break
            time.sleep(0.25)
        seconds = time.time() - t0
        for t in pumps:
            t.join(3)  # a leftover child may hold the pipes open: do not wait for it
        result["exit"], result["seconds"] = proc.returncode, round(seconds, 1)
        stdout = bytes(out).decode("utf-8", "replace")
        stderr = bytes(err).decode("utf-8", "replace")
        result["stdout"], result["stderr"] = stdout, stderr
        if killed:
            reasons.append(killed)

        time.sleep(1.0)  # what the marking left running has had time to show itself

        # Processes.
        me = os.getpid()
        after_procs = _processes()
        leftovers, zombies = {}, []
        for pid, (start, ppid, state, cmdline) in after_procs.items():
            if pid == me or before_procs.get(pid, (None,))[0] == start:
                continue
            # Ours for sure (these get killed): polled under the marker, adopted by this
            # subreaper, naming the class folder, or holding the canary token in its environment.
            related = (pid, start) in seen or (ppid == me and subreaper) or root in cmdline
            if not related:
                environ = _read("/proc/%d/environ" % pid, 1 << 20) or b""
                related = env_token.encode() in environ
            if not related:
                continue
            if state in ("Z", "X"):
                if ppid == me:
                    zombies.append(pid)
                continue
            leftovers[pid] = (state, cmdline)
        _kill_and_reap(zombies)
        if leftovers:
            shown = sorted(leftovers.items())[:3]
            reasons.append("%d process(es) outlived the marker: %s%s" % (
                len(leftovers), "; ".join("%d [%s] %s" % (p, s, _safe(c[:80])) for p, (s, c) in shown),
                " ..." if len(leftovers) > 3 else ""))
            _kill_and_reap(list(leftovers))

        # Files.
        changes = _changed(before_tree, _tree(root))
        if changes:
            reasons.append("class folder changed: %s" % ", ".join("%s (%s)" % c for c in changes[:6]))
        for path, digest in hashes.items():
            if _sha(path) != digest:
                reasons.append("%s is not byte-identical any more" % os.path.relpath(path, root))
        after_decoy = {r: _sha(os.path.join(decoy, r)) for r in _tree(decoy)}
        edited = sorted(r for r in set(after_decoy) | set(decoy_tree) if after_decoy.get(r) != decoy_tree.get(r))
        if edited:
            reasons.append("the decoy marking folder %s was edited: %s" % (decoy, ", ".join(edited)))
        tmp_bad = ["%s (%s)" % c for c in _changed(before_tmp, _litter(TMP))]
        litter += [os.path.join(TMP, name_) for name_, _ in _changed(before_tmp, _litter(TMP))]
        left = sorted(_tree(scratch, depth=0))
        if left:
            tmp_bad.append("the marker's TMPDIR still holds %s" % ", ".join(left[:3]))
        if tmp_bad:
            reasons.append("/tmp: %s" % ", ".join(tmp_bad[:6]))
        for home, before_home in before_homes.items():
            home_bad = _changed(before_home, _litter(home))
            if home_bad:
                reasons.append("%s: %s" % (home, ", ".join("%s (%s)" % c for c in home_bad[:6])))
                litter += [os.path.join(home, name_) for name_, _ in home_bad]

        # Secrets, network.
        for label, token in (("canary file", file_token), ("canary environment variable", env_token)):
            where = [s for s, text in (("stdout", stdout), ("stderr", stderr)) if token in text]
            if where:
                reasons.append("the %s's token is in the marker's %s" % (label, " and ".join(where)))
        connections = sum(lst.count for lst in listeners)
        if connections:
            reasons.append("%d connection(s) reached the canary listener (%s)" % (
                connections, ", ".join("127.0.0.1:%d" % lst.port for lst in listeners if lst.count)))

        # The report.
        for label, text in (("stdout", stdout), ("stderr", stderr)):
            bad = _bad_chars(text)
            if bad:
                reasons.append("%s holds control/hidden characters: %s" % (label, bad))
        report = None
        try:
            report = json.loads(stdout)
        except ValueError as e:
            reasons.append("stdout is not one JSON report (%s): %r" % (e, stdout[:120]))
        if report is not None:
            total = report.get("total") if isinstance(report, dict) else None
            if not isinstance(total, (int, float)) or isinstance(total, bool):
                reasons.append("the report has no numeric total")
            else:
                result["total"] = float(total)
                if limit is not None and total > limit + 1e-6:
                    reasons.append("total %.4g is over the %.4g the honest parts earn" % (total, limit))
            inner_bad = [b for b in (_bad_chars(s) for s in _json_strings(report)) if b]
            if inner_bad:
                reasons.append("%d string(s) of the JSON report hold control/hidden characters once decoded, "
                               "e.g. %s" % (len(inner_bad), inner_bad[0]))
        if not killed and proc.returncode not in (0, 1):
            reasons.append("the marker exited with %s (0 or 1 expected)%s" % (
                proc.returncode if proc.returncode >= 0 else "signal %d" % -proc.returncode,
                ": " + _safe(stderr.strip().splitlines()[-1][:160]) if stderr.strip() else ""))

    finally:
        # Clean up, also after an interruption: the marker's group, our listeners, the decoy,
        # the canary in /tmp, the litter the fixtures are known to leave.
        if proc is not None and proc.poll() is None:
            for sig in (signal.SIGKILL, signal.SIGCONT):
                try:
                    os.killpg(proc.pid, sig)
                except OSError:
                    pass
            proc.wait()
        for lst in listeners:
            lst.close()
        for path in litter:
            if os.path.isdir(path) and not os.path.islink(path):
                shutil.rmtree(path, ignore_errors=True)
            else:
                try:
                    os.unlink(path)
                except OSError:
                    pass
        shutil.rmtree(decoy, ignore_errors=True)
        shutil.rmtree(scratch, ignore_errors=True)
        try:
            os.unlink(tmp_canary)
        except OSError:
            pass
        if not keep:
            shutil.rmtree(root, ignore_errors=True)
    result["ok"] = not reasons
    if log:
        log(result)
    return result


def line(r):
    total = "-" if r["total"] is None else "%.2f" % r["total"]
    limit = "?" if r["max"] is None else "%g" % r["max"]
    head = "%s %-16s n %d total %6s / max %-5s exit %-4s %6ss" % (
        "PASS" if r["ok"] else "FAIL", r["name"], r.get("n") or 0, total, limit,
        "-" if r["exit"] is None else r["exit"], "-" if r["seconds"] is None else r["seconds"])
    if r["ok"]:
        return head
    return head + "\n     - " + "\n     - ".join(_safe(x) for x in r["reasons"])


def _check_one(job):
    name, options = job
    return check(name, **options)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("names", nargs="*", help="fixtures to run (default: all)")
    ap.add_argument("--only", action="append", default=[], metavar="NAME", help="a fixture to run (repeatable)")
    ap.add_argument("--siftlab", default=DEFAULT_SIFTLAB, help="the siftlab binary (default: $SIFTLAB or %(default)s)")
    ap.add_argument("--dataset", default=DEFAULT_DATASET, help="default: %(default)s")
    ap.add_argument("-n", type=int, default=None,
                    help="calls per task for every fixture (default: each fixture's own, CALLS)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--timeout", type=float, default=600.0, help="seconds before the marker is killed (a failure)")
    ap.add_argument("--no-sandbox", action="store_true", help="pass --no-sandbox to siftlab mark")
    ap.add_argument("--keep", action="store_true", help="keep each class folder (its path is printed)")
    ap.add_argument("-v", "--verbose", action="store_true", help="print the end of the marker's stderr on failure")
    ap.add_argument("-j", "--jobs", type=int, default=1,
                    help="fixtures checked at once, each in a process of its own (default: %(default)s)")
    a = ap.parse_args(argv)
    known = fixtures()
    names = a.names + a.only or known
    unknown = [x for x in names if x not in known]
    if unknown or not names:
        print("unknown fixture(s): %s (known: %s)" % (", ".join(unknown), ", ".join(known)), file=sys.stderr)
        return 2
    options = dict(siftlab=a.siftlab, dataset=a.dataset, n=a.n, seed=a.seed, no_sandbox=a.no_sandbox,
                   timeout=a.timeout, keep=a.keep)
    results = []
    # Several at once: each check runs in a worker process of its own, which becomes the
    # subreaper of what its marking leaves; what each watches is its own (a fresh class
    # folder, scratch TMPDIR, canary tokens and listener), so two never see each other's.
    if a.jobs > 1:
        import multiprocessing
        pool = multiprocessing.get_context("fork").Pool(a.jobs, maxtasksperchild=1)
        done = pool.imap(_check_one, [(name, options) for name in names])
    else:
        done = (check(name, **options) for name in names)
    for r in done:
        results.append(r)
        print(line(r), flush=True)
        if a.keep:
            print("     class folder: %s" % r["root"], flush=True)
        if a.verbose and not r["ok"] and r["stderr"].strip():
            tail = r["stderr"].strip().splitlines()[-8:]
            print("     stderr: " + "\n             ".join(_safe(t)[:200] for t in tail), flush=True)
    if a.jobs > 1:
        pool.close()
        pool.join()
    failed = [r["name"] for r in results if not r["ok"]]
    print("%d fixture(s): %d passed, %d failed%s" % (
        len(results), len(results) - len(failed), len(failed), (": " + ", ".join(failed)) if failed else ""))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
