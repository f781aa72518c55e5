#!/usr/bin/env python3
"""Trajectory metrics in numpy, the reference for `siftlab_core::vo::metrics::evaluate`
(`view_trajectory --metrics FILE`). Definitions (docs/fidelity.md §VO-9):

  ate_rmse            RMSE of position differences, no alignment
  ate_rmse_aligned    the same after the least-squares rigid alignment (Umeyama, no scale)
  rpe_trans_rmse      RMSE over i = 1..N-1 of |t(E_i)|, E_i = (G_{i-1}^-1 G_i)^-1 (S_{i-1}^-1 S_i)
  rpe_rot_rmse_deg    RMSE of angle(E_i) = arccos(clamp((tr R - 1) / 2)), in degrees
  kitti_t_err_pct, kitti_r_err_deg_per_100m
                      the KITTI devkit: start every 10th frame, lengths 100..800 m of true path,
                      last = first frame with dist > dist[first] + len,
                      E = (S_first^-1 S_last)^-1 (G_first^-1 G_last); mean |t(E)|/len (x100) and
                      angle(E)/len (deg per 100 m); null when no segment fits
  kitti_segments      how many (first, length) segments those means are over (0: none fits)

    python3 metrics_reference.py [--out tests/fixtures/metrics/reference.json]

Cases: the committed OpenCV trajectories on frames 0-150 (true path 110 m, so only a few 100 m
KITTI segments fit: the count says how many): "lk" (the lab's LK loop, tests/fixtures/vo_lk/) and
the three matcher-driven runs (tests/fixtures/vo_matched/); and "drift_300": the truth of frames
0-299 (252 m) times a made-up drift P_i = [Ry(0.002 i) | (0.01 i, -0.005 i, 0.03 i)], which has
segments of 100 and 200 m. Needs numpy.
"""
import argparse
import json
import os

import numpy as np

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def load_rows(path, n=None):
    rows = np.loadtxt(path).reshape(-1, 12)
    rows = rows if n is None else rows[:n]
    out = np.tile(np.eye(4), (len(rows), 1, 1))
    out[:, :3, :4] = rows.reshape(-1, 3, 4)
    return out


def angle(m):
    return float(np.arccos(np.clip(0.5 * (np.trace(m[:3, :3]) - 1.0), -1.0, 1.0)))


def ate(ep, gp):
    return float(np.sqrt(np.mean(np.sum((ep - gp) ** 2, axis=1))))


def aligned_ate(ep, gp):
    me, mg = ep.mean(axis=0), gp.mean(axis=0)
    h = (gp - mg).T @ (ep - me)
    u, _s, vt = np.linalg.svd(h)
    d = np.diag([1.0, 1.0, np.sign(np.linalg.det(u @ vt)) or 1.0])
    r = u @ d @ vt
    return ate((r @ ep.T).T + (mg - r @ me), gp)


def metrics(s, g):
    inv = np.linalg.inv
    ep, gp = s[:, :3, 3], g[:, :3, 3]
    te, re = [], []
    for i in range(1, len(s)):
        e = inv(inv(g[i - 1]) @ g[i]) @ (inv(s[i - 1]) @ s[i])
        te.append(np.linalg.norm(e[:3, 3]))
        re.append(angle(e))
    dist = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(gp, axis=0), axis=1))])
    kt, kr = [], []
    for first in range(0, len(g), 10):
        for length in range(100, 900, 100):
            beyond = np.nonzero(dist[first:] > dist[first] + length)[0]
            if len(beyond) == 0:
                continue
            last = first + int(beyond[0])
            e = inv(inv(s[first]) @ s[last]) @ (inv(g[first]) @ g[last])
            kt.append(np.linalg.norm(e[:3, 3]) / length)
            kr.append(angle(e) / length)
    return {
        "frames": len(s),
        "ate_rmse": ate(ep, gp),
        "ate_rmse_aligned": aligned_ate(ep, gp),
        "rpe_trans_rmse": float(np.sqrt(np.mean(np.square(te)))),
        "rpe_rot_rmse_deg": float(np.degrees(np.sqrt(np.mean(np.square(re))))),
        "kitti_t_err_pct": float(100 * np.mean(kt)) if kt else None,
        "kitti_r_err_deg_per_100m": float(np.degrees(np.mean(kr)) * 100) if kr else None,
        "kitti_segments": len(kt),
    }


def drift(g):
    s = g.copy()
    for i in range(len(g)):
        a = 0.002 * i
        p = np.eye(4)
        p[:3, :3] = [[np.cos(a), 0, np.sin(a)], [0, 1, 0], [-np.sin(a), 0, np.cos(a)]]
        p[:3, 3] = [0.01 * i, -0.005 * i, 0.03 * i]
        s[i] = g[i] @ p
    return s


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", default=os.path.join(REPO, "tests", "fixtures", "metrics", "reference.json"))
    a = ap.parse_args()
    poses = os.path.join(REPO, "www", "demo", "MyKITTI", "poses", "00.txt")
    cases = {}
    runs = [("lk", os.path.join("vo_lk", "poses.txt"))] + \
        [(name, os.path.join("vo_matched", name + ".txt")) for name in ("dt_200", "nn", "nndr_0.8")]
    for name, rel in runs:
        s = load_rows(os.path.join(REPO, "tests", "fixtures", rel))
        cases[name] = metrics(s, load_rows(poses, len(s)))
    g = load_rows(poses, 300)
    cases["drift_300"] = metrics(drift(g), g)
    # One case a line, so the Rust test reads it without a JSON library.
    text = "{\n" + ",\n".join('"%s": %s' % (k, json.dumps(v)) for k, v in cases.items()) + "\n}\n"
    with open(a.out, "w") as f:
        f.write(text)
    print(text, end="")


if __name__ == "__main__":
    main()
