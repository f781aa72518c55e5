#!/usr/bin/env python3
"""The reference marker: a student's `vision_tasks.py` marked with real CPython and OpenCV
4.8.0.76, as the lab's automarker marks it, on the cases `siftlab mark --json` lists (or on
cases of its own from a seed). `siftlab mark` and the app must give every file the marks
this script gives it (docs/marking.md).

    python3 tests/references/mark_reference.py STUDENT.py --cases REPORT.json [--out FILE]
    python3 tests/references/mark_reference.py STUDENT.py --seed 0 [-n 25] [--out FILE]
    python3 tests/references/mark_reference.py STUDENT.py --cases REPORT.json --compare

--cases takes `siftlab mark --json`'s output (an object with "cases") or a bare list of
cases, each {"task", "frame", "threshold", "strategy"?, "feature"?} (docs/marking.md,
"Cases"); other fields are ignored (--compare reads the report's per-case "status" and its
per-task marks, says where siftlab and the reference differ and exits 1 if they do).
--seed draws cases of its own with Python's `random`
(the distributions of docs/marking.md, not siftlab's generator: the same seed gives other
cases than `siftlab mark --seed`).

The student's file runs in a child process (this script with --worker) with real cv2, real
numpy, a `vision_tasks_base` of this script's own and only the lab's modules importable
(the standard library, cv2, numpy). Per call: the function gets fresh copies of the
arguments, 10 s of CPU time (a call over it is a runtime error; one still running after 3 x
10 s of wall time is killed and the child started again); per task 300 s in all (the calls
after that: runtime errors). CPU time, so that a busy machine does not fail slow calls. The
reference values are lab_reference.py's (the lab's strategies on cv2.BFMatcher().knnMatch).

A call is an error (runtime) when it raises, returns the wrong type (dt/nn/nndr: not a list
of lists or tuples of cv2.DMatch; matching_info: not three items, a tuple, a list and a
list, as the lab's base class asserts), or runs over the time; correct when dt/nn/nndr's
rows equal the reference's DMatch by DMatch (queryIdx, trainIdx, float32 distance, in
order) and when matching_info's three items == the reference's tuple (Python's ==). The
file scores 0 on every task when it is not printable ASCII (tab, newline, CRLF allowed),
does not compile, or fails to import or to build VisionTasks().

Prints one JSON object (--out writes it to a file too):
  {"file", "ascii": true|false, "load": {"ok": true} | {"error", "kind"},
   "tasks": {TASK: {"calls", "correct", "errors", "mark"}, ...}, "total",
   "cases": [{...the case..., "status": "correct"|"wrong"|"error", "kind"?, "message"?,
              "seconds" (CPU), "wall"}]}
mark = 0.5 (when errors == 0) + 4.5 * correct / calls; total = the four marks' sum.

OPENCV_IPP=disabled and OPENCV_CPU_DISABLE=AVX512-SKX are set before cv2 is imported (as
match_all_reference.py does), so the keypoints and descriptors are those siftlab computes at
8 lanes. Requires opencv-contrib-python-headless==4.8.0.76 and numpy<2.
"""
from __future__ import annotations

import argparse
import builtins
import io
import json
import os
import random
import select
import subprocess
import sys
import time
import traceback
import types

os.environ["OPENCV_IPP"] = "disabled"
# 8 lanes on any CPU; the hyphenated name is OpenCV's (g_hwFeatureNames in core/src/system.cpp).
os.environ["OPENCV_CPU_DISABLE"] = ",".join(
    v for v in (os.environ.get("OPENCV_CPU_DISABLE"), "AVX512-SKX") if v)

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
TASKS = ("dt", "nn", "nndr", "matching_info")
STRATEGIES = ("dt", "nn", "nndr")
CALL_LIMIT = 10.0
TASK_LIMIT = 300.0
STUDENT_FILE = "vision_tasks.py"

