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
import json
import os
import sys

os.environ["OPENCV_IPP"] = "disabled"
# 8 lanes on any CPU; the hyphenated name is OpenCV's (g_hwFeatureNames in core/src/system.cpp).
os.environ["OPENCV_CPU_DISABLE"] = ",".join(
    v for v in (os.environ.get("OPENCV_CPU_DISABLE"), "AVX512-SKX") if v)

# After the environment: cv2 must not be imported before OPENCV_* are set.
from mark_cases import draw_cases, read_cases  # noqa: E402
from mark_parent import CALL_LIMIT, TASK_LIMIT, mark  # noqa: E402
from mark_sift import SiftCache  # noqa: E402
from mark_worker import worker  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))


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
