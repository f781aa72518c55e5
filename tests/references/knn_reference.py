#!/usr/bin/env python3
"""The knnMatch golden for siftlab's cv2 shim: OpenCV 4.8's BFMatcher().knnMatch on the lab
manual's pair 119 -> 120, for a few queries chosen for their ties.

    python3 tests/references/knn_reference.py [--dataset DIR] [--out FILE]

Writes (default tests/fixtures/mark/knn_119_120.json) one JSON object:
  {"frames": [119, 120], "opencv": "4.8.0", "lanes": 8, "ipp": false, "nq": N1, "nt": N2,
   "des1_sha256", "des2_sha256": SHA-256 of the frames' descriptors as N x 128 bytes,
   "queries": [{"q": i, "why": "...", "k2": [[trainIdx, distance], ...], "k5": [...],
                "kx"?: {"k": K, "matches": [...]}}, ...],
   "full": [{"q": i, "why": "...", "k": N2, "matches": [[trainIdx, distance], ...]}, ...]}
Each list is row i of bf.knnMatch(des1, des2, k) (des1: frame 119, the query side), in
OpenCV's order; distance is the float32 widened to a Python float (repr, so exact). The
queries: ties between the nearest two (d1 == d2), ties across k = 2 (d2 == d3) and across
k = 5 (d5 == d6), ties deeper in the list with "kx" = the row at the k that cuts between the
two equal distances, a zero distance when there is one, the first and last query, and a few
others; "full" is k = len(des2) for two queries (all 1500 train rows, ties included).

OPENCV_IPP=disabled and 8 lanes (OPENCV_CPU_DISABLE=AVX512-SKX), checked as
match_all_reference.py checks them, so des1/des2 are siftlab's at 8 lanes bit for bit.
Requires opencv-contrib-python-headless==4.8.0.76 and numpy<2.
"""
from __future__ import annotations

import argparse
import hashlib
import json
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import match_all_reference as mar  # noqa: E402  (sets OPENCV_IPP / OPENCV_CPU_DISABLE, imports cv2)

import cv2  # noqa: E402
import numpy as np  # noqa: E402

import lab_reference as lab  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(HERE))
PREV, CUR = 119, 120


def pairs(row):
    return [[m.trainIdx, float(m.distance)] for m in row]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--dataset", default=os.path.join(ROOT, "www/demo/MyKITTI"))
    ap.add_argument("--out", default=os.path.join(ROOT, "tests/fixtures/mark/knn_119_120.json"))
    a = ap.parse_args()
    if not cv2.__version__.startswith("4.8.0"):
        sys.exit("OpenCV 4.8.0 is needed, found %s" % cv2.__version__)
    cv2.setNumThreads(1)
    if cv2.ipp.useIPP():
        sys.exit("OPENCV_IPP=disabled did not disable IPP")
    mar.check_eight_lanes(a.dataset)

    kp1, des1 = lab.sift_frame(lab.frame_path(a.dataset, PREV))
    kp2, des2 = lab.sift_frame(lab.frame_path(a.dataset, CUR))
    bf = cv2.BFMatcher()
    full = bf.knnMatch(des1, des2, k=len(des2))
    k2 = bf.knnMatch(des1, des2, k=2)
    k5 = bf.knnMatch(des1, des2, k=5)
    dist = [[float(m.distance) for m in row] for row in full]
    for q in range(len(des1)):  # knnMatch with a small k is the head of the full list
        assert pairs(k2[q]) == pairs(full[q])[:2] and pairs(k5[q]) == pairs(full[q])[:5], q

    picked = {}

    def pick(kind, qs, n):
        for q in qs:
            if len([1 for w in picked.values() if w == kind]) >= n:
                return
            picked.setdefault(q, kind)

    nq = len(des1)
    pick("tie d1 == d2", [q for q in range(nq) if dist[q][0] == dist[q][1]], 4)
    pick("tie d2 == d3 (across k = 2)", [q for q in range(nq) if dist[q][1] == dist[q][2]], 4)
    pick("tie d5 == d6 (across k = 5)", [q for q in range(nq) if dist[q][4] == dist[q][5]], 3)
    pick("tie within the nearest 5", [q for q in range(nq) if len(set(dist[q][:5])) < 5], 2)
    pick("zero distance", [q for q in range(nq) if dist[q][0] == 0.0], 1)
    # ties deeper in the list: k cuts between two equal distances (rank r and r + 1)
    first_tie = {}
    for q in range(nq):
        r = next((r for r in range(len(dist[q]) - 1) if dist[q][r] == dist[q][r + 1]), None)
        if r is not None and r < 64:
            first_tie[q] = r
    pick("tie across k = rank + 1", sorted(first_tie, key=lambda q: (first_tie[q], q)), 5)
    pick("first query", [0], 1)
    pick("last query", [nq - 1], 1)
    rest = [q for q in range(0, nq, 97) if q not in picked]
    pick("plain", rest, 20 - len(picked))
    queries = []
    cut = {}
    for q, why in sorted(picked.items()):
        rec = {"q": q, "why": why, "k2": pairs(k2[q]), "k5": pairs(k5[q])}
        if q in first_tie and first_tie[q] + 1 not in (2, 5):
            k = first_tie[q] + 1
            if k not in cut:
                cut[k] = bf.knnMatch(des1, des2, k=k)
            rec["kx"] = {"k": k, "matches": pairs(cut[k][q])}
        queries.append(rec)

    def ties_in(q):
        return len(dist[q]) - len(set(dist[q]))

    tie_q = max((q for q, w in picked.items() if w.startswith("tie")), key=ties_in, default=1)
    fulls = [{"q": q, "why": why, "k": len(des2), "matches": pairs(full[q])}
             for q, why in ((0, "first query"), (tie_q, "the most tied distances (%d)" % ties_in(tie_q)))]

    def sha(d):
        return hashlib.sha256(np.asarray(d).astype(np.uint8).tobytes()).hexdigest()

    out = {"frames": [PREV, CUR], "opencv": cv2.__version__, "lanes": 8, "ipp": False,
           "nq": len(des1), "nt": len(des2), "des1_sha256": sha(des1), "des2_sha256": sha(des2),
           "queries": queries, "full": fulls}
    os.makedirs(os.path.dirname(a.out), exist_ok=True)
    with open(a.out, "w") as fh:
        json.dump(out, fh, separators=(",", ":"))
        fh.write("\n")
    kinds = {}
    for w in picked.values():
        kinds[w] = kinds.get(w, 0) + 1
    print("%s: %d queries (%s), full lists for q %s" % (
        os.path.relpath(a.out, ROOT), len(queries), ", ".join("%s: %d" % kv for kv in kinds.items()),
        [f["q"] for f in fulls]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