# The base class the student's file imports (the lab's, as far as marking can tell).
BASE_SOURCE = '''
import cv2

NUM_FEATURES = 1500
MATCHING_ALGOS = ("dt", "nn", "nndr")


class VisionTasksBase:
    NUM_FEATURES = NUM_FEATURES

    def __init__(self, *args, **kwargs):
        algo = kwargs.get("matching_algo", args[0] if args else None)
        self.threshold = kwargs.get("threshold", args[1] if len(args) > 1 else None)
        self.matching_algo = getattr(self, algo) if algo in MATCHING_ALGOS else None
        self.detector = cv2.SIFT_create(nfeatures=NUM_FEATURES)

    def dt(self, des1, des2, threshold):
        raise NotImplementedError

    def nn(self, des1, des2, threshold=None):
        raise NotImplementedError

    def nndr(self, des1, des2, threshold):
        raise NotImplementedError

    def matching_info(self, kp1, kp2, matches):
        raise NotImplementedError

    def featureMatching(self, cur_image, prev_image):
        prev_kp, prev_des = self.detector.detectAndCompute(prev_image, None)
        cur_kp, cur_des = self.detector.detectAndCompute(cur_image, None)
        matches = self.matching_algo(prev_des, cur_des, self.threshold)
        assert type(matches) is list, "Matching algorithm must return a list of matches"
        return prev_kp, cur_kp, matches
'''


# --- the file checks ------------------------------------------------------------------------

def ascii_problem(data: bytes):
    """None when every byte is printable ASCII, tab or newline (CR only before LF), else a
    message naming the first other byte's line and column."""
    line, col = 1, 0
    for i, b in enumerate(data):
        col += 1
        if b == 0x0A:
            line, col = line + 1, 0
            continue
        if b == 0x09 or 0x20 <= b <= 0x7E:
            continue
        if b == 0x0D and data[i + 1:i + 2] == b"\n":
            continue
        return "byte 0x%02X at line %d, column %d is not printable ASCII" % (b, line, col)
    return None


# --- cases ----------------------------------------------------------------------------------

def draw_threshold(rng: random.Random, strategy: str):
    if strategy == "nn" and rng.random() < 0.2:
        return None
    hi, digits = (1.0, 2) if strategy == "nndr" else (500.0, 1)
    u = rng.random()
    if u < 0.05:
        return 0.0
    if u < 0.10:
        return hi
    return round(rng.uniform(0.0, hi), digits)


def draw_cases(seed: int, n: int, frames: int, keypoints_of):
    """n cases per task: frame uniform in 1..frames, thresholds as docs/marking.md says."""
    rng = random.Random(seed)
    cases = []
    for task in TASKS:
        for _ in range(n):
            frame = rng.randint(1, frames)
            if task == "matching_info":
                strategy = rng.choice(STRATEGIES)
                t = draw_threshold(rng, strategy)
                feature = rng.randrange(keypoints_of(frame - 1))
                cases.append({"task": task, "frame": frame, "threshold": t, "strategy": strategy,
                              "feature": feature})
            else:
                cases.append({"task": task, "frame": frame, "threshold": draw_threshold(rng, task)})
    return cases


def read_cases(path):
    with open(path) as fh:
        data = json.load(fh)
    if isinstance(data, dict):
        data = data["cases"]
    keep = ("task", "frame", "threshold", "strategy", "feature")
    out = []
    for c in data:
        case = {k: c[k] for k in keep if k in c}
        if case["task"] not in TASKS:
            raise ValueError("unknown task %r" % (case["task"],))
        if case["task"] == "matching_info" and ("strategy" not in case or "feature" not in case):
            raise ValueError("a matching_info case needs strategy and feature: %r" % (c,))
        out.append(case)
    return out


# --- SIFT, cached on disk across runs and worker restarts ----------------------------------

class SiftCache:
    """lab_reference's SIFT per frame, kept in memory and in $TMPDIR/siftlab-mark-sift (one
    .npz per frame, named by the PNG's SHA-1: a changed file is computed again). KeyPoints
    come back through cv2.KeyPoint(x, y, size, angle, response, octave), exact: the values
    are float32 both ways."""

    def __init__(self, lab, cv2, np):
        import tempfile
        self.lab, self.cv2, self.np = lab, cv2, np
        self.dir = os.path.join(tempfile.gettempdir(), "siftlab-mark-sift")
        os.makedirs(self.dir, exist_ok=True)
        self.mem = {}

    def key(self, path):
        """The PNG's SHA-1 (20 hex digits)."""
        if ("key", path) not in self.mem:
            import hashlib
            with open(path, "rb") as fh:
                self.mem[("key", path)] = hashlib.sha1(fh.read()).hexdigest()[:20]
        return self.mem[("key", path)]

    def get(self, path):
        if path in self.mem:
            return self.mem[path]
        np, cv2 = self.np, self.cv2
        file = os.path.join(self.dir, self.key(path) + ".npz")
        if os.path.exists(file):
            z = np.load(file)
            kv, oc, des = z["kv"], z["oc"], z["des"]
            kps = tuple(cv2.KeyPoint(float(x), float(y), float(s), float(a), float(r), int(o))
                        for (x, y, s, a, r), o in zip(kv.tolist(), oc.tolist()))
            res = (kps, des if len(kps) else None)
        else:
            kps, des = self.lab.sift_frame(path)
            kv = np.array([(k.pt[0], k.pt[1], k.size, k.angle, k.response) for k in kps],
                          np.float32).reshape(-1, 5)
            oc = np.array([k.octave for k in kps], np.int32)
            tmp = file + ".%d.tmp.npz" % os.getpid()
            np.savez(tmp, kv=kv, oc=oc, des=des if des is not None else np.zeros((0, 128), np.float32))
            os.replace(tmp, file)
            res = (kps, des)
        self.mem[path] = res
        return res


