#!/usr/bin/env python3
"""Regenerate siftlab's OpenCV golden fixtures (tests/fixtures/golden/).

Needs exactly:  pip install opencv-contrib-python-headless==4.8.0.76 "numpy<2"

Writes, for frames 000000..000005 and the lab manual's example frames 000119, 000120, 000149,
000150 of the dataset (default: the bundled real KITTI frames, www/demo/MyKITTI):

  golden/ipp/NNNNNN.sift     SIFT (nfeatures=1500) with the default wheel (IPP on)
  golden/noipp/NNNNNN.sift   the same with OPENCV_IPP=disabled set before cv2 is imported and
                             cv2.setNumThreads(1) (run in a subprocess: IPP is chosen at import)
  golden/meta.json           wheel, CPU, and the SIMD width (lanes) OpenCV's SIFT kernels ran with
  golden/get_info.jsonl      seeded random get_info draws (+ edge cases) over frame pairs 1..5, 120, 150,
                             stdout computed by lab_reference.py with the default wheel

.sift format (little-endian):
  magic b"SIFTGLD1", u32 width, u32 height, u32 N,
  N records of (x f32, y f32, size f32, angle f32, response f32, octave i32)   (24 bytes each),
  N*128 u8 descriptor values (OpenCV's float descriptors are integers 0..255; asserted).

get_info.jsonl, one object a line:
  {"dataset_frame": F, "feature": i, "algo": "dt"|"nn"|"nndr", "threshold": t|null,
   "stdout": "vo params: ...\\ndebug run: ...\\nret value: ...\\nret count: 3\\n"}
  where the dataset string printed is --label (default "www/demo/MyKITTI"), i.e. what
  `siftlab -d www/demo/MyKITTI get_info ...` run from the repository root must print.

Two sets are committed, each written on a CPU of its kind (meta.json says which, and on which
dataset); the default --out is the one that fits the CPU running the script:
  tests/fixtures/golden        an AVX-512 CPU: OpenCV's SIFT kernels 16 lanes wide
  tests/fixtures/golden-avx2   an AVX2 CPU without AVX-512: 8 lanes

Usage: python3 tests/references/gen_goldens.py [--dataset DIR] [--out DIR] [--draws 300] [--seed 24011]
"""
from __future__ import annotations

import argparse
import json
import os
import random
import struct
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
MAGIC = b"SIFTGLD1"
FRAMES = [0, 1, 2, 3, 4, 5, 119, 120, 149, 150]
# get_info matches frame F-1 against frame F: the first five pairs and the manual's two.
PAIRS = [1, 2, 3, 4, 5, 120, 150]
OPENCV_VERSION = "4.8.0"


def write_sift(path, width, height, kps, des):
    import numpy as np

    n = len(kps)
    if n:
        assert des is not None and des.shape == (n, 128), des.shape
        d = np.asarray(des)
        assert np.all(d == np.round(d)) and d.min() >= 0 and d.max() <= 255, "descriptor not integer 0..255"
        du8 = d.astype(np.uint8)
    else:
        du8 = np.zeros((0, 128), np.uint8)
    with open(path, "wb") as f:
        f.write(MAGIC)
        f.write(struct.pack("<III", width, height, n))
        for k in kps:
            f.write(struct.pack("<fffffi", k.pt[0], k.pt[1], k.size, k.angle, k.response, k.octave))
        f.write(du8.tobytes())


def read_sift(path):
    """(width, height, [(x, y, size, angle, response, octave)], uint8 array N x 128)."""
    import numpy as np

    with open(path, "rb") as f:
        b = f.read()
    if b[:8] != MAGIC:
        raise ValueError("%s: bad magic" % path)
    w, h, n = struct.unpack_from("<III", b, 8)
    off = 20
    recs = [struct.unpack_from("<fffffi", b, off + 24 * i) for i in range(n)]
    off += 24 * n
    des = np.frombuffer(b, dtype=np.uint8, count=128 * n, offset=off).reshape(n, 128)
    return w, h, recs, des


def worker(dataset, out_dir, frames):
    """Runs in a subprocess whose environment fixed IPP before cv2 was imported."""
    import cv2

    assert cv2.__version__ == OPENCV_VERSION, "need opencv-contrib-python-headless==4.8.0.76, have %s" % cv2.__version__
    if os.environ.get("OPENCV_IPP") == "disabled":
        cv2.setNumThreads(1)
        assert not cv2.ipp.useIPP(), "OPENCV_IPP=disabled did not disable IPP"
    os.makedirs(out_dir, exist_ok=True)
    sift = cv2.SIFT_create(nfeatures=1500)
    for i in frames:
        p = os.path.join(dataset, "gray", "00", "image_0", "%06d.png" % i)
        img = cv2.imread(p, 0)
        if img is None:
            raise SystemExit("cannot read %s" % p)
        kps, des = sift.detectAndCompute(img, None)
        write_sift(os.path.join(out_dir, "%06d.sift" % i), img.shape[1], img.shape[0], kps, des)
        print("%s %06d: %d keypoints (ipp=%s)" % (os.path.basename(out_dir), i, len(kps), cv2.ipp.useIPP()),
              file=sys.stderr)


def run_worker(dataset, out_dir, ipp: bool):
    env = dict(os.environ)
    env.pop("OPENCV_IPP", None)
    if not ipp:
        env["OPENCV_IPP"] = "disabled"
    subprocess.run([sys.executable, os.path.abspath(__file__), "--worker", "--dataset", dataset,
                    "--out", out_dir], env=env, check=True)


