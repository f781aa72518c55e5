#!/usr/bin/env python3
"""The COMP24011 lab's monocular visual odometry on OpenCV 4.8 — the reference for
`siftlab view_trajectory` (docs/fidelity.md §VO-5).

    python3 vo_reference.py [--dataset DIR] [--frames N] [--out poses.txt] [--trace FILE] [--json]
                            [--opencv-lanes {8,16}] [--no-ipp]
    python3 vo_reference.py --fixtures      # tests/fixtures/vo_lk/: frames 0-150, IPP off, 8 lanes
    python3 vo_reference.py --fixtures --camera-fixture   # tests/fixtures/vo_kitti03/: the same
        # frames as sequence 03 in KITTI's layout, with its calib.txt (fx = fy = 721.5377)

Per frame: SIFT (nfeatures=1500) keypoints of frame 0; LK tracking
(21x21, 3 levels, 30 iterations / 0.01); findEssentialMat(cur, ref, RANSAC, 0.999, 1 px);
recoverPose; t += scale * R.ti and R = Ri.R when the ground-truth scale > 0.1;
re-detection when fewer than 1500 points were tracked. The camera is the sequence's calib.txt P0
(the lab's KITTI 00 intrinsics when the lab's layout has none); -s picks the sequence.

Prints the final position, the trajectory error (ATE RMSE, no alignment, GT scale) and the
frames per second of the whole loop (image reading included, as the lab runs it). --out writes
the estimate in KITTI pose format, one line per frame from 0: the accumulated R and the position
the lab draws (0 for frames 0 and 1). --json prints one JSON object instead. --trace writes JSON
Lines, one object per frame, named as the fields of siftlab's `vo::StepResult` (what
`siftlab view_trajectory --trace` writes):
  {"frame": i, "points_in": points given to LK, "tracked": status-1 points,
   "essential_inliers": nonzero entries of findEssentialMat's RANSAC mask,
   "pose_inliers": recoverPose's returned count, "redetected": SIFT ran on this frame}
(frame 0: 0, 0, 0, 0, true).

OpenCV's configuration must be chosen before cv2 is imported, so these flags are read from the
command line at import (also when compare_vo.py or vo_matched_reference.py imports this module
with the same flags): --no-ipp sets OPENCV_IPP=disabled (the build siftlab reproduces bit for bit,
docs/fidelity.md §SIFT-14); --opencv-lanes 8 sets OPENCV_CPU_DISABLE=AVX512-SKX, so SIFT's
dispatched kernels run 8 lanes wide on an AVX-512 CPU too, as on an AVX2 one (siftlab
--opencv-lanes 8; §SIFT-13; OpenCV spells the feature with a hyphen). The default is what OpenCV
picks on this CPU. The script checks that the width asked for is the width OpenCV runs, and with
--fixtures (which implies --no-ipp --opencv-lanes 8) that SIFT on the golden-avx2 frames equals
tests/fixtures/golden-avx2/noipp/*.sift bit for bit before writing anything.

The dataset defaults to www/demo/MyKITTI (the bundled real KITTI 00 frames).
Requires opencv-contrib-python-headless==4.8.0.76 and numpy<2.
"""
from __future__ import annotations

import argparse
import json
import math
import os
import struct
import sys
import time


def _flag_value(argv, name):
    """The value of `name VALUE` or `name=VALUE` in argv, else None."""
    for k, a in enumerate(argv):
        if a == name and k + 1 < len(argv):
            return argv[k + 1]
        if a.startswith(name + "="):
            return a.split("=", 1)[1]
    return None


def configure_opencv(argv):
    """Sets OpenCV's environment from argv before cv2 is imported; returns the SIMD width asked
    for (8 or 16), or None for OpenCV's own choice."""
    fixtures = "--fixtures" in argv
    if "--no-ipp" in argv or fixtures:
        os.environ["OPENCV_IPP"] = "disabled"
    lanes = _flag_value(argv, "--opencv-lanes") or ("8" if fixtures else None)
    if lanes not in (None, "8", "16"):
        raise SystemExit("--opencv-lanes must be 8 or 16, got %s" % lanes)
    if lanes == "8":
        os.environ["OPENCV_CPU_DISABLE"] = ",".join(
            v for v in (os.environ.get("OPENCV_CPU_DISABLE"), "AVX512-SKX") if v)
    return int(lanes) if lanes else None


REQUESTED_LANES = configure_opencv(sys.argv[1:])

import cv2  # noqa: E402
import numpy as np  # noqa: E402