# --- the worker: the student's file with real cv2 -------------------------------------------

def worker(student_path, dataset):
    """Reads cases (JSON lines) on stdin; for each writes {"started": true} right before the
    student's call and then the outcome. The first line written is the load's outcome."""
    proto = os.fdopen(os.dup(1), "w")
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, 1)  # nothing but the protocol on the protocol's stream

    def send(obj):
        proto.write(json.dumps(obj) + "\n")
        proto.flush()

    import cv2
    import numpy as np

    sys.path.insert(0, HERE)
    import lab_reference as lab

    cv2.setNumThreads(1)
    cache = SiftCache(lab, cv2, np)

    base = types.ModuleType("vision_tasks_base")
    exec(compile(BASE_SOURCE, "vision_tasks_base.py", "exec"), base.__dict__)
    sys.modules["vision_tasks_base"] = base

    stdlib = set(sys.stdlib_module_names)
    real_import = builtins.__import__

    def guarded_import(name, globals=None, locals=None, fromlist=(), level=0):
        top = name.partition(".")[0]
        if level == 0 and top not in stdlib and top not in ("cv2", "numpy", "vision_tasks_base"):
            raise ModuleNotFoundError("No module named '%s'" % top, name=top)
        return real_import(name, globals, locals, fromlist, level)

    sb = dict(builtins.__dict__)
    sb["__import__"] = guarded_import

    def failure(e):
        frames = [f for f in traceback.extract_tb(e.__traceback__) if f.filename == STUDENT_FILE]
        msg = "".join(traceback.format_exception_only(type(e), e)).strip().splitlines()[-1]
        if frames:
            msg += " (%s, line %d)" % (STUDENT_FILE, frames[-1].lineno)
        return msg

    def quiet(fn, *args):
        saved = sys.stdout, sys.stderr, sys.stdin
        sys.stdout = sys.stderr = io.StringIO()
        sys.stdin = io.StringIO("")
        try:
            return fn(*args)
        finally:
            sys.stdout, sys.stderr, sys.stdin = saved

    with open(student_path, "rb") as fh:
        source = fh.read().decode("utf-8", "replace")
    mod = types.ModuleType("vision_tasks")
    mod.__file__ = STUDENT_FILE
    mod.__dict__["__builtins__"] = sb
    sys.modules["vision_tasks"] = mod

    def build():
        exec(compile(source, STUDENT_FILE, "exec"), mod.__dict__)
        return mod.VisionTasks()

    try:
        vt = quiet(build)
    except SyntaxError as e:
        send({"error": "%s: %s (line %s)" % (type(e).__name__, e.msg, e.lineno), "kind": "syntax"})
        return 0
    except BaseException as e:
        send({"error": failure(e), "kind": "import" if isinstance(e, ImportError) else "runtime"})
        return 0
    send({"ok": True})

    def sift(frame):
        return cache.get(lab.frame_path(dataset, frame))

    def rows_of(matches):
        return [[(m.queryIdx, m.trainIdx, float(m.distance)) for m in row] for row in matches]

    def fresh(row):
        return [cv2.DMatch(m.queryIdx, m.trainIdx, m.imgIdx, m.distance) for m in row]

    for line in sys.stdin:
        case = json.loads(line)
        task, frame, t = case["task"], case["frame"], case["threshold"]
        t = None if t is None else float(t)
        kp1, des1 = sift(frame - 1)
        kp2, des2 = sift(frame)
        if task == "matching_info":
            f = case["feature"]
            fn = lab.STRATEGIES[case["strategy"]]
            # a feature id past the frame's keypoints has no matches (the lab's ids run to 1499)
            row = fn(des1[f:f + 1], des2, t)[0] if f < len(kp1) else []
            for m in row:
                m.queryIdx = f
            expected = lab.matching_info(kp1, kp2, row)
            args = (kp1, kp2, fresh(row))
        else:
            # The reference's rows are computed when a value must be compared with them; a
            # digest of them is kept on disk, so a value equal to it needs no reference run.
            digest_file = os.path.join(cache.dir, "expected-%s-%s-%s-%s.sha256" % (
                task, cache.key(lab.frame_path(dataset, frame - 1)),
                cache.key(lab.frame_path(dataset, frame)), "None" if t is None else repr(t)))

            def compute(task=task, des1=des1, des2=des2, t=t, digest_file=digest_file):
                rows = rows_of(lab.STRATEGIES[task](des1, des2, t))
                tmp = "%s.%d.tmp" % (digest_file, os.getpid())
                with open(tmp, "w") as fh:
                    fh.write(rows_digest(rows))
                os.replace(tmp, digest_file)
                return rows

            known = None
            if os.path.exists(digest_file):
                with open(digest_file) as fh:
                    known = fh.read().strip()
            expected = (known, compute)
            args = (des1.copy(), des2.copy(), t)
        send({"started": True})
        t0 = time.process_time()
        try:
            value = quiet(getattr(vt, task), *args)
        except BaseException as e:
            send({"status": "error", "kind": "runtime", "message": failure(e),
                  "seconds": time.process_time() - t0})
            continue
        seconds = time.process_time() - t0
        try:
            status, kind, message = judge(task, value, expected, cv2.DMatch)
        except Exception as e:  # comparing raised (numpy arrays in the value, ...)
            status, kind, message = "wrong", None, "comparing the value raised %s" % type(e).__name__
        out = {"status": status, "seconds": seconds}
        if kind:
            out["kind"] = kind
        if message:
            out["message"] = message
        send(out)
    return 0


