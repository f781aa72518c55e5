"""siftlab's marking harness: runs a student's `vision_tasks.py` for `siftlab mark` and the
app's "Mark my code" view (docs/marking.md: the design and the messages).

Embedding (Pyodide): import this module, set `siftlab_harness.host_knn` to a function taking
one JSON line (a knn request) and returning one JSON line (the answer), then call
`handle(line) -> line` per request. When host_knn is unset and a `siftlab_knn` function is
on the JavaScript global scope, that one is used.

Command line (CPython): `python3 -I -S -B siftlab_harness.py [--path DIR]... [--drop-uid N]`
reads requests from stdin, one JSON line each, and writes each reply as one line on stdout;
while the student's code runs, each knn request is written to stdout and its answer read from
stdin. At start the protocol moves to private descriptors and fds 0 and 1 become /dev/null,
so nothing the student's code writes can reach the protocol's stdout. `--drop-uid N` (the
sandbox as root) sets the uid and gid to N before any other work; `--path DIR` puts DIR
(numpy's parent folder) on sys.path.

The harness judges nothing: it never sees the expected values. It returns what the
student's functions returned, encoded by type (docs/marking.md, "Typed values"), and siftlab
compares outside this interpreter.

Its parts are modules beside it, loaded from this folder as cv2 and its parts are:
`_siftlab_harness_run.py` (running the student's code), `_siftlab_harness_values.py` (what it
returned, as the replies carry it) and `_siftlab_harness_imports.py` (the lab's import rule,
in place once it is loaded).
"""

import os
import sys

if __name__ == "__main__":
    # Before anything else: leave root (the sandbox's real uid) for the marking uid, and
    # put numpy's folder on the path (-I -S gives the standard library only).
    _argv = sys.argv[1:]
    while _argv:
        _flag = _argv.pop(0)
        if _flag == "--drop-uid":
            _uid = int(_argv.pop(0))
            os.setgroups([])
            os.setgid(_uid)
            os.setuid(_uid)
        elif _flag == "--path":
            sys.path.append(_argv.pop(0))

import base64
import builtins
import importlib.util
import io
import json
import linecache
import types

HERE = os.path.dirname(os.path.abspath(__file__))


def _load_shim(name):
    """One of our modules from this folder, whatever else sys.path holds (in the CLI, -I
    leaves this folder off it): cv2 and its parts, vision_tasks_base, the harness's parts.
    Each imports those it uses by name, so they load in that order."""
    spec = importlib.util.spec_from_file_location(name, os.path.join(HERE, name + ".py"))
    mod = importlib.util.module_from_spec(spec)
    sys.modules[name] = mod
    spec.loader.exec_module(mod)
    return mod


for _part in ("_siftlab_cv2_base", "_siftlab_cv2_types", "_siftlab_cv2_descriptors"):
    _load_shim(_part)
del _part
cv2 = _load_shim("cv2")
_load_shim("vision_tasks_base")

if cv2._np is None:
    # Without numpy a file may still say `import numpy as np` and not use it; any use of
    # the stand-in module raises cv2's "this needs numpy" error, naming what was used.
    _numpy_stub = types.ModuleType("numpy", "stand-in: numpy is not available in this Python")

    def _numpy_getattr(name):
        if name.startswith("__"):
            raise AttributeError(name)
        raise cv2._numpy_missing("numpy.%s" % name)

    _numpy_stub.__getattr__ = _numpy_getattr
    sys.modules["numpy"] = _numpy_stub

# The embedder's knn function (one JSON line in, one JSON line out).
host_knn = None


def _host_bridge(request):
    fn = host_knn
    if fn is None and sys.platform == "emscripten":
        try:
            from js import siftlab_knn as fn  # noqa: F811
        except ImportError:
            fn = None
    if fn is None:
        raise RuntimeError("siftlab_harness.host_knn is not set: no matcher to answer knnMatch")
    answer = fn(json.dumps(request, separators=(",", ":")))
    if not isinstance(answer, str):
        answer = str(answer)
    return json.loads(answer)


