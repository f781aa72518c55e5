#!/usr/bin/env python3
"""siftlab's visual odometry against the lab's OpenCV 4.8 pipeline, in the same run.

    python3 tests/references/compare_vo.py [--dataset DIR] [--frames N] [--repeat K] [--baseline BIN] [--json]
                                           [--opencv-lanes {8,16}] [--no-ipp] [-a ALGO [-t T]]

Runs tests/references/vo_reference.py's loop (in this process) and
`target/release/siftlab -d DIR view_trajectory N --save-poses ... --trace ...` (a subprocess;
build it first with `cargo build --release --bin siftlab`), alternating K times, and reports for both:
the absolute trajectory error (RMSE of the position differences to the ground truth, no
alignment, GT scale as the lab uses it), the frame-by-frame distance between the two estimates
(max / median / at the last frame), and frames per second (best of K, whole loop with image
reading; ours includes process start-up) with the ratio ours / OpenCV, plus the ratio of each
back-to-back round and their median (the figure to quote on a machine whose speed drifts).
With --baseline (an older siftlab build) that binary runs in every round too (the two
builds alternating which runs first after OpenCV), and the per-round speed-up of --binary
over it is reported (and whether both estimates are equal).

It also compares the two per-frame traces (siftlab's --trace against vo_reference.py's: points
in, tracked, essential and pose inliers, re-detection) and names every frame where they differ.
--opencv-lanes 8 runs both at 8 lanes (OpenCV's AVX-512 dispatch disabled, `siftlab
--opencv-lanes 8`); --no-ipp runs OpenCV with OPENCV_IPP=disabled, the build siftlab reproduces
bit for bit (both are read by vo_reference.py before cv2 is imported). -a ALGO [-t T] compares the
matcher-driven loop (vo_matched_reference.py) with `view_trajectory -a ALGO -t T` instead; its
reference is the IPP-off build, so give --no-ipp.

    python3 tests/references/compare_vo.py --no-ipp --opencv-lanes 8 --frames 151      # the README's row
    python3 tests/references/compare_vo.py --no-ipp --opencv-lanes 8 --frames 151 -a dt -t 200

The dataset defaults to www/demo/MyKITTI (the bundled real KITTI 00 frames, 0-150).
Requires opencv-contrib-python-headless==4.8.0.76 and numpy<2.
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import vo_reference as ref  # noqa: E402  (configures OpenCV from argv, then imports cv2)

REPO = ref.REPO


def read_positions(path):
    out = []
    with open(path) as f:
        for line in f:
            v = [float(x) for x in line.split()]
            if len(v) != 12:
                raise SystemExit("%s: expected 12 numbers a line, got %d" % (path, len(v)))
            out.append((v[3], v[7], v[11]))
    return out


def dist(a, b):
    return sum((x - y) ** 2 for x, y in zip(a, b)) ** 0.5


def read_trace(path):
    with open(path) as f:
        return [json.loads(line) for line in f if line.strip()]


def run_ours(binary, dataset, frames, tmp, counts=False, lanes=None, algo=(), trace=None):
    """`view_trajectory FRAME_ID` runs frames 0..=FRAME_ID (the lab's count); a build from
    before that change (counts=True, --baseline-counts) took the number of frames."""
    poses = os.path.join(tmp, "ours_poses.txt")
    png = os.path.join(tmp, "trajectory.png")
    arg = frames if counts else frames - 1
    cmd = [binary, "-d", dataset] + (["--opencv-lanes", lanes] if lanes else []) + ["view_trajectory"] + \
        list(algo) + [str(arg), "--save-poses", poses, "--output", png] + (["--trace", trace] if trace else [])
    start = time.perf_counter()
    proc = subprocess.run(cmd, capture_output=True, text=True)
    elapsed = time.perf_counter() - start
    if proc.returncode != 0:
        raise SystemExit("siftlab failed (%d): %s" % (proc.returncode, proc.stderr.strip()[-2000:]))
    return read_positions(poses), elapsed, (proc.stdout + proc.stderr).strip()


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--dataset", default=None)
    ap.add_argument("--frames", type=int, default=None, help="frames from 0 (default: all)")
    ap.add_argument("--repeat", type=int, default=1, help="alternate both pipelines K times, keep the best time")
    ap.add_argument("--binary", default=os.path.join(REPO, "target", "release", "siftlab"))
    ap.add_argument("--baseline", default=None,
                    help="another siftlab binary (an older build) run in the same rounds, for the speed-up of a change")
    ap.add_argument("--baseline-counts", action="store_true",
                    help="the baseline takes view_trajectory N as a frame count (builds before the lab's count)")
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--opencv-lanes", choices=("8", "16"), default=None,
                    help="run OpenCV's SIFT and siftlab at this SIMD width (default: OpenCV's choice on this CPU)")
    ap.add_argument("--no-ipp", action="store_true", help="OpenCV with OPENCV_IPP=disabled")
    ap.add_argument("-a", "--algorithm", choices=("dt", "nn", "nndr"), default=None,
                    help="compare the matcher-driven loop instead of Lucas-Kanade")
    ap.add_argument("-t", "--threshold", type=float, default=None)
    args = ap.parse_args()
    ref.check_opencv()
    if args.threshold is not None and not args.algorithm:
        raise SystemExit("-t needs -a")
    algo_args = []
    if args.algorithm:
        import vo_matched_reference as matched  # noqa: E402  (cv2 is configured already)
        algo_args = ["-a", args.algorithm] + ([] if args.threshold is None else ["-t", repr(args.threshold)])

        def opencv_run(dataset, frames):
            positions, _rot, trace = matched.run(dataset, frames, args.algorithm, args.threshold)
            return positions, trace
    else:
        def opencv_run(dataset, frames):
            positions, _rot, _poses, trace = ref.run(dataset, frames)
            return positions, trace

    dataset = os.path.abspath(args.dataset or ref.default_dataset())
    available = min(ref.count_frames(dataset), len(ref.read_poses(dataset)))
    frames = args.frames if args.frames is not None else available
    if frames < 2 or frames > available:
        raise SystemExit("need 2..%d frames, got %d (dataset %s)" % (available, frames, dataset))
    if not os.path.isfile(args.binary):
        raise SystemExit("%s not found: run `cargo build --release --bin siftlab` first" % args.binary)
    if args.baseline and not os.path.isfile(args.baseline):
        raise SystemExit("--baseline %s not found" % args.baseline)

    gt = [ref.gt_position(p) for p in ref.read_poses(dataset)[:frames]]
    t_cv, t_ours, t_base = [], [], []
    with tempfile.TemporaryDirectory() as tmp:
        for round_no in range(max(1, args.repeat)):
            start = time.perf_counter()
            cv_pos, cv_trace = opencv_run(dataset, frames)
            t_cv.append(time.perf_counter() - start)
            # The two builds take turns at running right after OpenCV, so
            # neither always gets the same place in the round.
            builds = ["ours", "base"] if args.baseline else ["ours"]
            if round_no % 2 == 1:
                builds.reverse()
            for build in builds:
                if build == "base":
                    base_pos, elapsed, _ = run_ours(args.baseline, dataset, frames, tmp, args.baseline_counts,
                                                    args.opencv_lanes, algo_args)
                    t_base.append(elapsed)
                else:
                    trace_path = os.path.join(tmp, "ours_trace.jsonl")
                    our_pos, elapsed, our_text = run_ours(args.binary, dataset, frames, tmp, False,
                                                          args.opencv_lanes, algo_args, trace_path)
                    our_trace = read_trace(trace_path)
                    t_ours.append(elapsed)

    diffs = [dist(a, b) for a, b in zip(our_pos, cv_pos)]
    trace_diff = [(c["frame"], o, c) for o, c in zip(our_trace, cv_trace) if o != c]
    if len(our_trace) != len(cv_trace):
        raise SystemExit("traces have %d and %d frames" % (len(our_trace), len(cv_trace)))
    res = {
        "dataset": dataset,
        "frames": frames,
        "tracker": "LK" if not args.algorithm else " ".join(algo_args[1:]),
        "opencv_simd_lanes": ref.opencv_lanes(),
        "opencv_ipp": bool(ref.cv2.ipp.useIPP()),
        "diff_max_frame": max(range(len(diffs)), key=diffs.__getitem__),
        "trace_frames_equal": len(our_trace) - len(trace_diff),
        "trace_differences": [{"frame": f, "siftlab": o, "opencv": c} for f, o, c in trace_diff],
        "ate_rmse_ours": ref.ate_rmse(our_pos, gt),
        "ate_rmse_opencv": ref.ate_rmse(cv_pos, gt),
        "diff_max": max(diffs),
        "diff_median": statistics.median(diffs),
        "diff_last": diffs[-1],
        "final_ours": our_pos[-1],
        "final_opencv": cv_pos[-1],
        "final_gt": gt[-1],
        "fps_ours": frames / min(t_ours),
        "fps_opencv": frames / min(t_cv),
        "seconds_ours": t_ours,
        "seconds_opencv": t_cv,
        "cpus": os.cpu_count(),
    }
    res["fps_ratio"] = res["fps_ours"] / res["fps_opencv"]
    # This VM's speed drifts by up to 1.6x within minutes: the ratio of each
    # back-to-back round is the figure to trust, not ratios of bests.
    res["round_ratios"] = [c / o for c, o in zip(t_cv, t_ours)]
    res["median_round_ratio"] = statistics.median(res["round_ratios"])
    if t_base:
        res["baseline_round_ratios"] = [c / b for c, b in zip(t_cv, t_base)]
        res["median_baseline_round_ratio"] = statistics.median(res["baseline_round_ratios"])
        res["speedup_rounds"] = [b / o for b, o in zip(t_base, t_ours)]
        res["median_speedup"] = statistics.median(res["speedup_rounds"])
        res["baseline_positions_equal"] = base_pos == our_pos
    if args.json:
        print(json.dumps(res))
        return
    print("dataset %s, frames 0..%d, %s; OpenCV %d lanes, IPP %s" % (
        dataset, frames - 1, res["tracker"], res["opencv_simd_lanes"], "on" if res["opencv_ipp"] else "off"))
    print("ATE RMSE (no alignment, GT scale): siftlab %.6f m, OpenCV %.6f m" % (res["ate_rmse_ours"], res["ate_rmse_opencv"]))
    print("siftlab vs OpenCV, per-frame position difference: max %.3e m (frame %d), median %.3e m, last frame %.3e m"
          % (res["diff_max"], res["diff_max_frame"], res["diff_median"], res["diff_last"]))
    print("trace (points in, tracked, essential and pose inliers, re-detection): %d / %d frames equal"
          % (res["trace_frames_equal"], frames))
    for d in res["trace_differences"][:20]:
        print("  frame %d: siftlab %s, OpenCV %s" % (d["frame"], d["siftlab"], d["opencv"]))
    print("final position: siftlab (%.4f, %.4f, %.4f), OpenCV (%.4f, %.4f, %.4f), truth (%.4f, %.4f, %.4f)"
          % (*res["final_ours"], *res["final_opencv"], *res["final_gt"]))
    print("speed (best of %d): siftlab %.2f frames/s, OpenCV %.2f frames/s, ratio %.2fx"
          % (len(t_ours), res["fps_ours"], res["fps_opencv"], res["fps_ratio"]))
    print("per-round ratios (OpenCV time / siftlab time, back to back): %s; median %.2fx"
          % (", ".join("%.2f" % r for r in res["round_ratios"]), res["median_round_ratio"]))
    if t_base:
        print("baseline %s, same rounds: OpenCV time / baseline time %s; median %.2fx"
              % (args.baseline, ", ".join("%.2f" % r for r in res["baseline_round_ratios"]), res["median_baseline_round_ratio"]))
        print("speed-up of %s over the baseline (per round): %s; median %.2fx; estimates %s"
              % (args.binary, ", ".join("%.2f" % r for r in res["speedup_rounds"]), res["median_speedup"],
                 "identical" if res["baseline_positions_equal"] else "DIFFER"))


if __name__ == "__main__":
    main()