def rows_digest(rows):
    import hashlib
    return hashlib.sha256(json.dumps(rows).encode()).hexdigest()


def judge(task, value, expected, DMatch):
    """(status, kind, message) of one returned value. expected: matching_info's tuple, or for
    dt/nn/nndr (digest of the reference's rows or None, a function computing the rows)."""
    if task == "matching_info":
        try:
            a, b, c = value
        except Exception:
            return "error", "type", "matching_info must return three items, got %s" % type(value).__name__
        for part, want, what in ((a, tuple, "the feature's coordinates"), (b, list, "the matches' coordinates"),
                                 (c, list, "the matches' distances")):
            if type(part) is not want:
                return "error", "type", "%s must be a %s, got %s" % (what, want.__name__, type(part).__name__)
        if (a, b, c) == expected:
            return "correct", None, None
        return "wrong", None, "expected %r, got %r" % (expected, value)
    if type(value) is not list:
        return "error", "type", "%s must return a list, got %s" % (task, type(value).__name__)
    got = []
    for qi, row in enumerate(value):
        if type(row) is not list and type(row) is not tuple:
            return "error", "type", "the item for query %d is %s" % (qi, type(row).__name__)
        for j, m in enumerate(row):
            if not isinstance(m, DMatch):
                return "error", "type", "item %d of query %d is %s" % (j, qi, type(m).__name__)
        got.append([(m.queryIdx, m.trainIdx, float(m.distance)) for m in row])
    known, compute = expected
    if known is not None and rows_digest(got) == known:
        return "correct", None, None
    expected = compute()
    if got == expected:
        return "correct", None, None
    if len(got) != len(expected):
        return "wrong", None, "%d query lists, expected %d" % (len(got), len(expected))
    for qi, (g, e) in enumerate(zip(got, expected)):
        if g != e:
            return "wrong", None, ("query %d (of %d differing): expected %d matches %s, got %d %s"
                                   % (qi, sum(x != y for x, y in zip(got, expected)), len(e), e[:3],
                                      len(g), g[:3]))
    return "wrong", None, None


# --- the parent: timeouts, restarts, marks -------------------------------------------------

