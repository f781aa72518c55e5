#!/usr/bin/env python3
"""Time `siftlab mark` on the correct solution, two builds interleaved (docs/marking.md).

    python3 tests/benchmarks/bench_mark.py --before OLD_SIFTLAB [--after target/release/siftlab]
        [--rounds 3] [-n 25] [--seed 0] [--extra-after=--no-sandbox] [--class K [--jobs 2]]

Each round runs both builds, alternating which goes first, on the bundled frames at
`--opencv-lanes 8`; a shared machine's speed drifts, so only the ratio of the two medians,
measured in the same run, means anything. Both must give the same total (20.00).
Prints one line per run and the medians and their ratio (after / before).

With `--class K`, each run marks a class of K copies of the correct solution
(`mark CLASS --out OUT --jobs J`, a fresh OUT each run) and every row of grades.csv must be
20.00; the medians are also given as submissions an hour.
"""
import argparse
import csv
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))


def run(binary, n, seed, extra):
    cmd = [binary, "--opencv-lanes", "8", "-d", os.path.join(ROOT, "www/demo/MyKITTI"), "mark",
           os.path.join(ROOT, "tests/fixtures/mark/good/vision_tasks.py"), "-n", str(n), "--seed", str(seed),
           "--json"] + extra
    t0 = time.monotonic()
    p = subprocess.run(cmd, capture_output=True, text=True)
    took = time.monotonic() - t0
    try:
        total = json.loads(p.stdout)["total"]
    except (ValueError, KeyError):
        sys.exit("%s failed (exit %d): %s" % (binary, p.returncode, p.stderr[-2000:]))
    return took, total


def run_class(binary, n, seed, extra, class_dir, jobs):
    out = tempfile.mkdtemp(prefix="siftlab-bench-out-")
    os.rmdir(out)  # mark makes it
    cmd = [binary, "--opencv-lanes", "8", "-d", os.path.join(ROOT, "www/demo/MyKITTI"), "mark", class_dir,
           "--out", out, "--jobs", str(jobs), "-n", str(n), "--seed", str(seed)] + extra
    t0 = time.monotonic()
    p = subprocess.run(cmd, capture_output=True, text=True)
    took = time.monotonic() - t0
    try:
        with open(os.path.join(out, "grades.csv"), newline="") as f:
            totals = [float(r["total"]) for r in csv.DictReader(f)]
    except (OSError, KeyError, ValueError):
        sys.exit("%s failed (exit %d): %s" % (binary, p.returncode, p.stderr[-2000:]))
    finally:
        shutil.rmtree(out, ignore_errors=True)
    return took, min(totals) if totals else -1.0


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--before", required=True)
    ap.add_argument("--after", default=os.path.join(ROOT, "target/release/siftlab"))
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("-n", type=int, default=25)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--extra-after", action="append", default=[], help="an argument for the after build only")
    ap.add_argument("--class", dest="klass", type=int, default=0, metavar="K",
                    help="mark a class of K copies of the correct solution instead of one file")
    ap.add_argument("--jobs", type=int, default=2)
    a = ap.parse_args()
    class_dir = None
    if a.klass:
        class_dir = tempfile.mkdtemp(prefix="siftlab-bench-class-")
        src = os.path.join(ROOT, "tests/fixtures/mark/good/vision_tasks.py")
        for i in range(a.klass):
            shutil.copy(src, os.path.join(class_dir, "s%02d.py" % (i + 1)))
    times = {"before": [], "after": []}
    for r in range(a.rounds):
        order = [("before", a.before, []), ("after", a.after, a.extra_after)]
        if r % 2:
            order.reverse()
        for name, binary, extra in order:
            if class_dir:
                took, total = run_class(binary, a.n, a.seed, extra, class_dir, a.jobs)
            else:
                took, total = run(binary, a.n, a.seed, extra)
            times[name].append(took)
            print("round %d %-6s %7.1f s  total %.2f" % (r + 1, name, took, total), flush=True)
            if total != 20.0:
                sys.exit("%s: the correct solution scored %.2f" % (name, total))
    b, c = statistics.median(times["before"]), statistics.median(times["after"])
    print("median before %.1f s, after %.1f s, after / before %.3f (%d interleaved rounds, n = %d)"
          % (b, c, c / b, a.rounds, a.n))
    if class_dir:
        print("a class of %d, --jobs %d: before %.0f, after %.0f submissions an hour"
              % (a.klass, a.jobs, 3600 * a.klass / b, 3600 * a.klass / c))
        shutil.rmtree(class_dir, ignore_errors=True)


if __name__ == "__main__":
    main()
