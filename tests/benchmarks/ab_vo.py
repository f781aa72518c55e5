#!/usr/bin/env python3
"""Two siftlab builds' `view_trajectory`, interleaved round after round: wall and CPU time.

    python3 tests/benchmarks/ab_vo.py OLD_BINARY NEW_BINARY [--rounds 8] [--dataset DIR] [--frames 99]

On this shared VM the speed drifts by up to 1.6x within minutes, so a change is judged by
the per-round ratios of two builds run back to back (the order alternating every round),
not by times taken apart. CPU time (user + system of the process, from wait4) is the
steadier figure: the odometry keeps both cores busy, so CPU seconds are what a change
saves. Prints each build's times, the per-round ratios OLD / NEW (> 1: NEW is faster) and
their medians, and whether the two builds wrote identical poses.
No dependencies beyond Python 3; build both binaries with `cargo build --release`.
"""
from __future__ import annotations

import argparse
import filecmp
import os
import statistics
import subprocess
import tempfile
import time
from pathlib import Path


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("old")
    ap.add_argument("new")
    ap.add_argument("--rounds", type=int, default=8)
    here = Path(__file__).resolve().parents[2]
    ap.add_argument("--dataset", default=str(here / "www" / "demo" / "MyKITTI"))
    ap.add_argument("--frames", type=int, default=99, help="view_trajectory's FRAME_ID")
    a = ap.parse_args()
    bins = [a.old, a.new]
    out = Path(tempfile.mkdtemp(prefix="ab_vo_"))
    times: dict[str, list[tuple[float, float]]] = {b: [] for b in bins}
    for r in range(a.rounds):
        for i, b in (list(enumerate(bins)) if r % 2 == 0 else list(enumerate(bins))[::-1]):
            cmd = [b, "-d", a.dataset, "view_trajectory", str(a.frames),
                   "--output", str(out / f"t{i}.png"), "--save-poses", str(out / f"poses{i}.txt")]
            t0 = time.time()
            p = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
            _, status, ru = os.wait4(p.pid, 0)
            if status != 0:
                raise SystemExit(f"{' '.join(cmd)} failed (status {status})")
            times[b].append((time.time() - t0, ru.ru_utime + ru.ru_stime))
    for b in bins:
        print(b, "wall", " ".join(f"{w:.2f}" for w, _ in times[b]), "| cpu", " ".join(f"{c:.2f}" for _, c in times[b]))
    for k, name in ((0, "wall"), (1, "cpu")):
        ratios = [o[k] / n[k] for o, n in zip(times[a.old], times[a.new])]
        print(f"{name} ratio old/new: median {statistics.median(ratios):.3f} (rounds {' '.join(f'{x:.3f}' for x in ratios)})")
    same = filecmp.cmp(out / "poses0.txt", out / "poses1.txt", shallow=False)
    print("poses identical" if same else "POSES DIFFER")


if __name__ == "__main__":
    main()
