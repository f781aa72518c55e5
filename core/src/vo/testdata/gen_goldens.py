#!/usr/bin/env python3
"""Regenerates the VO goldens under core/src/vo/testdata from OpenCV 4.8.0.76
(opencv-contrib-python-headless==4.8.0.76, numpy<2).

Writes lk_prev.png / lk_next.png (a synthetic 320x240 pair: blurred noise and
its sub-pixel shift) and five_point_golden.txt (findEssentialMat on 5 points),
and prints Rust literals for lk.rs (calcOpticalFlowPyrLK) and the
ransac/recover_pose tests (findEssentialMat, recoverPose).
"""
import os
import sys

import cv2
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))


def f32bits(v):
    return "0x%08x" % np.float32(v).view(np.uint32)


def lk_pair():
    rs = np.random.RandomState(7)
    noise = rs.rand(240, 320).astype(np.float32)
    blur = cv2.GaussianBlur(noise, (0, 0), 3.0)
    blur = (blur - blur.min()) / (blur.max() - blur.min()) * 220 + 15
    prev = np.round(blur).astype(np.uint8)
    m = np.float32([[1, 0, -2.37], [0, 1, 1.61]])
    nxt = cv2.warpAffine(blur, m, (320, 240), flags=cv2.INTER_CUBIC, borderMode=cv2.BORDER_REFLECT_101)
    nxt = np.clip(np.round(nxt), 0, 255).astype(np.uint8)
    cv2.imwrite(os.path.join(HERE, "lk_prev.png"), prev)
    cv2.imwrite(os.path.join(HERE, "lk_next.png"), nxt)
    pts = []
    for gy in range(7):
        for gx in range(9):
            pts.append((12.25 + 37.0 * gx, 9.5 + 36.0 * gy))
    pts += [(-15.0, 100.0), (330.0, 20.0), (160.0, -30.0), (3.75, 236.5), (318.0, 2.0)]
    pts = np.float32(pts)
    prev = cv2.imread(os.path.join(HERE, "lk_prev.png"), 0)
    nxt = cv2.imread(os.path.join(HERE, "lk_next.png"), 0)
    out, st, err = cv2.calcOpticalFlowPyrLK(
        prev, nxt, pts, None, winSize=(21, 21),
        criteria=(cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 30, 0.01))
    print("// LK golden: (x, y) in, (x bits, y bits) out, status, err bits (status 1)")
    for p, o, s, e in zip(pts, out, st.ravel(), err.ravel()):
        print("    ([%r, %r], [%s, %s], %d, %s)," % (float(p[0]), float(p[1]), f32bits(o[0]), f32bits(o[1]),
                                                 int(s), f32bits(e) if s else "0x00000000"))


# ---- five-point (findEssentialMat on exactly 5 normalized points) ----
M=(1<<64)-1
def rodrigues(w):
    R,_=cv2.Rodrigues(np.array(w,np.float64)); return R
def scene(R,t,n,seed):
    s=seed
    def rnd():
        nonlocal s
        s=(s*6364136223846793005+1442695040888963407)&M
        return (s>>11)/float(1<<53)
    a=[];b=[]
    for _ in range(n):
        x1=np.array([rnd()*8-4, rnd()*4-2, 5+rnd()*20])
        x2=R@x1+np.array(t)
        a.append([x1[0]/x1[2],x1[1]/x1[2]]); b.append([x2[0]/x2[2],x2[1]/x2[2]])
    return np.array(a),np.array(b)
def skew(v): return np.array([[0,-v[2],v[1]],[v[2],0,-v[0]],[-v[1],v[0],0]])
cases=[([0.02,-0.05,0.01],[0.1,0.05,-1.0],11),([-0.1,0.2,0.05],[1.0,-0.2,0.3],12),([0.3,0.1,-0.2],[-0.4,0.8,0.5],13),([0.001,0.004,-0.002],[0.01,-0.02,1.0],14)]


FIVE_POINT_HEADER = """\
# Five-point goldens for vo/five_point.rs, written by gen_goldens.py: synthetic
# scenes (X2 = R·X1 + t, depths 5-25) and cv2.findEssentialMat(p1, p2, focal=1.0,
# pp=(0, 0), method=cv2.RANSAC) with exactly 5 points (4.8.0.76 wheel). One case
# a paragraph: the scene's rvec and t, the points p1 and p2 (x y x y ...), then
# every solution E of OpenCV's kernel in order, row-major.
"""


