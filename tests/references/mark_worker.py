"""The reference marker's child: the student's file run with real cv2, each value judged."""

import builtins
import io
import json
import os
import sys
import time
import traceback
import types

from mark_sift import SiftCache

HERE = os.path.dirname(os.path.abspath(__file__))
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