cv2._host = _host_bridge


# The harness's parts: running the student's code, and what it returns as the replies carry it.
_load_shim("_siftlab_harness_run")
_load_shim("_siftlab_harness_values")
from _siftlab_harness_run import STUDENT_FILE, _Failure, _add_output, _error_reply, _run  # noqa: E402
from _siftlab_harness_values import _check_matches, _describe, _dumps, _tname, _typed  # noqa: E402

# What the student's file may import: the lab's rule (standard library, cv2, numpy,
# vision_tasks_base) on every route in, put in place by loading its module. It goes last, after
# every import of the harness's own, and takes the real import functions now, before any of the
# student's code runs.
_load_shim("_siftlab_harness_imports")

_student_builtins = builtins.__dict__


# --- state ---------------------------------------------------------------------------------

class _Pair:
    __slots__ = ("id", "kp1", "data1", "n1", "kp2", "data2", "n2")

    def images(self):
        """(previous, current) as images the shim's SIFT knows: for the base class's
        featureMatching(cur_image, prev_image) / featureInfo, which marking does not call."""
        return (cv2.Frame("%s/1" % self.id, self.kp1, self.data1, self.n1),
                cv2.Frame("%s/2" % self.id, self.kp2, self.data2, self.n2))


class _State:
    def __init__(self):
        self.module = None
        self.vt = None
        self.pairs = {}


_state = _State()


def _keypoints(rows):
    out = []
    for r in rows:
        x, y, size, angle, response, octave = r
        out.append((float(x), float(y), float(size), float(angle), float(response), int(octave)))
    return out


def _des_bytes(b64, n):
    data = base64.b64decode(b64) if b64 else b""
    if len(data) != 128 * n:
        raise ValueError("descriptors: %d bytes for %d keypoints (128 each)" % (len(data), n))
    return data


def _load(msg):
    source = msg["source"]
    if not isinstance(source, str):
        raise ValueError("load: source must be a string")
    _state.module = _state.vt = None
    try:
        code = compile(source, STUDENT_FILE, "exec", dont_inherit=True)
    except (SyntaxError, ValueError) as e:  # ValueError: null bytes (before Python 3.12)
        if isinstance(e, SyntaxError):
            return _error_reply(e, "syntax")
        return {"error": "SyntaxError: %s (%s)" % (e, STUDENT_FILE), "kind": "syntax"}
    linecache.cache[STUDENT_FILE] = (len(source), None, source.splitlines(True), STUDENT_FILE)
    mod = types.ModuleType("vision_tasks")
    mod.__file__ = STUDENT_FILE
    mod.__dict__["__builtins__"] = _student_builtins
    sys.modules["vision_tasks"] = mod

    def build():
        exec(code, mod.__dict__)
        cls = mod.__dict__.get("VisionTasks")
        if cls is None:
            raise NameError("%s defines no class VisionTasks" % STUDENT_FILE)
        return cls()

    try:
        vt, buf = _run(build, ())
    except _Failure as f:
        if isinstance(f.exc, ImportError):
            f.reply["kind"] = "import"
        return f.reply
    _state.module, _state.vt = mod, vt
    return _add_output({"ok": True}, buf)


def _pair(msg):
    p = _Pair()
    p.id = str(msg["id"])
    p.kp1 = _keypoints(msg["kp1"])
    p.kp2 = _keypoints(msg["kp2"])
    p.n1, p.n2 = len(p.kp1), len(p.kp2)
    p.data1 = _des_bytes(msg["des1"], p.n1)
    p.data2 = _des_bytes(msg["des2"], p.n2)
    _state.pairs[p.id] = p
    return {"ok": True}


