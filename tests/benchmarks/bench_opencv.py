#!/usr/bin/env python3
"""Times OpenCV 4.8.0.76 single-threaded on the lab's workload and prints one JSON object.

  sift_ms      cv2.SIFT_create(nfeatures=1500).detectAndCompute on a 1241x376 frame (decode
               excluded), median over frames x repeats
  knn2_ms      cv2.BFMatcher().knnMatch(des1, des2, k=2) on the 1500x1500 descriptors of frames 0, 1
  knn1_ms      the same with k=1 (the lab's nn)
  knn_all_ms   (only with --knn-all) the same with k=len(des2) (the lab's dt); slow (~7 s): it
               builds 2.25 M Python DMatch objects

A Rust-side bench runner calls this in the same run and divides its own times by these.

Usage: python3 tests/benchmarks/bench_opencv.py [--dataset DIR] [--repeat 5] [--frames 3] [--knn-all]
Dataset default: www/demo/MyKITTI (the bundled real KITTI 00 frames).
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))


def default_dataset():
    return os.path.join(ROOT, "www", "demo", "MyKITTI")


def timed(fn, repeat):
    ts = []
    out = None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        ts.append((time.perf_counter() - t0) * 1000.0)
    return ts, out


def cpu_model():
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor()


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--dataset", default=None)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--frames", type=int, default=3, help="frames 0..N-1 are timed for SIFT")
    ap.add_argument("--knn-all", action="store_true", help="also time knnMatch(k=len(des2)) (the lab's dt)")
    a = ap.parse_args(argv)
    import cv2

    cv2.setNumThreads(1)
    ds = a.dataset or default_dataset()
    imgs = []
    for i in range(max(a.frames, 2)):
        p = os.path.join(ds, "gray", "00", "image_0", "%06d.png" % i)
        img = cv2.imread(p, 0)
        if img is None:
            print("cannot read %s" % p, file=sys.stderr)
            return 1
        imgs.append(img)

    sift = cv2.SIFT_create(nfeatures=1500)
    sift.detectAndCompute(imgs[0], None)  # warm-up (allocations, IPP dispatch)
    sift_ts = []
    feats = []
    for img in imgs[:max(a.frames, 1)]:
        ts, out = timed(lambda: sift.detectAndCompute(img, None), a.repeat)
        sift_ts += ts
        feats.append(out)
    if len(feats) < 2:
        feats.append(sift.detectAndCompute(imgs[1], None))
    des1, des2 = feats[0][1], feats[1][1]
    bf = cv2.BFMatcher()
    bf.knnMatch(des1, des2, k=2)
    knn2, _ = timed(lambda: bf.knnMatch(des1, des2, k=2), a.repeat)
    knn1, _ = timed(lambda: bf.knnMatch(des1, des2, k=1), a.repeat)
    res = {
        "sift_ms": statistics.median(sift_ts),
        "knn2_ms": statistics.median(knn2),
        "knn1_ms": statistics.median(knn1),
        "sift_min_ms": min(sift_ts),
        "knn2_min_ms": min(knn2),
        "n_query": int(len(des1)),
        "n_train": int(len(des2)),
        "width": int(imgs[0].shape[1]),
        "height": int(imgs[0].shape[0]),
        "frames": max(a.frames, 1),
        "repeat": a.repeat,
        "threads": cv2.getNumThreads(),
        "ipp": bool(cv2.ipp.useIPP()),
        "opencv": cv2.__version__,
        "cpu": cpu_model(),
        "dataset": ds,
    }
    if a.knn_all:
        knn_all, _ = timed(lambda: bf.knnMatch(des1, des2, k=len(des2)), 1)
        res["knn_all_ms"] = knn_all[0]
    print(json.dumps(res))
    return 0


if __name__ == "__main__":
    sys.exit(main())