FOCAL = 718.8560
PP = (607.1928, 185.2157)
NFEATURES = 1500
LK_PARAMS = dict(winSize=(21, 21), criteria=(cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 30, 0.01))

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
FIXTURE_DIR = os.path.join(REPO, "tests", "fixtures", "vo_lk")
# The same loop on the bundled frames as KITTI-layout sequence 03, with 03's camera.
CAMERA_FIXTURE_DIR = os.path.join(REPO, "tests", "fixtures", "vo_kitti03")
# The committed references run frames 0..FIXTURE_FRAMES-1 (the bundled 0-150).
FIXTURE_FRAMES = 151
GOLDEN = os.path.join(REPO, "tests", "fixtures", "golden-avx2")
# Field names of siftlab's vo::StepResult, in the order the trace writes them.
TRACE_FIELDS = ("frame", "points_in", "tracked", "essential_inliers", "pose_inliers", "redetected")


def opencv_lanes():
    """SIMD width of OpenCV's dispatched SIFT kernels in this process: 16 when the AVX512_SKX
    dispatch is taken (marked '*AVX512-SKX', without '?', in getCPUFeaturesLine), else 8."""
    return 16 if "*AVX512-SKX" in cv2.getCPUFeaturesLine().split() else 8


def check_opencv(require_goldens=False):
    """OpenCV is 4.8.0, runs at the width asked for, without IPP if asked; with
    `require_goldens`, SIFT on every golden-avx2 frame equals its noipp file bit for bit."""
    if cv2.__version__ != "4.8.0":
        raise SystemExit("need opencv-contrib-python-headless==4.8.0.76, have %s" % cv2.__version__)
    if os.environ.get("OPENCV_IPP") == "disabled" and cv2.ipp.useIPP():
        raise SystemExit("OPENCV_IPP=disabled did not disable IPP")
    if REQUESTED_LANES is not None and opencv_lanes() != REQUESTED_LANES:
        raise SystemExit("asked for %d lanes, but OpenCV runs %d here (%s)"
                         % (REQUESTED_LANES, opencv_lanes(), cv2.getCPUFeaturesLine()))
    if not require_goldens:
        return
    with open(os.path.join(GOLDEN, "meta.json")) as f:
        meta = json.load(f)
    if meta["opencv_simd_lanes"] != opencv_lanes() or cv2.ipp.useIPP():
        raise SystemExit("the golden check needs IPP off and %d lanes" % meta["opencv_simd_lanes"])
    sift = cv2.SIFT_create(nfeatures=NFEATURES)
    for name in meta["frames"]:
        with open(os.path.join(GOLDEN, "noipp", name + ".sift"), "rb") as f:
            b = f.read()
        n = struct.unpack_from("<III", b, 8)[2]
        kps, des = sift.detectAndCompute(cv2.imread(frame_path(default_dataset(), int(name)), 0), None)
        got = b"".join(struct.pack("<fffffi", k.pt[0], k.pt[1], k.size, k.angle, k.response, k.octave)
                       for k in kps)
        if len(kps) != n or got != b[20:20 + 24 * n] or des.astype(np.uint8).tobytes() != b[20 + 24 * n:]:
            raise SystemExit("SIFT on frame %s differs from golden-avx2/noipp: OpenCV is not configured "
                             "as the goldens were written" % name)


def fixture_meta(frames, extra=None):
    """What wrote a fixture: the wheel, OpenCV's CPU line and SIFT width, IPP, the frames."""
    meta = {
        "wheel": "opencv-contrib-python-headless==4.8.0.76",
        "opencv": cv2.__version__,
        "numpy": np.__version__,
        "ipp": bool(cv2.ipp.useIPP()),
        "opencv_cpu_features": cv2.getCPUFeaturesLine(),
        "opencv_simd_lanes": opencv_lanes(),
        "dataset": "www/demo/MyKITTI",
        "frames": [0, frames - 1],
    }
    meta.update(extra or {})
    return meta


def write_json(path, obj):
    with open(path, "w") as f:
        f.write(json.dumps(obj, indent=1) + "\n")


def write_trace(path, trace):
    """JSON Lines, one StepResult-named object per frame, as `siftlab --trace` writes them."""
    with open(path, "w") as f:
        for row in trace:
            f.write(json.dumps({k: row[k] for k in TRACE_FIELDS}) + "\n")


def trace_row(frame, points_in=0, tracked=0, essential_inliers=0, pose_inliers=0, redetected=False):
    return {"frame": frame, "points_in": points_in, "tracked": tracked,
            "essential_inliers": essential_inliers, "pose_inliers": pose_inliers,
            "redetected": bool(redetected)}


def default_dataset() -> str:
    return os.path.join(REPO, "www", "demo", "MyKITTI")


def sequence_dir(dataset: str, seq: str = "00") -> str:
    """The sequence's folder: gray/NN (the lab's MyKITTI layout, preferred when both exist, as
    siftlab does) or sequences/NN (KITTI's odometry layout)."""
    lab = os.path.join(dataset, "gray", seq)
    if os.path.isdir(os.path.join(lab, "image_0")):
        return lab
    return os.path.join(dataset, "sequences", seq)