def five_point():
    """Writes five_point_golden.txt: a data file rather than Rust literals, so
    the numbers stay one line a row (repr: the test parses the same f64s)."""
    def row(key, values):
        return key + " " + " ".join(repr(float(v)) for v in values)
    paragraphs = []
    for w, t, seed in cases:
        R = rodrigues(w)
        a, b = scene(R, t, 5, seed)
        E, mask = cv2.findEssentialMat(a, b, focal=1.0, pp=(0., 0.), method=cv2.RANSAC, prob=0.999, threshold=1.0)
        k = E.shape[0] // 3
        lines = [row("rvec", w), row("t", t), row("p1", a.ravel()), row("p2", b.ravel())]
        lines += [row("E", E[3 * i:3 * i + 3].ravel()) for i in range(k)]
        paragraphs.append("\n".join(lines) + "\n")
    with open(os.path.join(HERE, "five_point_golden.txt"), "w", encoding="utf-8") as f:
        f.write(FIVE_POINT_HEADER + "\n".join(paragraphs))


# ---- RANSAC: pixel points of a scene with 60 outliers, KITTI intrinsics ----
F, CX, CY = 718.856, 607.1928, 185.2157


def lcg_scene(R, t, n, seed):
    """Mirrors ransac.rs tests::pixel_scene operation by operation (plain
    IEEE double arithmetic, left to right), so both sides get the same f32."""
    s = seed
    def rnd():
        nonlocal s
        s = (s * 6364136223846793005 + 1442695040888963407) & M
        return (s >> 11) / float(1 << 53)
    p1, p2 = [], []
    for _ in range(n):
        x1 = [rnd() * 8.0 - 4.0, rnd() * 4.0 - 2.0, 5.0 + rnd() * 20.0]
        x2 = [R[i][0] * x1[0] + R[i][1] * x1[1] + R[i][2] * x1[2] + t[i] for i in range(3)]
        p1.append([np.float32(x1[0] / x1[2] * F + CX), np.float32(x1[1] / x1[2] * F + CY)])
        p2.append([np.float32(x2[0] / x2[2] * F + CX), np.float32(x2[1] / x2[2] * F + CY)])
    return np.array(p1, np.float32), np.array(p2, np.float32)


# cv2.Rodrigues(np.array([0.005, -0.0316, 0.005])), as literals for both sides.
RANSAC_R = [[0.9994882647177734, -0.005078119343031715, -0.03158197896573382],
            [0.004920133148589171, 0.9999750021844237, -0.005078119343031715],
            [0.03160697678131018, 0.004920133148589171, 0.9994882647177734]]
RANSAC_T = [0.05, -0.02, -1.0]


def ransac():
    p1, p2 = lcg_scene(RANSAC_R, RANSAC_T, 300, 99)
    for i in range(0, 300, 5):
        p1[i, 0] = np.float32(p1[i, 0] + np.float32(15 + i % 25))
        p1[i, 1] = np.float32(p1[i, 1] - np.float32(20))
    E, mask = cv2.findEssentialMat(p1, p2, focal=F, pp=(CX, CY), method=cv2.RANSAC, prob=0.999, threshold=1.0)
    print("// RANSAC golden: E, inliers, outlier indices")
    print("    const OPENCV_E: [f64; 9] = [%s];" % ", ".join(repr(float(v)) for v in E.ravel()))
    print("    const OPENCV_INLIERS: usize = %d;" % int(mask.sum()))
    print("    const OPENCV_OUTLIERS: &[usize] = &[%s];" % ", ".join(str(i) for i in np.flatnonzero(mask.ravel() == 0)))
    n, R, t, pmask = cv2.recoverPose(E, p1, p2, focal=F, pp=(CX, CY))
    print("// recoverPose golden")
    print("    const OPENCV_POSE_INLIERS: usize = %d;" % n)
    print("    const OPENCV_R: [f64; 9] = [%s];" % ", ".join(repr(float(v)) for v in R.ravel()))
    print("    const OPENCV_T: [f64; 3] = [%s];" % ", ".join(repr(float(v)) for v in t.ravel()))


if __name__ == "__main__":
    what = sys.argv[1:] or ["lk", "five_point", "ransac"]
    if "lk" in what:
        lk_pair()
    if "five_point" in what:
        five_point()
    if "ransac" in what:
        ransac()