class Worker:
    def __init__(self, student, dataset):
        self.args = [sys.executable, os.path.abspath(__file__), "--worker", student, "--dataset", dataset]
        self.start()

    def start(self):
        self.p = subprocess.Popen(self.args, stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                  stderr=subprocess.DEVNULL, text=True, bufsize=1)
        self.buf = b""
        self.load = self.read(60.0)
        if self.load is None:
            self.kill()
            self.load = {"error": "loading the file took over 60 s", "kind": "timeout"}

    def read(self, timeout):
        """The next line as JSON, None after `timeout` seconds. Reads the pipe's file
        descriptor itself: a buffered reader could hold a line select() does not see."""
        deadline = time.monotonic() + timeout
        fd = self.p.stdout.fileno()
        while b"\n" not in self.buf:
            left = deadline - time.monotonic()
            if left <= 0 or not select.select([fd], [], [], left)[0]:
                return None
            chunk = os.read(fd, 1 << 16)
            if not chunk:
                return {"status": "error", "kind": "runtime", "message": "the Python process ended"}
            self.buf += chunk
        line, self.buf = self.buf.split(b"\n", 1)
        return json.loads(line)

    def kill(self):
        self.p.kill()
        self.p.wait()

    def close(self):
        try:
            self.p.stdin.close()
        except OSError:
            pass
        self.p.wait()


def mark(student, cases, dataset, call_limit=CALL_LIMIT, task_limit=TASK_LIMIT, log=None, wall_factor=3.0):
    """The report. The limits are on the CPU time the call used (the child measures it), so a
    busy machine does not turn slow calls into timeouts; a call still running after
    wall_factor x call_limit seconds of wall time is killed (and is over the limit)."""
    with open(student, "rb") as fh:
        data = fh.read()
    report = {"file": student, "ascii": True, "tasks": {}, "total": 0.0, "cases": []}
    problem = ascii_problem(data)
    if problem:
        report["ascii"] = False
        report["load"] = {"error": "not printable ASCII: " + problem, "kind": "ascii"}
    else:
        try:
            compile(data.decode("ascii"), STUDENT_FILE, "exec", dont_inherit=True)
        except (SyntaxError, ValueError) as e:
            report["load"] = {"error": "%s: %s" % (type(e).__name__, getattr(e, "msg", e)), "kind": "syntax"}
    w = None
    if "load" not in report:
        w = Worker(student, dataset)
        report["load"] = w.load
    loaded = "ok" in report["load"]
    spent = {t: 0.0 for t in TASKS}
    for case in cases:
        task = case["task"]
        rec = dict(case)
        if not loaded:
            rec.update(status="error", kind="load", message=report["load"]["error"])
        elif spent[task] >= task_limit:
            rec.update(status="error", kind="task-time", message="the task's %g s are used up" % task_limit)
        else:
            w.p.stdin.write(json.dumps(case) + "\n")
            w.p.stdin.flush()
            started = w.read(600.0)
            if started is None or "started" not in started:
                raise RuntimeError("worker did not start the call: %r" % (started,))
            t0 = time.monotonic()
            out = w.read(wall_factor * min(call_limit, task_limit - spent[task]) + 0.5)
            wall = time.monotonic() - t0
            if out is None:
                w.kill()
                spent[task] += call_limit
                rec.update(status="error", kind="timeout", message="over %g s" % call_limit,
                           seconds=None, wall=round(wall, 3))
                w.start()
            else:
                secs = out.pop("seconds", wall)
                spent[task] += secs
                if secs > call_limit:
                    out = {"status": "error", "kind": "timeout", "message": "over %g s" % call_limit}
                rec.update(out)
                rec["seconds"] = round(secs, 3)
                rec["wall"] = round(wall, 3)
        report["cases"].append(rec)
        if log:
            print("%-13s frame %3d t=%-6s %s %s" % (task, case["frame"], case["threshold"], rec["status"],
                                                    rec.get("message", "")[:150]), file=log)
    if w is not None:
        w.close()
    total = 0.0
    for task in TASKS:
        recs = [r for r in report["cases"] if r["task"] == task]
        if not recs:
            continue
        correct = sum(r["status"] == "correct" for r in recs)
        errors = sum(r["status"] == "error" for r in recs)
        m = (0.5 if errors == 0 else 0.0) + 4.5 * correct / len(recs) if loaded else 0.0
        report["tasks"][task] = {"calls": len(recs), "correct": correct, "errors": errors, "mark": m}
        total += m
    report["total"] = total
    return report


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("student", help="the student's vision_tasks.py")
    ap.add_argument("--cases", help="siftlab mark --json's output, or a JSON list of cases")
    ap.add_argument("--seed", type=int, default=0, help="draw cases of our own (without --cases)")
    ap.add_argument("-n", type=int, default=25, help="cases per task when drawing (default 25)")
    ap.add_argument("--dataset", default=os.path.join(ROOT, "www/demo/MyKITTI"))
    ap.add_argument("--out", help="also write the JSON report here")
    ap.add_argument("--compare", action="store_true",
                    help="--cases is siftlab mark --json's report: compare its per-case status and "
                         "marks with ours (exit 1 when they differ)")
    ap.add_argument("--call-limit", type=float, default=CALL_LIMIT)
    ap.add_argument("--task-limit", type=float, default=TASK_LIMIT)
    ap.add_argument("--wall-factor", type=float, default=3.0,
                    help="kill a call after this many times --call-limit of wall time (default 3)")
    ap.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("-q", "--quiet", action="store_true", help="no per-case lines on stderr")
    a = ap.parse_args(argv)
    if a.worker:
        return worker(a.student, a.dataset)

    import cv2
    if not cv2.__version__.startswith("4.8.0"):
        sys.exit("OpenCV 4.8.0 is needed, found %s" % cv2.__version__)
    if cv2.ipp.useIPP():
        sys.exit("OPENCV_IPP=disabled did not disable IPP")
    sys.path.insert(0, HERE)
    import gen_goldens
    if gen_goldens.opencv_lanes(cv2.getCPUFeaturesLine()) != 8:
        sys.exit("OpenCV still dispatches AVX-512: OPENCV_CPU_DISABLE did not work")

    if a.cases:
        cases = read_cases(a.cases)
    else:
        import lab_reference as lab
        import numpy as np
        cache = SiftCache(lab, cv2, np)
        image_dir = os.path.join(a.dataset, "gray", "00", "image_0")
        frames = len([f for f in os.listdir(image_dir) if f.endswith(".png")]) - 1
        cases = draw_cases(a.seed, a.n, frames,
                           lambda f: len(cache.get(lab.frame_path(a.dataset, f))[0]))
    report = mark(a.student, cases, a.dataset, a.call_limit, a.task_limit,
                  log=None if a.quiet else sys.stderr, wall_factor=a.wall_factor)
    if not a.cases:
        report["seed"] = a.seed
    status = 0
    if a.compare:
        report["compare"] = compare(report, a.cases)
        status = 0 if report["compare"]["agree"] else 1
    text = json.dumps(report)
    if a.out:
        with open(a.out, "w") as fh:
            fh.write(text + "\n")
    print(text)
    print("marks: " + ", ".join("%s %.2f" % (t, v["mark"]) for t, v in report["tasks"].items())
          + "; total %.2f / 20" % report["total"], file=sys.stderr)
    if a.compare:
        c = report["compare"]
        for d in c["disagreements"]:
            print("DISAGREE %s" % json.dumps(d), file=sys.stderr)
        print("siftlab's report %s the reference: %d of %d cases differ; marks %s" % (
            "agrees with" if c["agree"] else "DIFFERS from", len(c["disagreements"]), c["cases"],
            "equal" if c["marks_equal"] else "differ: %s" % c["marks"]), file=sys.stderr)
    return status


