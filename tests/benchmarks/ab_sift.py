#!/usr/bin/env python3
"""Two siftlab builds' SIFT, interleaved round after round on one core: the speed ratio.

    python3 tests/benchmarks/ab_sift.py OLD_BINARY NEW_BINARY [--rounds 6] [--repeat 5] [--dataset DIR]

The companion of ab_vo.py for the SIFT kernels. Each round runs `siftlab sift FRAME --repeat R`
(the best of R runs, decode excluded) with both builds back to back, pinned to core 0, the
order alternating every round, on four bundled frames; the report is the median of the
per-frame ratios OLD / NEW (> 1: NEW is faster), and whether `sift --json` is identical.
`SIFTLAB_SIMD=avx2` (or `scalar`) in the environment times the kernels a weaker CPU runs.
Build both binaries with `cargo build --release`.
"""
from __future__ import annotations

import argparse
import re
import statistics
import subprocess
from pathlib import Path

FRAMES = ("000000", "000050", "000120", "000149")


def best_ms(binary: str, frame: Path, repeat: int) -> float:
    out = subprocess.run(["taskset", "-c", "0", binary, "sift", str(frame), "--repeat", str(repeat)],
                         capture_output=True, text=True, check=True).stdout
    m = re.search(r"in ([\d.]+) ms", out)
    if not m:
        raise SystemExit(f"{binary}: no timing in {out!r}")
    return float(m.group(1))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("old")
    ap.add_argument("new")
    ap.add_argument("--rounds", type=int, default=6)
    ap.add_argument("--repeat", type=int, default=5)
    here = Path(__file__).resolve().parents[2]
    ap.add_argument("--dataset", default=str(here / "www" / "demo" / "MyKITTI"))
    a = ap.parse_args()
    frames = [Path(a.dataset) / "gray" / "00" / "image_0" / f"{f}.png" for f in FRAMES]
    outputs = [subprocess.run([b, "sift", str(frames[0]), "--json"], capture_output=True, check=True).stdout
               for b in (a.old, a.new)]
    same = outputs[0] == outputs[1]
    ratios = []
    for r in range(a.rounds):
        row = []
        for f in frames:
            pair = [(0, a.old), (1, a.new)] if r % 2 == 0 else [(1, a.new), (0, a.old)]
            t = {i: best_ms(b, f, a.repeat) for i, b in pair}
            row.append(t[0] / t[1])
        ratios += row
        print(f"round {r}: " + " ".join(f"{x:.3f}" for x in row), flush=True)
    print(f"SIFT old/new: median {statistics.median(ratios):.3f} over {len(ratios)} (> 1: new faster); "
          f"sift --json {'identical' if same else 'DIFFERS'} on {FRAMES[0]}")


if __name__ == "__main__":
    main()
