#!/usr/bin/env python3
"""The COMP24011 lab's feature-matching functions on OpenCV 4.8 — the reference siftlab must equal.

As a module:
    kp, des = sift_frame(path)                      # cv2.SIFT_create(nfeatures=1500) on imread(path, 0)
    dt(des1, des2, t) / nn(des1, des2, t=None) / nndr(des1, des2, t)   # list (per query) of lists
    matching_info(kp1, kp2, fm)                     # ((x, y), [(x, y), ...], [d, ...])
    get_info(dataset, frame_id, feature_id, algo, threshold, cache=None)
    get_info_stdout(dataset, frame_id, feature_id, algo, threshold, cache=None) -> the 4 lines

As a CLI mirroring `siftlab` / the lab's run_odometry.py:
    python3 lab_reference.py [-d DATASET] get_info -a {dt,nn,nndr} [-t T] FRAME_ID FEATURE_ID
prints
    vo params: ('dt', 100.0, '<dataset as given>')
    debug run: get_info(42, 7)
    ret value: ((523, 181), [(517, 183)], [61.400001525878906])
    ret count: 3

Frame FRAME_ID-1 is the query (des1), frame FRAME_ID the train set (des2); matches are computed
with cv2.BFMatcher() (NORM_L2). Requires opencv-contrib-python-headless==4.8.0.76, numpy<2.
"""
from __future__ import annotations

import argparse
import os
import sys

import cv2

NFEATURES = 1500
ALGOS = ("dt", "nn", "nndr")


def frame_path(dataset: str, frame_id: int) -> str:
    return os.path.join(os.path.expanduser(dataset), "gray", "00", "image_0", "%06d.png" % frame_id)


def sift_image(img):
    sift = cv2.SIFT_create(nfeatures=NFEATURES)
    return sift.detectAndCompute(img, None)


def sift_frame(path: str):
    img = cv2.imread(path, 0)
    if img is None:
        raise FileNotFoundError("cannot read image %s" % path)
    return sift_image(img)


# --- the three strategies, exactly as the lab writes them (a list of matches per query) -------

def dt(des1, des2, t):
    """Distance threshold: every train descriptor with distance < t, ascending."""
    bf = cv2.BFMatcher()
    matches = bf.knnMatch(des1, des2, k=len(des2))
    return [[m for m in row if m.distance < t] for row in matches]


def nn(des1, des2, t=None):
    """Nearest neighbour, kept if there is no threshold or its distance < t."""
    bf = cv2.BFMatcher()
    matches = bf.knnMatch(des1, des2, k=1)
    out = []
    for row in matches:
        m = row[0]
        out.append([m] if t is None or m.distance < t else [])
    return out


def nndr(des1, des2, t):
    """Nearest-neighbour distance ratio: the nearest, kept if d1 < t * d2."""
    bf = cv2.BFMatcher()
    matches = bf.knnMatch(des1, des2, k=2)
    out = []
    for m, n in matches:
        out.append([m] if m.distance < t * n.distance else [])
    return out


STRATEGIES = {"dt": dt, "nn": nn, "nndr": nndr}


def matching_info(kp1, kp2, fm):
    if not fm:
        return ((0, 0), [], [])
    q = kp1[fm[0].queryIdx].pt
    pts = [(int(kp2[m.trainIdx].pt[0]), int(kp2[m.trainIdx].pt[1])) for m in fm]
    return ((int(q[0]), int(q[1])), pts, [m.distance for m in fm])


class FeatureCache:
    """SIFT results per frame path (so many draws over a few frames run in seconds)."""

    def __init__(self):
        self._d = {}

    def get(self, path):
        if path not in self._d:
            self._d[path] = sift_frame(path)
        return self._d[path]


