#!/usr/bin/env python3
"""Reference drawings from OpenCV 4.8.0.76 for the render unit tests.

Run: python3 gen_refs.py  (opencv-contrib-python-headless==4.8.0.76, numpy<2).
Writes small PNGs next to this script; each drawing starts from a fresh
process where it depends on cv::theRNG (the lab runs one drawMatchesKnn per
process), so the random colours are the lab's.
"""
import os
import subprocess
import sys

import cv2
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))


def frames():
    y, x = np.mgrid[0:60, 0:80]
    a = ((x * 3 + y * 2) % 256).astype(np.uint8)
    b = ((x * 2 + y * 5 + 40) % 256).astype(np.uint8)
    return a, b


def knn():
    a, b = frames()
    kp1 = [cv2.KeyPoint(20.3, 30.7, 5), cv2.KeyPoint(1.2, 2.6, 5), cv2.KeyPoint(77.9, 58.6, 5)]
    kp2 = [cv2.KeyPoint(60.6, 10.4, 5), cv2.KeyPoint(0.4, 57.5, 5), cv2.KeyPoint(33.25, 29.75, 5)]
    m = [[cv2.DMatch(0, 2, 1.0), cv2.DMatch(0, 0, 2.0), cv2.DMatch(0, 1, 3.0)],
         [cv2.DMatch(1, 1, 1.0)], [], [cv2.DMatch(2, 0, 5.0)]]
    out = cv2.drawMatchesKnn(a, kp1, b, kp2, m, None, flags=2)
    cv2.imwrite(os.path.join(HERE, "knn.png"), out)


def prims():
    a, _ = frames()
    img = cv2.cvtColor(a, cv2.COLOR_GRAY2BGR)
    # LINE_AA lines with 4 fractional bits, every octant, some off the edges.
    segs = [((5, 7), (1200, 300)), ((1000, 900), (80, 20)), ((300, 40), (310, 900)),
            ((1270, 10), (-40, 950)), ((-100, 500), (2000, 480)), ((640, 480), (640, 481))]
    for i, (p, q) in enumerate(segs):
        cv2.line(img, p, q, (30 * i, 255 - 40 * i, 90), 1, cv2.LINE_AA, 4)
    cv2.imwrite(os.path.join(HERE, "lines_aa.png"), img)
    img = cv2.cvtColor(a, cv2.COLOR_GRAY2BGR)
    for i, c in enumerate([(325, 491), (8, 8), (1260, 950), (640, 300)]):
        cv2.circle(img, c, 48, (0, 40 * i, 255 - 50 * i), 1, cv2.LINE_AA, 4)
    cv2.imwrite(os.path.join(HERE, "circles_aa.png"), img)
    img = cv2.cvtColor(a, cv2.COLOR_GRAY2BGR)
    for c in [(20, 30), (75, 2), (50, 45)]:
        cv2.circle(img, c, 10, (0, 255, 0), 2)
    cv2.imwrite(os.path.join(HERE, "circles_thick2.png"), img)


def traj():
    """The lab's showDrive loop (truth from the fixture poses, a made-up
    estimate) on its 600x600 canvas; the caption text is Hershey, which the
    Rust side does not reproduce, so tests skip the band rows 20..60."""
    poses = os.path.join(HERE, "..", "..", "..", "..", "tests", "fixtures", "synthetic", "poses", "00.txt")
    traj = np.zeros((600, 600, 3), dtype=np.uint8)
    for i, line in enumerate(open(poses)):
        v = [float(s) for s in line.split()]
        tx, tz = v[3], v[11]
        x, y, z = tx * 0.9 - i * 0.05, v[7], tz * 0.97
        draw_x, draw_y = int(x) + 290, int(z) + 90
        true_x, true_y = int(tx) + 290, int(tz) + 90
        cv2.circle(traj, (draw_x, draw_y), 1, (0, 0, 255), 1)
        cv2.circle(traj, (true_x, true_y), 1, (0, 255, 0), 1)
        cv2.rectangle(traj, (10, 20), (600, 60), (0, 0, 0), -1)
        text = "Coordinates: x=%2fm y=%2fm z=%2fm" % (x, y, z)
        cv2.putText(traj, text, (20, 40), cv2.FONT_HERSHEY_PLAIN, 1, (255, 255, 255), 1, 8)
    cv2.imwrite(os.path.join(HERE, "trajectory_lab.png"), traj)


if __name__ == "__main__":
    if len(sys.argv) > 1:
        {"knn": knn, "prims": prims, "traj": traj}[sys.argv[1]]()
    else:
        assert cv2.__version__ == "4.8.0", cv2.__version__
        for what in ("knn", "prims", "traj"):
            subprocess.run([sys.executable, os.path.abspath(__file__), what], check=True)
