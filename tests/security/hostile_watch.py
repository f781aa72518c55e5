"""The watchers of hostile_check.py: the processes a marking leaves (from /proc, with this
process as their child subreaper), the files it changes, and TCP listeners a fixture's
connections would reach. Linux (/proc), Python 3.8+, standard library only.
"""

import ctypes
import hashlib
import os
import re
import signal
import socket
import threading
import time

OUR_LITTER = re.compile(r"^siftlab_pwned")


# --- processes ----------------------------------------------------------------------------

def read(path, limit=1 << 16):
    try:
        with open(path, "rb") as f:
            return f.read(limit)
    except OSError:
        return None


def proc(pid):
    """(starttime, ppid, state, cmdline) of a live pid, or None."""
    data = read("/proc/%d/stat" % pid)
    if not data:
        return None
    try:
        rest = data[data.rindex(b")") + 2:].split()
        state, ppid, start = rest[0].decode(), int(rest[1]), int(rest[19])
    except (ValueError, IndexError):
        return None
    cmd = read("/proc/%d/cmdline" % pid) or b""
    cmdline = " ".join(a.decode("utf-8", "replace") for a in cmd.split(b"\0") if a)
    return start, ppid, state, cmdline


def processes():
    """{pid: proc(pid)} of every process this process can see."""
    out = {}
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            info = proc(int(entry))
            if info is not None:
                out[int(entry)] = info
    return out


def descendants(procs, root):
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


def state(pid):
    info = proc(pid)
    return info[2] if info else None


_SUBREAPER = [None]


def become_subreaper():
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


def kill_and_reap(pids):
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
            info = proc(pid)
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


def leftovers(before, seen, root, env_token, subreaper):
    """The live processes the marking left: new since `before` and ours for sure (polled under
    the marker, in `seen` as (pid, starttime); adopted by this subreaper; naming the class
    folder `root`; or holding the canary token in their environment). Reaps our zombies.
    Returns {pid: (state, cmdline)}."""
    me = os.getpid()
    out, zombies = {}, []
    for pid, (start, ppid, st, cmdline) in processes().items():
        if pid == me or before.get(pid, (None,))[0] == start:
            continue
        related = (pid, start) in seen or (ppid == me and subreaper) or root in cmdline
        if not related:
            environ = read("/proc/%d/environ" % pid, 1 << 20) or b""
            related = env_token.encode() in environ
        if not related:
            continue
        if st in ("Z", "X"):
            if ppid == me:
                zombies.append(pid)
            continue
        out[pid] = (st, cmdline)
    kill_and_reap(zombies)
    return out


# --- files --------------------------------------------------------------------------------

def sha(path):
    try:
        with open(path, "rb") as f:
            return hashlib.sha256(f.read()).hexdigest()
    except OSError:
        return None


def tree(root, depth=64):
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


def litter(folder):
    """The fixtures' litter (siftlab_pwned*) at the top of a folder: {name: (kind, mtime, size)}."""
    return {n: v for n, v in tree(folder, depth=0).items() if OUR_LITTER.match(n)}


def changed(before, after):
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

class Listener:
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