def _call(msg):
    vt = _state.vt
    if vt is None:
        return {"error": "no file loaded", "kind": "protocol"}
    fn = msg["fn"]
    p = _state.pairs.get(str(msg["pair"]))
    if p is None:
        return {"error": "no pair %r" % (msg["pair"],), "kind": "protocol"}
    compact = bool(msg.get("compact"))
    if fn in ("dt", "nn", "nndr"):
        des1 = cv2._descriptors(p.data1, p.n1)
        des2 = cv2._descriptors(p.data2, p.n2)
        cv2._refs[:] = [(d, "%s/%d" % (p.id, i), data) for i, d, data in
                        ((1, des1, p.data1), (2, des2, p.data2)) if d is not None]
        t = msg.get("threshold")
        t = None if t is None else float(t)
        try:
            value, buf = _run(getattr(vt, fn), (des1, des2, t))
            rows = _check_matches(fn, value, compact)
        except _Failure as f:
            return f.reply
        finally:
            cv2._refs[:] = []
        return _add_output({"ok": rows}, buf)
    if fn == "matching_info":
        kp1 = tuple(cv2._keypoint(*k) for k in p.kp1)
        kp2 = tuple(cv2._keypoint(*k) for k in p.kp2)
        matches = [cv2._dmatch(int(q), int(t), 0, float(d)) for q, t, d in msg["matches"]]
        try:
            value, buf = _run(vt.matching_info, (kp1, kp2, matches))
        except _Failure as f:
            return f.reply
        shape = "((x, y), [(x, y), ...], [d, ...])"
        try:
            a, b, c = value
        except Exception:
            return _add_output({"error": "matching_info must return %s, got %s" % (shape, _describe(value)),
                                "kind": "type"}, buf)
        for part, want, what in ((a, tuple, "the feature's coordinates"),
                                 (b, list, "the matches' coordinates"),
                                 (c, list, "the matches' distances")):
            if type(part) is not want:
                return _add_output({"error": "matching_info: %s must be a %s, got %s"
                                    % (what, want.__name__, _tname(part)), "kind": "type"}, buf)
        return _add_output({"ok": _typed((a, b, c))}, buf)
    return {"error": "unknown fn %r" % (fn,), "kind": "protocol"}


def _hello(msg):
    np = cv2._np
    return {"ok": True, "python": sys.version.split()[0], "platform": sys.platform,
            "numpy": None if np is None else np.__version__}


def _drop(msg):
    _state.pairs.pop(str(msg["id"]), None)
    return {"ok": True}


_OPS = {"load": _load, "pair": _pair, "call": _call, "hello": _hello, "drop": _drop}


def handle(line):
    """One request line -> one reply line (docs/marking.md)."""
    msg = None
    try:
        msg = json.loads(line)
        op = _OPS.get(msg.get("op")) if isinstance(msg, dict) else None
        if op is None:
            reply = {"error": "unknown request %r" % (line[:80],), "kind": "protocol"}
        else:
            reply = op(msg)
    except KeyboardInterrupt:
        raise
    except BaseException as e:  # a malformed request, or a fault of ours
        reply = {"error": "%s: %s" % (type(e).__name__, e), "kind": "protocol"}
    if isinstance(msg, dict) and "req" in msg:
        reply["req"] = msg["req"]
    return _dumps(reply)


def main():
    global host_knn
    # The protocol on descriptors of its own; fds 0 and 1 become /dev/null, so the student's
    # raw writes (os.write(1, ...), sys.__stdout__) never reach siftlab's reader.
    inp = os.fdopen(os.dup(0), "rb")
    out = os.fdopen(os.dup(1), "wb")
    null = os.open(os.devnull, os.O_RDWR)
    os.dup2(null, 0)
    os.dup2(null, 1)
    sys.stdin = io.StringIO("")
    sys.stdout = sys.__stdout__ = open(os.devnull, "w")

    def cli_knn(line):
        out.write(line.encode("utf-8") + b"\n")
        out.flush()
        answer = inp.readline()
        if not answer:  # the host is gone
            os._exit(3)
        return answer.decode("utf-8")

    host_knn = cli_knn
    while True:
        raw = inp.readline()
        if not raw:
            return 0
        line = raw.decode("utf-8").strip()
        if not line:
            continue
        out.write(handle(line).encode("utf-8") + b"\n")
        out.flush()


if __name__ == "__main__":
    sys.exit(main())
