#!/usr/bin/env python3
"""SIFT speed against OpenCV 4.8.0.76 with the two measured side by side, round after round.

On a shared 2-core VM the machine's speed drifts by up to 1.6x within minutes (measured: OpenCV
single-thread SIFT took 133 ms in one minute and 216 ms a few minutes later), so a ratio of two
times taken minutes apart (bench_compare.sh: OpenCV first, then the criterion benches) can be
off either way. Here every round times, back to back on the same frame:
  - OpenCV: cv2.SIFT_create(nfeatures=1500).detectAndCompute under cv2.setNumThreads(1)
    (and, for reference, with OpenCV's default threads);
  - siftlab: `siftlab sift FRAME --repeat R` on all cores and pinned to one core (taskset -c 0);
each side's best of R runs, decode excluded. The round's ratios are ours / OpenCV single-thread;
the report gives each round and the median. Target (issue [1]): SIFT <= 0.5x OpenCV's
single-thread time natively.

Usage: python3 tests/benchmarks/bench_interleaved.py [--dataset DIR] [--rounds 6] [--repeat 5]
       [--frame 0] [--binary target/release/siftlab] [--json FILE]
Needs opencv-contrib-python-headless==4.8.0.76, numpy<2 and a release build of siftlab.
"""
from __future__ import annotations

import argparse
import json
import os
import re
import shutil
import statistics
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, HERE)

from bench_opencv import cpu_model, default_dataset  # noqa: E402


def best_ms(fn, repeat):
    best = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        best = min(best, (time.perf_counter() - t0) * 1000.0)
    return best


def ours_ms(cmd):
    """Best time `siftlab sift --repeat` reports: 'N keypoints in T ms (best of R; ...)'."""
    out = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
    m = re.search(r"keypoints in ([\d.]+) ms", out)
    if not m:
        raise SystemExit("unexpected siftlab output: %r" % out)
    return float(m.group(1))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--dataset", default=None)
    ap.add_argument("--rounds", type=int, default=6)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--frame", type=int, default=0)
    ap.add_argument("--binary", default=os.path.join(ROOT, "target", "release", "siftlab"))
    ap.add_argument("--json", default=None, help="also write the figures to this file")
    a = ap.parse_args(argv)

    import cv2

    ds = a.dataset or default_dataset()
    path = os.path.join(ds, "gray", "00", "image_0", "%06d.png" % a.frame)
    img = cv2.imread(path, 0)
    if img is None:
        print("cannot read %s" % path, file=sys.stderr)
        return 1
    if not os.access(a.binary, os.X_OK):
        print("no siftlab binary at %s: run `cargo build --release --bin siftlab`" % a.binary, file=sys.stderr)
        return 1
    sift = cv2.SIFT_create(nfeatures=1500)
    default_threads = cv2.getNumThreads()
    sift.detectAndCompute(img, None)  # warm-up
    ours_all = [a.binary, "sift", path, "--repeat", str(a.repeat)]
    taskset = shutil.which("taskset")
    ours_one = [taskset, "-c", "0"] + ours_all if taskset else None

    rows = []
    for r in range(a.rounds):
        cv2.setNumThreads(1)
        cv1 = best_ms(lambda: sift.detectAndCompute(img, None), a.repeat)
        cv2.setNumThreads(default_threads)
        cvn = best_ms(lambda: sift.detectAndCompute(img, None), a.repeat)
        all_ms = ours_ms(ours_all)
        one_ms = ours_ms(ours_one) if ours_one else float("nan")
        rows.append({"cv_1t": cv1, "cv_default": cvn, "ours_all": all_ms, "ours_1core": one_ms})
        print("round %d: OpenCV 1 thread %.1f ms, %d threads %.1f ms | siftlab all cores %.1f ms (%.3f), "
              "one core %.1f ms (%.3f)" % (r + 1, cv1, default_threads, cvn, all_ms, all_ms / cv1, one_ms, one_ms / cv1),
              file=sys.stderr)

    med = lambda k: statistics.median(row[k] / row["cv_1t"] for row in rows)  # noqa: E731
    res = {
        "frame": path,
        "rounds": a.rounds,
        "repeat": a.repeat,
        "cpu": cpu_model(),
        "cores": os.cpu_count(),
        "opencv": cv2.__version__,
        "opencv_default_threads": default_threads,
        "median_ratio_all_cores": med("ours_all"),
        "median_ratio_one_core": med("ours_1core"),
        "median_ratio_opencv_default_threads": med("cv_default"),
        "rounds_detail": rows,
    }
    print("SIFT detect+compute, %s (%d rounds, best of %d each side):" % (os.path.basename(path), a.rounds, a.repeat))
    print("  siftlab all cores / OpenCV 1 thread: median %.3f (target <= 0.5)" % res["median_ratio_all_cores"])
    print("  siftlab one core  / OpenCV 1 thread: median %.3f" % res["median_ratio_one_core"])
    print("  OpenCV %d threads / OpenCV 1 thread: median %.3f" % (default_threads, res["median_ratio_opencv_default_threads"]))
    if a.json:
        with open(a.json, "w") as f:
            json.dump(res, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
