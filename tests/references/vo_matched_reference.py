#!/usr/bin/env python3
"""The lab's odometry loop with Lucas-Kanade replaced by the student's matcher, on OpenCV 4.8:
the reference for `siftlab view_trajectory -a {dt,nn,nndr} [-t T]` (docs/fidelity.md §VO-8).

    python3 vo_matched_reference.py -a dt -t 200 [--frames N] [--out poses.txt] [--trace FILE]
                                    [--opencv-lanes {8,16}]
    python3 vo_matched_reference.py --fixtures      # the three committed references, frames 0-150

Per frame i >= 1: SIFT (nfeatures=1500) keypoints and descriptors of frames i-1 (query) and i
(train), detected once per frame; the lab's strategy (lab_reference.dt / nn / nndr, BFMatcher L2
k-NN) per query; in query order, the first (nearest) match of each query that has one;
findEssentialMat(px_cur, px_ref, focal, pp, RANSAC, 0.999, 1.0) and recoverPose as the lab calls
them; frame 1 sets R, t; later frames add scale * R.ti and set R = Ri.R when the ground-truth scale
is > 0.1. With fewer than 5 matches the pose is kept.

dt's first match of a row is its nearest neighbour if that is below t, so dt runs as knnMatch(k=1)
plus the test (the lab's k = len(des2) call builds 2.25 million DMatch objects a frame); --check
confirms on frames 0-1 that this equals the lab's dt row by row.

Runs with OPENCV_IPP=disabled (set here before cv2 is imported), which makes OpenCV's SIFT equal
siftlab's bit for bit (docs/fidelity.md §SIFT-14); --opencv-lanes 8 disables OpenCV's AVX-512
dispatch (vo_reference.configure_opencv), so its SIFT runs 8 lanes wide on any CPU, as
`siftlab --opencv-lanes 8` does. Writes KITTI pose lines (accumulated R, the position the lab
draws), one per frame from 0. --trace writes one JSON object per frame with the fields of
siftlab's vo::StepResult, as `siftlab view_trajectory -a ... --trace` does: frame, points_in (the
previous frame's keypoints, the queries), tracked (the matches), essential_inliers (nonzero
entries of findEssentialMat's mask), pose_inliers (recoverPose's count), redetected (always true:
SIFT runs on every frame); the three counts after tracked are 0 for frame 0 and when fewer than 5
matches keep the pose.

--fixtures (IPP off, 8 lanes, SIFT first checked against tests/fixtures/golden-avx2 bit for bit)
writes tests/fixtures/vo_matched/NAME.txt and NAME.trace.jsonl for dt 200, nn and nndr 0.8 on
frames 0-150, and meta.json. Requires opencv-contrib-python-headless==4.8.0.76.
"""
from __future__ import annotations

import argparse
import math
import os
import sys
import time

os.environ.setdefault("OPENCV_IPP", "disabled")
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import vo_reference as vo  # noqa: E402  (configures OpenCV from argv, then imports cv2)
import cv2  # noqa: E402
import numpy as np  # noqa: E402

import lab_reference as lab  # noqa: E402

# The committed references: (algorithm, threshold, file name).
FIXTURES = (("dt", 200.0, "dt_200"), ("nn", None, "nn"), ("nndr", 0.8, "nndr_0.8"))
FIXTURE_DIR = os.path.join(vo.REPO, "tests", "fixtures", "vo_matched")


def first_matches(algo, des1, des2, t):
    """Per query, in query order: its first (nearest) match, if it has one."""
    if algo == "dt":
        rows = cv2.BFMatcher().knnMatch(des1, des2, k=1)
        return [row[0] for row in rows if row and row[0].distance < t]
    rows = lab.STRATEGIES[algo](des1, des2, t)
    return [row[0] for row in rows if row]


def check_dt(dataset, t):
    _, d1 = lab.sift_frame(vo.frame_path(dataset, 0))
    _, d2 = lab.sift_frame(vo.frame_path(dataset, 1))
    fast = [(m.queryIdx, m.trainIdx, m.distance) for m in first_matches("dt", d1, d2, t)]
    full = [(r[0].queryIdx, r[0].trainIdx, r[0].distance) for r in lab.dt(d1, d2, t) if r]
    if fast != full:
        raise SystemExit("dt shortcut differs from the lab's dt on frames 0-1")
    print("check ok: dt's first matches equal knnMatch(k=1) below t (%d matches)" % len(full))