def frame_path(dataset: str, i: int, seq: str = "00") -> str:
    return os.path.join(sequence_dir(dataset, seq), "image_0", "%06d.png" % i)


def read_poses(dataset: str, seq: str = "00"):
    with open(os.path.join(dataset, "poses", seq + ".txt")) as f:
        rows = [[float(v) for v in line.split()] for line in f if line.strip()]
    return rows


def read_camera(dataset: str, seq: str = "00"):
    """(focal, pp) from the sequence's calib.txt P0 line (fx = P0[0], cx = P0[2], fy = P0[5],
    cy = P0[6]); the lab's KITTI 00 camera when the lab's layout has no calib.txt."""
    path = os.path.join(sequence_dir(dataset, seq), "calib.txt")
    if not os.path.isfile(path):
        if os.path.basename(os.path.dirname(sequence_dir(dataset, seq))) == "sequences":
            raise SystemExit("%s is missing: KITTI's layout needs the sequence's camera" % path)
        return FOCAL, PP
    with open(path) as f:
        for line in f:
            if line.startswith("P0:"):
                p = [float(v) for v in line.split()[1:]]
                if p[0] != p[5]:
                    raise SystemExit("%s: fx != fy; the lab's call passes one focal length" % path)
                return p[0], (p[2], p[6])
    raise SystemExit("%s has no P0 line" % path)


def gt_position(row):
    return (row[3], row[7], row[11])


def count_frames(dataset: str, seq: str = "00") -> int:
    n = 0
    while os.path.isfile(frame_path(dataset, n, seq)):
        n += 1
    return n


def run(dataset: str, frames: int, seq: str = "00"):
    """The lab's loop on sequence `seq` with its camera (`read_camera`). Returns (positions,
    rotations, poses, trace): the trace as `trace_row`s."""
    poses = read_poses(dataset, seq)
    focal, pp = read_camera(dataset, seq)
    sift = cv2.SIFT_create(nfeatures=NFEATURES)

    def detect(img):
        return np.array([k.pt for k in sift.detect(img, None)], dtype=np.float32)

    positions, rotations, trace = [], [], []
    R = np.eye(3)
    t = np.zeros((3, 1))
    last = ref = None
    for i in range(frames):
        img = cv2.imread(frame_path(dataset, i, seq), 0)
        if img is None:
            raise SystemExit("cannot read frame %d (%s)" % (i, frame_path(dataset, i, seq)))
        if i == 0:
            ref = detect(img)
            trace.append(trace_row(0, redetected=True))
        else:
            points_in = len(ref)
            cur, st, _err = cv2.calcOpticalFlowPyrLK(last, img, ref, None, **LK_PARAMS)
            st = st.reshape(-1)
            ref, cur = ref[st == 1], cur[st == 1]
            E, mask = cv2.findEssentialMat(cur, ref, focal=focal, pp=pp, method=cv2.RANSAC,
                                           prob=0.999, threshold=1.0)
            n_pose, Ri, ti, _mask = cv2.recoverPose(E, cur, ref, focal=focal, pp=pp)
            redetected = False
            if i == 1:
                R, t = Ri, ti
            else:
                scale = math.dist(gt_position(poses[i - 1]), gt_position(poses[i]))
                if scale > 0.1:
                    t = t + scale * R.dot(ti)
                    R = Ri.dot(R)
                if len(ref) < NFEATURES:
                    cur = detect(img)
                    redetected = True
            trace.append(trace_row(i, points_in, len(ref), int(np.count_nonzero(mask)), int(n_pose), redetected))
            ref = cur
        last = img
        positions.append(tuple(float(v) for v in t.ravel()) if i >= 2 else (0.0, 0.0, 0.0))
        rotations.append(np.array(R, dtype=np.float64))
    return positions, rotations, poses, trace


