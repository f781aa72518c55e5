#!/usr/bin/env python3
"""The starving attack beside a correct student (docs/marking.md, "The sandbox", accounting).

A class of two, marked with `--jobs 2` so both run at once:

    ROOT/subs/attacker/vision_tasks.py   tests/fixtures/mark/hostile/cpu_farm (48 chains of
                                         reaped children burning CPU in every dt call)
    ROOT/subs/good/vision_tasks.py       tests/fixtures/mark/good (20.00 alone)

`SIFTLAB -d DATASET mark ROOT/subs --out ROOT/out-R --jobs 2 -n N --seed S` is run R times;
each run's grades.csv must give `good` a total of 20.00 and `attacker` at most 15 (dt times
out: the chains' CPU is the sandbox's). Prints one line per run, then a summary; exit status
1 when any run fails.

    python3 tests/security/starve_check.py [--runs 5] [-n 5] [--seed 0] [--siftlab PATH]
        [--dataset DIR] [--jobs 2]

SIFTLAB in the environment is the default --siftlab. Standard library only.
"""

import argparse
import csv
import os
import shutil
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(os.path.dirname(HERE))
FIXTURES = os.path.join(REPO, "tests", "fixtures", "mark")
ATTACK = os.path.join(FIXTURES, "hostile", "cpu_farm", "vision_tasks.py")
GOOD = os.path.join(FIXTURES, "good", "vision_tasks.py")


def run_once(siftlab, dataset, root, run, n, seed, jobs):
    out = os.path.join(root, "out-%d" % run)
    cmd = [siftlab, "-d", dataset, "mark", os.path.join(root, "subs"), "--out", out, "--jobs", str(jobs),
           "-n", str(n), "--seed", str(seed)]
    t0 = time.time()
    p = subprocess.run(cmd, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                       timeout=3600)
    seconds = time.time() - t0
    rows = {}
    path = os.path.join(out, "grades.csv")
    if os.path.isfile(path):
        with open(path, newline="") as f:
            for row in csv.DictReader(f):
                rows[row.get("student")] = row
    notes = [line for line in p.stderr.decode("utf-8", "replace").splitlines() if "machine" in line]
    return rows, p.returncode, seconds, notes


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--siftlab", default=os.environ.get("SIFTLAB") or os.path.join(REPO, "target", "release", "siftlab"))
    ap.add_argument("--dataset", default=os.path.join(REPO, "www", "demo", "MyKITTI"))
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("-n", type=int, default=5)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--jobs", type=int, default=2)
    a = ap.parse_args(argv)
    root = tempfile.mkdtemp(prefix="siftlab-starve-")
    failed = 0
    try:
        for name, src in (("attacker", ATTACK), ("good", GOOD)):
            os.makedirs(os.path.join(root, "subs", name))
            shutil.copyfile(src, os.path.join(root, "subs", name, "vision_tasks.py"))
        for run in range(1, a.runs + 1):
            rows, code, seconds, notes = run_once(a.siftlab, a.dataset, root, run, a.n, a.seed, a.jobs)
            good = rows.get("good", {}).get("total")
            attacker = rows.get("attacker", {}).get("total")
            ok = good is not None and abs(float(good) - 20.0) < 1e-9 and attacker is not None \
                and float(attacker) <= 15.0 + 1e-9
            failed += not ok
            print("%s run %d: good %s, attacker %s, exit %s, %.0f s%s" % (
                "PASS" if ok else "FAIL", run, good, attacker, code, seconds,
                "".join("\n     " + x[:200] for x in notes)), flush=True)
    finally:
        shutil.rmtree(root, ignore_errors=True)
    print("%d run(s) of -n %d, --jobs %d: %d passed, %d failed" % (a.runs, a.n, a.jobs, a.runs - failed, failed))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