def compare(report, siftlab_report_path):
    """siftlab mark --json's per-case status and marks against this report's."""
    with open(siftlab_report_path) as fh:
        theirs = json.load(fh)
    if not isinstance(theirs, dict) or "cases" not in theirs:
        sys.exit("--compare needs siftlab mark --json's report as --cases")
    dis = []
    for i, (mine, other) in enumerate(zip(report["cases"], theirs["cases"])):
        got = str(other.get("status", "")).lower()
        if got != mine["status"]:
            dis.append({"case": i, "task": mine["task"], "frame": mine["frame"],
                        "threshold": mine["threshold"], "siftlab": got, "reference": mine["status"],
                        "reference_message": mine.get("message"), "siftlab_diagnosis": other.get("diagnosis")})
    tasks = theirs.get("tasks", [])
    if isinstance(tasks, dict):
        tasks = [dict(v, task=k) for k, v in tasks.items()]
    marks = {}
    for t in tasks:
        m = t.get("marks", t.get("mark"))
        ref = report["tasks"].get(t.get("task"), {}).get("mark")
        marks[t.get("task")] = {"siftlab": m, "reference": ref}
    marks_equal = all(v["reference"] is not None and v["siftlab"] is not None
                      and abs(v["siftlab"] - v["reference"]) < 1e-9 for v in marks.values())
    n = len(report["cases"])
    return {"agree": not dis and marks_equal and n == len(theirs["cases"]), "cases": n,
            "disagreements": dis, "marks": marks, "marks_equal": marks_equal}


if __name__ == "__main__":
    sys.exit(main())