def kitti_layout_copy(dataset: str, seq: str, calib: str) -> str:
    """A temporary dataset in KITTI's layout: sequences/SEQ/image_0/ links to the lab-layout
    frames of `dataset`, sequences/SEQ/calib.txt is a copy of `calib`, poses/SEQ.txt of the
    dataset's poses/00.txt (what tests/ builds for siftlab the same way)."""
    import shutil
    import tempfile
    root = tempfile.mkdtemp(prefix="siftlab-kitti-")
    frames = os.path.join(root, "sequences", seq, "image_0")
    os.makedirs(frames)
    os.makedirs(os.path.join(root, "poses"))
    for i in range(count_frames(dataset)):
        os.symlink(os.path.abspath(frame_path(dataset, i)), os.path.join(frames, "%06d.png" % i))
    shutil.copy(calib, os.path.join(root, "sequences", seq, "calib.txt"))
    shutil.copy(os.path.join(dataset, "poses", "00.txt"), os.path.join(root, "poses", seq + ".txt"))
    return root


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
    ap.add_argument("--trace", default=None, help="write the per-frame counts here (JSON Lines)")
    ap.add_argument("--opencv-lanes", choices=("8", "16"), default=None,
                    help="SIFT's SIMD width: 8 disables OpenCV's AVX-512 dispatch (default: OpenCV's choice)")
    ap.add_argument("--no-ipp", action="store_true", help="OPENCV_IPP=disabled (the build siftlab reproduces)")
    ap.add_argument("--fixtures", action="store_true",
                    help="write tests/fixtures/vo_lk/ (frames 0-150, IPP off, 8 lanes, checked against the goldens)")
    ap.add_argument("-s", "--sequence", default="00", help="the sequence (gray/NN or sequences/NN; default 00)")
    ap.add_argument("--camera-fixture", action="store_true",
                    help="with --fixtures: write tests/fixtures/vo_kitti03/ instead, the bundled frames as sequence 03 "
                         "in KITTI's layout with that folder's calib.txt (sequence 03's camera)")
    args = ap.parse_args()
    args.sequence = "%02d" % int(args.sequence)
    check_opencv(require_goldens=args.fixtures)
    if os.environ.get("OPENCV_IPP") == "disabled":
        cv2.setNumThreads(1)  # as the goldens were written (threads never change the output)
    dataset = args.dataset or default_dataset()
    fixture_dir = FIXTURE_DIR
    if args.camera_fixture and not args.fixtures:
        raise SystemExit("--camera-fixture goes with --fixtures")
    if args.fixtures:
        if args.dataset or args.out or args.trace:
            raise SystemExit("--fixtures writes the bundled dataset's references; drop --dataset/--out/--trace")
        if args.camera_fixture:
            fixture_dir = CAMERA_FIXTURE_DIR
            dataset = kitti_layout_copy(dataset, "03", os.path.join(fixture_dir, "calib.txt"))
            args.sequence = "03"
        os.makedirs(fixture_dir, exist_ok=True)
        args.frames = args.frames or FIXTURE_FRAMES
        args.out = os.path.join(fixture_dir, "poses.txt")
        args.trace = os.path.join(fixture_dir, "trace.jsonl")
    seq = args.sequence
    available = count_frames(dataset, seq)
    frames = args.frames if args.frames is not None else available
    if frames < 2 or frames > available:
        raise SystemExit("need 2..%d frames, got %d (dataset %s)" % (available, frames, dataset))

    start = time.perf_counter()
    positions, rotations, poses, trace = run(dataset, frames, seq)
    elapsed = time.perf_counter() - start
    gt = [gt_position(poses[i]) for i in range(frames)]
    ate = ate_rmse(positions, gt)
    if args.out:
        write_poses(args.out, positions, rotations)
    if args.trace:
        write_trace(args.trace, trace)
    if args.fixtures:
        extra = {
            "loop": "the lab's LK loop (tests/references/vo_reference.py --fixtures%s)"
                    % (" --camera-fixture" if args.camera_fixture else ""),
            "files": {"poses.txt": "KITTI pose lines, frames 0..%d" % (frames - 1),
                      "trace.jsonl": "per-frame counts, vo::StepResult names"}}
        if args.camera_fixture:
            focal, pp = read_camera(dataset, seq)
            extra["layout"] = ("KITTI's: sequences/03/image_0 = the bundled frames, sequences/03/calib.txt = "
                               "calib.txt here, poses/03.txt = the bundled poses/00.txt")
            extra["camera"] = {"focal": focal, "pp": list(pp)}
            extra["files"]["calib.txt"] = "the P0 line of KITTI sequence 03 (input, not written)"
        write_json(os.path.join(fixture_dir, "meta.json"), fixture_meta(frames, extra))
    result = {
        "dataset": dataset,
        "frames": frames,
        "seconds": elapsed,
        "fps": frames / elapsed,
        "final_position": positions[-1],
        "final_gt": gt[-1],
        "ate_rmse": ate,
        "opencv": cv2.__version__,
        "opencv_simd_lanes": opencv_lanes(),
        "ipp": bool(cv2.ipp.useIPP()),
    }
    if args.json:
        print(json.dumps(result))
    else:
        x, y, z = positions[-1]
        print("final position: x=%.4f y=%.4f z=%.4f (ground truth %.4f %.4f %.4f)" % (x, y, z, *gt[-1]))
        print("trajectory error (ATE RMSE, %d frames): %.4f m" % (frames, ate))
        print("%.2f frames/s (%.3f s for %d frames, OpenCV %s, %d lanes, IPP %s)"
              % (frames / elapsed, elapsed, frames, cv2.__version__, opencv_lanes(),
                 "on" if cv2.ipp.useIPP() else "off"))


if __name__ == "__main__":
    main()