def run(dataset, frames, algo, t):
    poses = vo.read_poses(dataset)
    sift = cv2.SIFT_create(nfeatures=vo.NFEATURES)
    R = np.eye(3)
    tr = np.zeros((3, 1))
    positions, rotations, trace = [], [], []
    prev = None
    for i in range(frames):
        img = cv2.imread(vo.frame_path(dataset, i), 0)
        if img is None:
            raise SystemExit("cannot read frame %d" % i)
        kp, des = sift.detectAndCompute(img, None)
        row = vo.trace_row(i, redetected=True)
        if i >= 1:
            kp1, des1 = prev
            m = first_matches(algo, des1, des, t)
            row["points_in"], row["tracked"] = len(kp1), len(m)
            if len(m) >= 5:
                px_ref = np.array([kp1[x.queryIdx].pt for x in m], dtype=np.float32)
                px_cur = np.array([kp[x.trainIdx].pt for x in m], dtype=np.float32)
                E, mask = cv2.findEssentialMat(px_cur, px_ref, focal=vo.FOCAL, pp=vo.PP,
                                               method=cv2.RANSAC, prob=0.999, threshold=1.0)
                n_pose, Ri, ti, _mask = cv2.recoverPose(E, px_cur, px_ref, focal=vo.FOCAL, pp=vo.PP)
                row["essential_inliers"], row["pose_inliers"] = int(np.count_nonzero(mask)), int(n_pose)
                if i == 1:
                    R, tr = Ri, ti
                else:
                    scale = math.dist(vo.gt_position(poses[i - 1]), vo.gt_position(poses[i]))
                    if scale > 0.1:
                        tr = tr + scale * R.dot(ti)
                        R = Ri.dot(R)
        prev = (kp, des)
        trace.append(row)
        positions.append(tuple(float(v) for v in tr.ravel()) if i >= 2 else (0.0, 0.0, 0.0))
        rotations.append(np.array(R, dtype=np.float64))
    return positions, rotations, trace


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--dataset", default=None)
    ap.add_argument("-a", "--algorithm", choices=lab.ALGOS)
    ap.add_argument("-t", "--threshold", type=float, default=None)
    ap.add_argument("--frames", type=int, default=None, help="frames from 0 (default: all; --fixtures: 151)")
    ap.add_argument("--out", default=None)
    ap.add_argument("--trace", default=None, help="write the per-frame counts here (JSON Lines)")
    ap.add_argument("--opencv-lanes", choices=("8", "16"), default=None,
                    help="SIFT's SIMD width: 8 disables OpenCV's AVX-512 dispatch (default: OpenCV's choice)")
    ap.add_argument("--fixtures", action="store_true",
                    help="write the three references under tests/fixtures/vo_matched/ (IPP off, 8 lanes)")
    ap.add_argument("--check", action="store_true", help="check the dt shortcut against the lab's dt")
    a = ap.parse_args()
    dataset = a.dataset or vo.default_dataset()
    vo.check_opencv(require_goldens=a.fixtures)
    cv2.setNumThreads(1)
    if a.check:
        check_dt(dataset, 200.0)
        return
    if a.fixtures and (a.dataset or a.out or a.trace):
        raise SystemExit("--fixtures writes the bundled dataset's references; drop --dataset/--out/--trace")
    frames = a.frames or (vo.FIXTURE_FRAMES if a.fixtures else vo.count_frames(dataset))
    if a.fixtures:
        jobs = [(alg, t, os.path.join(FIXTURE_DIR, name + ".txt"), os.path.join(FIXTURE_DIR, name + ".trace.jsonl"))
                for alg, t, name in FIXTURES]
    else:
        jobs = [(a.algorithm, a.threshold, a.out, a.trace)]
    for alg, t, out, trace_out in jobs:
        if alg is None:
            raise SystemExit("give -a ALGO (or --fixtures)")
        start = time.perf_counter()
        positions, rotations, trace = run(dataset, frames, alg, t)
        s = time.perf_counter() - start
        if out:
            vo.write_poses(out, positions, rotations)
        if trace_out:
            vo.write_trace(trace_out, trace)
        x, y, z = positions[-1]
        counts = [r["tracked"] for r in trace[1:]]
        print("%s %s: final position x=%.4f y=%.4f z=%.4f, matches %d..%d, %.2f frames/s (OpenCV %s, %d lanes)"
              % (alg, t, x, y, z, min(counts), max(counts), frames / s, cv2.__version__, vo.opencv_lanes()))
    if a.fixtures:
        vo.write_json(os.path.join(FIXTURE_DIR, "meta.json"), vo.fixture_meta(frames, {
            "loop": "the matcher-driven loop (tests/references/vo_matched_reference.py --fixtures)",
            "runs": {name: {"algorithm": alg, "threshold": t} for alg, t, name in FIXTURES},
            "files": {"NAME.txt": "KITTI pose lines, frames 0..%d" % (frames - 1),
                      "NAME.trace.jsonl": "per-frame counts, vo::StepResult names"}}))


if __name__ == "__main__":
    main()
