#!/usr/bin/env python3
"""Compares siftlab's view_feature / view_info PNGs with the lab's OpenCV 4.8 images.

For each case the lab's images are drawn by OpenCV in a fresh process (as the
lab's run_odometry.py does: one drawMatchesKnn per process, so theRNG colours
are the lab's), from the lab's own SIFT + BFMatcher strategies
(tests/references/lab_reference.py); siftlab's come from the binary. Prints the
number of differing pixels per image.

  python3 compare_visual.py --siftlab target/release/siftlab -d DATASET \
      [--case dt:200:2:7 ...] [--random N --frames F]
"""
import argparse
import os
import random
import subprocess
import sys
import tempfile

import cv2
import numpy as np

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", "..", ".."))
sys.path.insert(0, os.path.join(ROOT, "tests", "scripts"))
import lab_reference as lab  # noqa: E402


def lab_images(dataset, algo, t, frame, feature, outdir):
    """The lab's visualiseFeature / visualiseFeatureInfo on OpenCV's keypoints."""
    img1 = cv2.imread(lab.frame_path(dataset, frame - 1), 0)
    img2 = cv2.imread(lab.frame_path(dataset, frame), 0)
    kp1, des1 = lab.sift_image(img1)
    kp2, des2 = lab.sift_image(img2)
    fm = lab.STRATEGIES[algo](des1, des2, t)[feature]
    ov = cv2.drawMatchesKnn(img1, kp1, img2, kp2, [fm], None, flags=2)
    info = lab.matching_info(kp1, kp2, fm)
    a = cv2.cvtColor(img1, cv2.COLOR_GRAY2BGR)
    b = cv2.cvtColor(img2, cv2.COLOR_GRAY2BGR)
    if len(info[1]) > 0:
        a = cv2.circle(a, info[0], 10, (0, 255, 0), 2)
        for p in info[1]:
            b = cv2.circle(b, p, 10, (0, 255, 0), 2)
    cv = cv2.vconcat([ov, cv2.hconcat([a, b])])
    cv2.imwrite(os.path.join(outdir, "opencv_visual.png"), ov)
    cv2.imwrite(os.path.join(outdir, "custom_visual.png"), cv)
    return len(fm)


def fnv1a64(img_bgr):
    """FNV-1a 64 of the RGB bytes, row-major (what core/tests/cli_visual.rs hashes)."""
    h = 0xcbf29ce484222325
    data = cv2.cvtColor(img_bgr, cv2.COLOR_BGR2RGB).tobytes()
    arr = np.frombuffer(data, dtype=np.uint8)
    # Vectorised FNV is awkward; a plain loop over ~3 MB takes a few seconds.
    for b in arr.tolist():
        h = ((h ^ b) * 0x100000001b3) & 0xFFFFFFFFFFFFFFFF
    return h


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--siftlab", required=True)
    ap.add_argument("-d", "--dataset", required=True)
    ap.add_argument("--case", action="append", default=[])
    ap.add_argument("--random", type=int, default=0)
    ap.add_argument("--frames", type=int, default=6)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--lab-one", nargs=6, help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.lab_one:
        ds, algo, t, frame, feature, out = a.lab_one
        n = lab_images(ds, algo, None if t == "None" else float(t), int(frame), int(feature), out)
        print(n)
        if os.environ.get("SIFTLAB_HASH"):
            for name in ("opencv_visual.png", "custom_visual.png"):
                print(name, "0x%016x" % fnv1a64(cv2.imread(os.path.join(out, name))), file=sys.stderr)
        return 0
    cases = [tuple(c.split(":")) for c in a.case]
    rng = random.Random(a.seed)
    for _ in range(a.random):
        algo = rng.choice(["dt", "nn", "nndr"])
        t = {"dt": rng.uniform(150, 500), "nn": rng.choice([None, rng.uniform(0, 500)]),
             "nndr": rng.uniform(0.3, 1.0)}[algo]
        cases.append((algo, "None" if t is None else repr(t), str(rng.randint(1, a.frames - 1)),
                      str(rng.randint(0, 400))))
    total_bad = 0
    for algo, t, frame, feature in cases:
        with tempfile.TemporaryDirectory() as cvdir, tempfile.TemporaryDirectory() as rsdir:
            n = subprocess.run([sys.executable, __file__, "--siftlab", a.siftlab, "-d", a.dataset,
                                "--lab-one", a.dataset, algo, t, frame, feature, cvdir],
                               check=True, capture_output=True, text=True).stdout.strip()
            args = [os.path.abspath(a.siftlab), "-d", os.path.abspath(a.dataset)]
            for cmd in ("view_feature", "view_info"):
                targs = [] if t == "None" else ["-t", t]
                subprocess.run(args + [cmd, "-a", algo] + targs + [frame, feature], cwd=rsdir,
                               check=True, capture_output=True)
            res = []
            for name in ("opencv_visual.png", "custom_visual.png"):
                x = cv2.imread(os.path.join(cvdir, name))
                y = cv2.imread(os.path.join(rsdir, name))
                if x.shape != y.shape:
                    res.append("%s shape %s vs %s" % (name, x.shape, y.shape))
                    total_bad += 1
                    continue
                d = int(np.any(x != y, axis=2).sum())
                total_bad += d > 0
                res.append("%s %d px differ" % (name, d))
            print("%s t=%s frame=%s feature=%s matches=%s: %s" % (algo, t, frame, feature, n, "; ".join(res)))
    print("cases with differences:", total_bad)
    return 1 if total_bad else 0


if __name__ == "__main__":
    sys.exit(main())