def draw_case(rng, n_features):
    """One random (feature, algo, threshold) for a frame pair whose query frame has n_features:
    thresholds dt/nn uniform in [0, 500] (nn: 20% None), nndr in [0, 1], rounded to 2 decimals.
    Shared by this generator and compare_opencv.py."""
    feat = rng.randrange(max(n_features, 1))
    algo = rng.choice(("dt", "nn", "nndr"))
    if algo == "nndr":
        t = round(rng.uniform(0.0, 1.0), 2)
    else:
        t = round(rng.uniform(0.0, 500.0), 2)
        if algo == "nn" and rng.random() < 0.2:
            t = None
    return feat, algo, t


def draws(counts, n_draws, seed):
    """(frame, feature, algo, threshold) cases: seeded uniform draws, then edge cases."""
    rng = random.Random(seed)
    out = []
    for _ in range(n_draws):
        f = rng.choice(PAIRS)
        out.append((f, *draw_case(rng, counts[f])))
    for f in PAIRS:
        last = counts[f] - 1
        mid = rng.randrange(counts[f])
        for feat in (0, last, mid):
            out.append((f, feat, "dt", 0.0))
            out.append((f, feat, "nn", 0.0))
            out.append((f, feat, "nndr", 0.0))
        out.append((f, 0, "dt", 300.0))
        out.append((f, last, "dt", 500.0))
        out.append((f, 0, "nn", None))
        out.append((f, last, "nn", None))
        out.append((f, 0, "nndr", 0.8))
        out.append((f, last, "nndr", 1.0))
    return out


def gen_get_info(dataset, label, out_path, n_draws, seed):
    sys.path.insert(0, HERE)
    import cv2
    import lab_reference as lab

    assert cv2.__version__ == OPENCV_VERSION
    cache = lab.FeatureCache()
    # counts[F]: keypoints of the query frame F-1 of pair F.
    counts = {}
    for f in PAIRS:
        kp, _ = cache.get(lab.frame_path(dataset, f - 1))
        counts[f] = len(kp)
    cases = draws(counts, n_draws, seed)
    n_nonempty = 0
    with open(out_path, "w") as fo:
        for f, feat, algo, t in cases:
            ret = lab.get_info(dataset, f, feat, algo, t, cache)
            n_nonempty += bool(ret[1])
            stdout = lab.format_stdout(label, f, feat, algo, t, ret)
            fo.write(json.dumps({"dataset_frame": f, "feature": feat, "algo": algo, "threshold": t,
                                 "stdout": stdout}) + "\n")
    print("get_info.jsonl: %d cases, %d with matches" % (len(cases), n_nonempty), file=sys.stderr)


def opencv_lanes(cpu_line: str) -> int:
    """SIMD width of OpenCV's dispatched SIFT kernels: 16 when the AVX512_SKX dispatch is taken
    (a '*' marks an available dispatched feature in getCPUFeaturesLine), else 8 (AVX2)."""
    return 16 if "*AVX512-SKX" in cpu_line.split() else 8


def write_meta(path, label):
    """What produced the goldens: the SIMD width changes angles/descriptors at the ulp level
    (docs/fidelity.md §SIFT-13), so tests must reproduce the goldens' width, not the test host's."""
    import cv2
    import numpy as np

    line = cv2.getCPUFeaturesLine()
    cpu = ""
    try:
        with open("/proc/cpuinfo") as f:
            cpu = next((l.split(":", 1)[1].strip() for l in f if l.startswith("model name")), "")
    except OSError:
        pass
    meta = {
        "wheel": "opencv-contrib-python-headless==4.8.0.76",
        "opencv": cv2.__version__,
        "numpy": np.__version__,
        "cpu_model": cpu,
        "opencv_cpu_features": line,
        "opencv_simd_lanes": opencv_lanes(line),
        "dataset": label,
        "frames": ["%06d" % i for i in FRAMES],
        "sift": "cv2.SIFT_create(nfeatures=1500).detectAndCompute(cv2.imread(path, 0), None)",
    }
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "w") as f:
        json.dump(meta, f, indent=1)
        f.write("\n")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--dataset", default=os.path.join(ROOT, "www", "demo", "MyKITTI"))
    ap.add_argument("--out", default=None, help="default: tests/fixtures/golden on AVX-512, golden-avx2 on AVX2")
    ap.add_argument("--label", default="www/demo/MyKITTI",
                    help="dataset path from the repository root, printed in get_info stdout")
    ap.add_argument("--draws", type=int, default=300)
    ap.add_argument("--seed", type=int, default=24011)
    ap.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    a = ap.parse_args(argv)
    if a.worker:
        worker(a.dataset, a.out, FRAMES)
        return 0
    import cv2

    if cv2.__version__ != OPENCV_VERSION:
        print("need opencv-contrib-python-headless==4.8.0.76 (have %s)" % cv2.__version__, file=sys.stderr)
        return 1
    if a.out is None:
        lanes = opencv_lanes(cv2.getCPUFeaturesLine())
        a.out = os.path.join(ROOT, "tests", "fixtures", "golden" if lanes == 16 else "golden-avx2")
    write_meta(os.path.join(a.out, "meta.json"), a.label)
    run_worker(a.dataset, os.path.join(a.out, "ipp"), ipp=True)
    run_worker(a.dataset, os.path.join(a.out, "noipp"), ipp=False)
    gen_get_info(a.dataset, a.label, os.path.join(a.out, "get_info.jsonl"), a.draws, a.seed)
    return 0


if __name__ == "__main__":
    sys.exit(main())