def check_args(frame_id, feature_id, algo, threshold):
    if algo not in ALGOS:
        raise ValueError("algorithm must be one of dt, nn, nndr, not %r" % (algo,))
    if frame_id < 1:
        raise ValueError("FRAME_ID must be >= 1 (frames FRAME_ID-1 and FRAME_ID are matched)")
    if feature_id < 0:
        raise ValueError("FEATURE_ID must be >= 0")
    if threshold is None and algo != "nn":
        raise ValueError("-t THRESHOLD is required for %s" % algo)


def get_info(dataset, frame_id, feature_id, algo, threshold, cache=None, row_only=True):
    """The lab's get_info: matching_info of feature `feature_id` of frame frame_id-1 against frame_id.

    row_only=True runs the strategy on the single query row: BFMatcher treats every query row
    independently, so this equals row `feature_id` of the full call (checked by --self-check) and
    keeps dt (k = len(des2)) cheap."""
    check_args(frame_id, feature_id, algo, threshold)
    cache = cache or FeatureCache()
    kp1, des1 = cache.get(frame_path(dataset, frame_id - 1))
    kp2, des2 = cache.get(frame_path(dataset, frame_id))
    if des1 is None or feature_id >= len(kp1):
        raise ValueError("FEATURE_ID %d out of range: frame %d has %d keypoints"
                         % (feature_id, frame_id - 1, 0 if des1 is None else len(kp1)))
    if des2 is None or len(des2) == 0:
        return matching_info(kp1, kp2, [])
    fn = STRATEGIES[algo]
    if row_only:
        fm = fn(des1[feature_id:feature_id + 1], des2, threshold)[0]
        # queryIdx is 0 for a one-row query; matching_info reads it, so restore the real index
        for m in fm:
            m.queryIdx = feature_id
    else:
        fm = fn(des1, des2, threshold)[feature_id]
    return matching_info(kp1, kp2, fm)


def format_stdout(dataset, frame_id, feature_id, algo, threshold, ret) -> str:
    lines = [
        "vo params: " + str((algo, threshold, dataset)),
        "debug run: get_info(%d, %d)" % (frame_id, feature_id),
        "ret value: " + str(ret),
        "ret count: %d" % len(ret),
    ]
    return "\n".join(lines) + "\n"


def get_info_stdout(dataset, frame_id, feature_id, algo, threshold, cache=None) -> str:
    ret = get_info(dataset, frame_id, feature_id, algo, threshold, cache)
    return format_stdout(dataset, frame_id, feature_id, algo, threshold, ret)


def self_check(dataset, frame_id=1, rows=(0, 1, 7, 500, 1499)):
    """Row-only evaluation equals the lab's full-matrix evaluation."""
    cache = FeatureCache()
    for algo, t in (("dt", 250.0), ("nn", None), ("nn", 200.0), ("nndr", 0.8)):
        for r in rows:
            a = get_info(dataset, frame_id, r, algo, t, cache, row_only=True)
            b = get_info(dataset, frame_id, r, algo, t, cache, row_only=False)
            if a != b:
                print("MISMATCH", algo, t, r, a, b)
                return 1
    print("self-check ok: row-only == full matrix")
    return 0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="lab_reference.py", description="OpenCV reference for siftlab get_info")
    ap.add_argument("-d", "--dataset", default="~/MyKITTI")
    sub = ap.add_subparsers(dest="cmd", required=True)
    g = sub.add_parser("get_info")
    g.add_argument("-a", "--algorithm", required=True, choices=ALGOS)
    g.add_argument("-t", "--threshold", type=float, default=None)
    g.add_argument("frame_id", type=int)
    g.add_argument("feature_id", type=int)
    sc = sub.add_parser("self-check")
    sc.add_argument("frame_id", type=int, nargs="?", default=1)
    a = ap.parse_args(argv)
    if a.cmd == "self-check":
        return self_check(a.dataset, a.frame_id)
    try:
        sys.stdout.write(get_info_stdout(a.dataset, a.frame_id, a.feature_id, a.algorithm, a.threshold))
    except (ValueError, FileNotFoundError) as e:
        print("error: %s" % e, file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
