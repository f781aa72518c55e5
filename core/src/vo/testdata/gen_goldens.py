#!/usr/bin/env python3
"""Regenerates the VO goldens under core/src/vo/testdata from OpenCV 4.8.0.76
(opencv-contrib-python-headless==4.8.0.76, numpy<2).

Writes lk_prev.png / lk_next.png (a synthetic 320x240 pair: blurred noise and
its sub-pixel shift) and prints Rust literals for lk.rs (calcOpticalFlowPyrLK),
five_point/ransac/recover_pose tests (findEssentialMat, recoverPose).
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


if __name__ == "__main__":
    lk_pair()
