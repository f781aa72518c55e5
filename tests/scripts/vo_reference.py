#!/usr/bin/env python3
"""The COMP24011 lab's monocular visual odometry on OpenCV 4.8 — the reference for
`siftlab view_trajectory` (docs/fidelity.md §VO-5).

    python3 vo_reference.py --dataset DIR [--frames N] [--out poses.txt] [--json]

Per frame: SIFT (nfeatures=1500) keypoints of frame 0; LK tracking
(21x21, 3 levels, 30 iterations / 0.01); findEssentialMat(cur, ref, RANSAC, 0.999, 1 px);
recoverPose; t += scale * R.ti and R = Ri.R when the ground-truth scale > 0.1;
re-detection when fewer than 1500 points were tracked. KITTI 00 intrinsics.

Prints the final position, the trajectory error (ATE RMSE, no alignment, GT scale) and the
frames per second of the whole loop (image reading included, as the lab runs it). --out writes
the estimate in KITTI pose format, one line per frame from 0: the accumulated R and the position
the lab draws (0 for frames 0 and 1). --json prints one JSON object instead.

The dataset defaults to www/demo/MyKITTI (the bundled real KITTI 00 frames).
Requires opencv-contrib-python-headless==4.8.0.76 and numpy<2.
"""
from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time

import cv2
import numpy as np

FOCAL = 718.8560
PP = (607.1928, 185.2157)
NFEATURES = 1500
LK_PARAMS = dict(winSize=(21, 21), criteria=(cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 30, 0.01))

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def default_dataset() -> str:
    return os.path.join(REPO, "www", "demo", "MyKITTI")


def frame_path(dataset: str, i: int) -> str:
    return os.path.join(dataset, "gray", "00", "image_0", "%06d.png" % i)


def read_poses(dataset: str):
    with open(os.path.join(dataset, "poses", "00.txt")) as f:
        rows = [[float(v) for v in line.split()] for line in f if line.strip()]
    return rows


def gt_position(row):
    return (row[3], row[7], row[11])


def count_frames(dataset: str) -> int:
    n = 0
    while os.path.isfile(frame_path(dataset, n)):
        n += 1
    return n


def run(dataset: str, frames: int):
    """The lab's loop. Returns (positions, rotations, per-frame seconds)."""
    poses = read_poses(dataset)
    sift = cv2.SIFT_create(nfeatures=NFEATURES)

    def detect(img):
        return np.array([k.pt for k in sift.detect(img, None)], dtype=np.float32)

    positions, rotations = [], []
    R = np.eye(3)
    t = np.zeros((3, 1))
    last = ref = None
    for i in range(frames):
        img = cv2.imread(frame_path(dataset, i), 0)
        if img is None:
            raise SystemExit("cannot read frame %d (%s)" % (i, frame_path(dataset, i)))
        if i == 0:
            ref = detect(img)
        else:
            cur, st, _err = cv2.calcOpticalFlowPyrLK(last, img, ref, None, **LK_PARAMS)
            st = st.reshape(-1)
            ref, cur = ref[st == 1], cur[st == 1]
            E, _mask = cv2.findEssentialMat(cur, ref, focal=FOCAL, pp=PP, method=cv2.RANSAC,
                                            prob=0.999, threshold=1.0)
            _n, Ri, ti, _mask = cv2.recoverPose(E, cur, ref, focal=FOCAL, pp=PP)
            if i == 1:
                R, t = Ri, ti
            else:
                scale = math.dist(gt_position(poses[i - 1]), gt_position(poses[i]))
                if scale > 0.1:
                    t = t + scale * R.dot(ti)
                    R = Ri.dot(R)
                if len(ref) < NFEATURES:
                    cur = detect(img)
            ref = cur
        last = img
        positions.append(tuple(float(v) for v in t.ravel()) if i >= 2 else (0.0, 0.0, 0.0))
        rotations.append(np.array(R, dtype=np.float64))
    return positions, rotations, poses


def ate_rmse(est, gt):
    return math.sqrt(sum(sum((a - b) ** 2 for a, b in zip(e, g)) for e, g in zip(est, gt)) / len(est))


def write_poses(path, positions, rotations):
    with open(path, "w") as f:
        for p, R in zip(positions, rotations):
            row = [R[0, 0], R[0, 1], R[0, 2], p[0], R[1, 0], R[1, 1], R[1, 2], p[1],
                   R[2, 0], R[2, 1], R[2, 2], p[2]]
            f.write(" ".join(repr(float(v)) for v in row) + "\n")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--dataset", default=None, help="MyKITTI layout (default: www/demo/MyKITTI)")
    ap.add_argument("--frames", type=int, default=None, help="number of frames from 0 (default: all)")
    ap.add_argument("--out", default=None, help="write the estimated poses here (KITTI format)")
    ap.add_argument("--json", action="store_true", help="print one JSON object")
    args = ap.parse_args()
    dataset = args.dataset or default_dataset()
    available = count_frames(dataset)
    frames = args.frames if args.frames is not None else available
    if frames < 2 or frames > available:
        raise SystemExit("need 2..%d frames, got %d (dataset %s)" % (available, frames, dataset))

    start = time.perf_counter()
    positions, rotations, poses = run(dataset, frames)
    elapsed = time.perf_counter() - start
    gt = [gt_position(poses[i]) for i in range(frames)]
    ate = ate_rmse(positions, gt)
    if args.out:
        write_poses(args.out, positions, rotations)
    result = {
        "dataset": dataset,
        "frames": frames,
        "seconds": elapsed,
        "fps": frames / elapsed,
        "final_position": positions[-1],
        "final_gt": gt[-1],
        "ate_rmse": ate,
        "opencv": cv2.__version__,
    }
    if args.json:
        print(json.dumps(result))
    else:
        x, y, z = positions[-1]
        print("final position: x=%.4f y=%.4f z=%.4f (ground truth %.4f %.4f %.4f)" % (x, y, z, *gt[-1]))
        print("trajectory error (ATE RMSE, %d frames): %.4f m" % (frames, ate))
        print("%.2f frames/s (%.3f s for %d frames, OpenCV %s)" % (frames / elapsed, elapsed, frames, cv2.__version__))


if __name__ == "__main__":
    main()
