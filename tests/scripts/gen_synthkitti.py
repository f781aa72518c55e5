#!/usr/bin/env python3
"""Deterministic synthetic stand-in for KITTI odometry sequence 00 (monocular, left gray camera).

Writes the lab's MyKITTI layout:

    DIR/gray/00/image_0/000000.png ...   1241x376 8-bit gray PNG
    DIR/poses/00.txt                     KITTI poses: camera-to-world [R|t], 12 numbers a line

The real KITTI data (CC BY-NC-SA 3.0) cannot be shipped or fetched here, so this renders a
street scene procedurally: a camera 1.65 m above a road plane drives ~1 m/frame along a gentle
right-hand curve between rows of textured buildings, parked cars and poles. Every texture is a
function of world (surface) coordinates, so frames are mutually consistent and SIFT, LK,
findEssentialMat and recoverPose behave as on a real drive. Rendering is per-pixel ray casting
in numpy with 2x2 supersampling plus analytic, distance-aware band limiting (no aliasing
shimmer for LK), then mild seeded Gaussian sensor noise.

The output is a pure function of (--seed, frame index): same numpy => same bytes.

Usage: gen_synthkitti.py --out DIR [--frames 100] [--seed 0] [--first 0] [--last N-1]
"""
from __future__ import annotations

import argparse
import os
import sys
import time

import numpy as np

# KITTI 00 camera (P0), as used by the lab's VO.
FX = FY = 718.856
CX, CY = 607.1928, 185.2157
W, H = 1241, 376
CAM_HEIGHT = 1.65  # world y is down, so the road plane is y = +1.65
SS = 2  # supersampling factor per axis

# Trajectory: arc length per frame and the heading (yaw) as a function of arc length.
YAW_TOTAL = 0.32  # rad (~18 deg) of right-hand turn spread over s in [YAW_S0, YAW_S1]
YAW_S0, YAW_S1 = 12.0, 80.0


def smoothstep(a, b, x):
    t = np.clip((np.asarray(x, dtype=np.float64) - a) / (b - a), 0.0, 1.0)
    return t * t * (3.0 - 2.0 * t)


def yaw_of_s(s):
    return YAW_TOTAL * smoothstep(YAW_S0, YAW_S1, s)


class Path:
    """Centre line of the road: x(s), z(s) integrated from the heading with a fine fixed step."""

    def __init__(self, s_min=-40.0, s_max=320.0, ds=0.01):
        # integer grid so that s = 0 is a sample exactly (frame 0 must be the identity pose)
        self.s = np.arange(int(round(s_min / ds)), int(round(s_max / ds)) + 1) * ds
        yaw = yaw_of_s(self.s)
        # trapezoid integration of (sin yaw, cos yaw), anchored at s = 0 -> (0, 0)
        dx = np.concatenate([[0.0], np.cumsum(0.5 * (np.sin(yaw[1:]) + np.sin(yaw[:-1])) * ds)])
        dz = np.concatenate([[0.0], np.cumsum(0.5 * (np.cos(yaw[1:]) + np.cos(yaw[:-1])) * ds)])
        i0 = int(round(-s_min / ds))
        self.x = dx - dx[i0]
        self.z = dz - dz[i0]
        self.yaw = yaw

    def at(self, s):
        return (np.interp(s, self.s, self.x), np.interp(s, self.s, self.z), float(yaw_of_s(s)))


def rot_y(a):
    c, s = np.cos(a), np.sin(a)
    # rotates camera +z (forward) towards +x (right) for a > 0
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def rot_x(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def trajectory(n_frames: int, path: Path):
    """Camera-to-world poses (R, t) per frame; frame 0 is the identity."""
    poses = []
    s = 0.0
    for i in range(n_frames):
        x, z, yaw = path.at(s)
        # small pitch/roll wobble and a little heading jitter, like a real car body
        pitch = 0.004 * np.sin(2 * np.pi * i / 23.0) * (i > 0)
        roll = 0.002 * np.sin(2 * np.pi * i / 31.0 + 1.0) * (i > 0)
        dyaw = 0.003 * np.sin(2 * np.pi * i / 17.0) * (i > 0)
        bounce = 0.01 * np.sin(2 * np.pi * i / 11.0) * (i > 0)
        Rz = np.array([[np.cos(roll), -np.sin(roll), 0.0], [np.sin(roll), np.cos(roll), 0.0], [0.0, 0.0, 1.0]])
        R = rot_y(yaw + dyaw) @ rot_x(pitch) @ Rz
        t = np.array([x, bounce, z])
        poses.append((R, t))
        # speed 0.8 .. 1.2 m/frame, smooth
        s += 1.0 + 0.18 * np.sin(2 * np.pi * i / 41.0 + 0.5) + 0.04 * np.sin(2 * np.pi * i / 7.0)
    return poses


# ---------------------------------------------------------------------------------------------
# Scene: oriented boxes (rotation about y only) standing on the road plane.
# ---------------------------------------------------------------------------------------------
KIND_BUILDING, KIND_CAR, KIND_POLE, KIND_WALL = 0, 1, 2, 3


def build_scene(path: Path, seed: int, s_end: float):
    rng = np.random.default_rng([seed, 1])
    boxes = []  # (cx, cy, cz, hx, hy, hz, yaw, kind, albedo, p1, p2, p3)

    def place(s_mid, lateral, hx, hy, hz, kind, albedo, p1=0.0, p2=0.0, p3=0.0, yaw_off=0.0):
        x, z, yaw = path.at(s_mid)
        # lateral offset to the right (+) of the heading
        nx, nz = np.cos(yaw), -np.sin(yaw)
        cx, cz = x + lateral * nx, z + lateral * nz
        cy = CAM_HEIGHT - hy  # bottom on the ground
        boxes.append((cx, cy, cz, hx, hy, hz, yaw + yaw_off, kind, albedo, p1, p2, p3))

    for side in (-1.0, 1.0):
        # front row of buildings with gaps, a back row to fill the gaps
        for row, (set0, set1, gap_max) in enumerate(((7.0, 9.5, 4.0), (17.0, 22.0, 1.0))):
            s = -30.0 + rng.uniform(0, 5)
            while s < s_end:
                length = rng.uniform(6.0, 14.0) if row == 0 else rng.uniform(10.0, 20.0)
                depth = rng.uniform(4.0, 9.0)
                height = rng.uniform(4.0, 13.0) if row == 0 else rng.uniform(10.0, 22.0)
                setback = rng.uniform(set0, set1)
                albedo = rng.uniform(0.35, 0.85)
                # window grid: horizontal pitch, vertical pitch, style seed
                place(s + length / 2, side * (setback + depth / 2), depth / 2, height / 2, length / 2,
                      KIND_BUILDING, albedo, rng.uniform(2.2, 3.6), rng.uniform(2.8, 3.4), rng.uniform(0, 1000),
                      yaw_off=rng.uniform(-0.04, 0.04))
                s += length + rng.uniform(0.3, gap_max)
        # parked cars along the kerb
        s = -20.0 + rng.uniform(0, 6)
        while s < s_end:
            if rng.uniform() < 0.55:
                place(s + 2.2, side * rng.uniform(3.6, 4.2), 0.9, 0.72, 2.15, KIND_CAR,
                      rng.uniform(0.15, 0.9), rng.uniform(0, 1000), 0.0, 0.0, yaw_off=rng.uniform(-0.05, 0.05))
            s += rng.uniform(5.0, 9.0)
        # poles / tree trunks on the pavement
        s = -20.0 + rng.uniform(0, 10)
        while s < s_end:
            place(s, side * rng.uniform(5.2, 6.2), 0.15, rng.uniform(2.5, 4.5), 0.15, KIND_POLE,
                  rng.uniform(0.2, 0.7), rng.uniform(0, 1000))
            s += rng.uniform(8.0, 20.0)
        # low garden walls in the building gaps
        s = -25.0 + rng.uniform(0, 10)
        while s < s_end:
            L = rng.uniform(3.0, 10.0)
            place(s + L / 2, side * rng.uniform(6.4, 6.9), 0.15, rng.uniform(0.5, 1.1), L / 2, KIND_WALL,
                  rng.uniform(0.4, 0.8), rng.uniform(0, 1000))
            s += L + rng.uniform(4.0, 25.0)
    return np.array(boxes, dtype=np.float64)


# ---------------------------------------------------------------------------------------------
# Textures (functions of surface coordinates in metres)
# ---------------------------------------------------------------------------------------------
class Noise:
    """Value noise from a seeded lattice table.

    The lattice (N x N cells, wrapping) is upsampled once by UP with bicubic interpolation, so a
    sample is a single bilinear lookup into a smooth table (cv2.remap, much faster than numpy
    gathers)."""

    N = 128
    UP = 8

    def __init__(self, seed: int):
        import cv2

        rng = np.random.default_rng([seed, 2])
        N, UP = self.N, self.UP
        table = rng.random((N, N), dtype=np.float32) * 2.0 - 1.0
        tiled = np.tile(table, (3, 3))
        up = cv2.resize(tiled, (3 * N * UP, 3 * N * UP), interpolation=cv2.INTER_CUBIC)
        # cubic resize places sample k at (k + 0.5) / UP - 0.5 in lattice units; crop one period
        self.up = np.ascontiguousarray(up[N * UP:2 * N * UP, N * UP:2 * N * UP])
        self.hash = rng.integers(0, 2**31 - 1, size=(1 << 16,), dtype=np.int64)
        h = self.hash
        # per-hash blob parameters: centre inside the cell, radius (cells), sign (0 = no blob)
        self.b_cx = (0.3 + 0.4 * (h & 1023) / 1023.0).astype(np.float32)
        self.b_cy = (0.3 + 0.4 * ((h >> 10) & 1023) / 1023.0).astype(np.float32)
        self.b_r = (0.08 + 0.16 * ((h >> 20) & 255) / 255.0).astype(np.float32)
        hs = (h >> 28) & 3
        self.b_amp = np.where(hs == 1, 0.0, np.where(hs >= 2, 1.0, -1.0)).astype(np.float32)
        self._cv2 = cv2

    def value(self, u, v, freq, off=0.0):
        """Smooth noise in about [-1, 1] with `freq` lattice cells per metre."""
        cv2 = self._cv2
        span = float(self.N * self.UP)
        mx = np.mod((u * freq + off) * self.UP, span).astype(np.float32)
        my = np.mod((v * freq + off * 1.618) * self.UP, span).astype(np.float32)
        n = mx.size
        cols = 1024
        rows = (n + cols - 1) // cols
        pad = rows * cols - n
        if pad:
            mx = np.concatenate([mx.ravel(), np.zeros(pad, np.float32)])
            my = np.concatenate([my.ravel(), np.zeros(pad, np.float32)])
        out = cv2.remap(self.up, mx.reshape(rows, cols), my.reshape(rows, cols), cv2.INTER_LINEAR,
                        borderMode=cv2.BORDER_WRAP)
        return out.ravel()[:n].reshape(u.shape)

    def cell_index(self, iu, iv, salt):
        # int32 arithmetic wraps, which is all a hash needs
        iu = iu.astype(np.int32)
        iv = iv.astype(np.int32)
        return ((iu * np.int32(73856093)) ^ (iv * np.int32(19349663)) ^ np.int32(salt)) & 0xFFFF

    def cell_hash(self, iu, iv, salt):
        return self.hash[self.cell_index(iu, iv, salt)]

    def blobs(self, u, v, cell, fp, salt):
        """Sparse soft discs (at most one per lattice cell, inside it): SIFT's favourite structure."""
        inv = np.float32(1.0 / cell)
        fu = u * inv
        fv = v * inv
        iu = np.floor(fu)
        iv = np.floor(fv)
        k = self.cell_index(iu, iv, salt)
        dx = fu - iu - self.b_cx[k]
        dy = fv - iv - self.b_cy[k]
        dist = np.sqrt(dx * dx + dy * dy)
        # anti-aliased edge: transition width = footprint in cells
        w = np.maximum(fp * inv, np.float32(0.02))
        m = np.clip((self.b_r[k] - dist) / w + np.float32(0.5), 0.0, 1.0)
        return m * self.b_amp[k]


def band(freq, fp):
    """Weight of a texture component of `freq` cycles/m at footprint fp m/pixel (kills aliasing)."""
    return np.clip(1.6 - 3.2 * freq * fp, 0.0, 1.0)


def soft_rect(fu, fv, u0, u1, v0, v1, wu, wv):
    """Anti-aliased indicator of [u0,u1]x[v0,v1] on cell-fraction coordinates."""
    a = np.clip(np.minimum(fu - u0, u1 - fu) / wu + 0.5, 0.0, 1.0)
    b = np.clip(np.minimum(fv - v0, v1 - fv) / wv + 0.5, 0.0, 1.0)
    return a * b


def add_layer(acc, amp, freq, fp, fn, u, v, *args):
    """acc += amp * band(freq, fp) * fn(u, v, *args), evaluated only where the band is open
    (fine layers vanish with distance, so most pixels skip them)."""
    w = band(freq, fp)
    on = w > 0
    n_on = int(np.count_nonzero(on))
    if n_on == 0:
        return
    if n_on > 0.7 * on.size:
        acc += amp * w * fn(u, v, *args)
    else:
        idx = np.flatnonzero(on)
        acc[idx] += amp * w[idx] * fn(u[idx], v[idx], *args)


def multiscale(noise, acc, amp, u, v, fp, base_freq, octaves, gain, off):
    f = base_freq
    for k in range(octaves):
        add_layer(acc, amp, f, fp, noise.value, u, v, f, off + 17.3 * k)
        amp *= gain
        f *= 2.0


def blob_layer(noise, acc, amp, u, v, cell, fp, salt):
    w = band(1.0 / cell, fp)
    idx = np.flatnonzero(w > 0)
    if idx.size == 0:
        return
    acc[idx] += amp * w[idx] * noise.blobs(u[idx], v[idx], cell, fp[idx], salt)


def tex_ground(noise, x, z, fp):
    # asphalt: multi-scale noise plus blotches, patches, gravel and spots at several scales
    g = np.full_like(x, 0.42)
    multiscale(noise, g, 0.12, x, z, fp, 0.2, 6, 0.75, 3.0)
    blob_layer(noise, g, 0.12, x, z, 2.0, fp, 11)
    blob_layer(noise, g, 0.12, x + 0.3, z, 0.7, fp, 12)
    blob_layer(noise, g, 0.12, x, z + 0.1, 0.3, fp, 13)
    blob_layer(noise, g, 0.14, x + 0.05, z, 0.13, fp, 14)
    blob_layer(noise, g, 0.14, x, z + 0.02, 0.06, fp, 15)
    return g


def tex_facade(noise, u, v, fp, albedo, pu, pv, style, kind):
    """u: horizontal metres along the face, v: metres up from the ground."""
    g = albedo.copy()
    us = u + style
    multiscale(noise, g, 0.12, us, v, fp, 0.3, 6, 0.75, 7.0)
    blob_layer(noise, g, 0.12, us, v, 2.5, fp, 22)
    blob_layer(noise, g, 0.14, us, v, 0.9, fp, 21)
    blob_layer(noise, g, 0.14, us, v + 0.2, 0.4, fp, 23)
    blob_layer(noise, g, 0.16, us + 0.05, v, 0.18, fp, 24)
    blob_layer(noise, g, 0.16, us, v + 0.03, 0.08, fp, 25)
    is_b = kind == KIND_BUILDING
    if np.any(is_b):
        fu = (u + style) / pu
        fv = (v - 0.4) / pv
        cu = fu - np.floor(fu)
        cv = fv - np.floor(fv)
        wu = np.maximum(fp / pu, 1e-3)
        wv = np.maximum(fp / pv, 1e-3)
        # window frame (light) and glass (dark, varying per window)
        frame = soft_rect(cu, cv, 0.22, 0.78, 0.2, 0.82, wu, wv)
        glass = soft_rect(cu, cv, 0.27, 0.73, 0.26, 0.76, wu, wv)
        hsh = noise.cell_hash(np.floor(fu), np.floor(fv), 31)
        shade = ((hsh & 255) / 255.0).astype(np.float32)
        lit = ((hsh >> 8) & 7) == 0
        win = frame * 0.18 - glass * (0.18 + 0.3 * (1.0 - shade)) + glass * lit * 0.45
        keep = (v > 1.2) & ((hsh >> 12) & 15 != 0)  # no windows at street level, some missing
        g = g + np.where(is_b & keep, win * band(1 / pu, fp * 0.5), 0.0)
        # a horizontal ledge per floor
        lv = (v - 0.4) / pv
        ledge = soft_rect(np.zeros_like(v) + 0.5, lv - np.floor(lv), 0.0, 1.0, 0.0, 0.06, 1.0, wv)
        g = g + np.where(is_b, 0.08 * ledge, 0.0)
    is_car = kind == KIND_CAR
    if np.any(is_car):
        # dark window band and wheel-height skirt
        band_w = soft_rect(np.zeros_like(v) + 0.5, v, 0.0, 1.0, 0.85, 1.3, 1.0, np.maximum(fp, 1e-3))
        g = g - np.where(is_car, 0.25 * band_w, 0.0)
        skirt = np.clip((0.35 - v) / np.maximum(fp, 1e-3) + 0.5, 0, 1)
        g = g - np.where(is_car, 0.15 * skirt, 0.0)
    return g


# ---------------------------------------------------------------------------------------------
# Ray casting
# ---------------------------------------------------------------------------------------------
SUN = np.array([0.45, -0.75, 0.35])
SUN = SUN / np.linalg.norm(SUN)


class Renderer:
    def __init__(self, seed: int, n_frames: int):
        self.seed = seed
        self.path = Path()
        self.poses = trajectory(n_frames, self.path)
        s_end = 160.0 + 1.25 * n_frames
        self.boxes = build_scene(self.path, seed, s_end)
        self.noise = Noise(seed)
        # supersampled pixel grid in camera coordinates (direction z = 1)
        xs = (np.arange(W * SS, dtype=np.float64) + 0.5) / SS - 0.5
        ys = (np.arange(H * SS, dtype=np.float64) + 0.5) / SS - 0.5
        self.dxc = ((xs - CX) / FX).astype(np.float32)
        self.dyc = ((ys - CY) / FY).astype(np.float32)

    def box_corners(self, b):
        cx, cy, cz, hx, hy, hz, yaw = b[:7]
        c, s = np.cos(yaw), np.sin(yaw)
        pts = []
        for sx in (-1, 1):
            for sy in (-1, 1):
                for sz in (-1, 1):
                    lx, ly, lz = sx * hx, sy * hy, sz * hz
                    pts.append((cx + c * lx + s * lz, cy + ly, cz - s * lx + c * lz))
        return np.array(pts)

    def screen_rect(self, corners_cam):
        """Supersampled pixel rectangle covering the box (clipped against z = near)."""
        near = 0.05
        edges = [(i, j) for i in range(8) for j in range(i + 1, 8) if bin(i ^ j).count("1") == 1]
        pts = [p for p in corners_cam if p[2] >= near]
        for i, j in edges:
            a, b = corners_cam[i], corners_cam[j]
            if (a[2] - near) * (b[2] - near) < 0:
                t = (near - a[2]) / (b[2] - a[2])
                pts.append(a + t * (b - a))
        if not pts:
            return None
        pts = np.array(pts)
        u = (FX * pts[:, 0] / pts[:, 2] + CX + 0.5) * SS - 0.5
        v = (FY * pts[:, 1] / pts[:, 2] + CY + 0.5) * SS - 0.5
        c0 = max(int(np.floor(u.min())) - 1, 0)
        c1 = min(int(np.ceil(u.max())) + 2, W * SS)
        r0 = max(int(np.floor(v.min())) - 1, 0)
        r1 = min(int(np.ceil(v.max())) + 2, H * SS)
        if c0 >= c1 or r0 >= r1:
            return None
        return r0, r1, c0, c1

    def render(self, i: int) -> np.ndarray:
        R, t = self.poses[i]
        Rf = R.astype(np.float32)
        hs, ws = H * SS, W * SS
        dxc = self.dxc[None, :]
        dyc = self.dyc[:, None]
        # world ray directions (not normalised; camera z component = 1)
        dwx = Rf[0, 0] * dxc + Rf[0, 1] * dyc + Rf[0, 2]
        dwy = Rf[1, 0] * dxc + Rf[1, 1] * dyc + Rf[1, 2]
        dwz = Rf[2, 0] * dxc + Rf[2, 1] * dyc + Rf[2, 2]
        ox, oy, oz = (float(v) for v in t)

        tbest = np.full((hs, ws), np.inf, dtype=np.float32)
        hit = np.full((hs, ws), -1, dtype=np.int32)  # -1 sky, -2 ground, >=0 box index
        face = np.zeros((hs, ws), dtype=np.int8)  # 0: +-x (local), 1: +-z, 2: top
        fsign = np.zeros((hs, ws), dtype=np.int8)

        with np.errstate(divide="ignore", invalid="ignore"):
            tg = (CAM_HEIGHT - oy) / dwy
        gm = (dwy > 1e-6) & (tg > 0)
        tbest[gm] = tg[gm]
        hit[gm] = -2

        # visible boxes, nearest first, so boxes hidden behind nearer ones are skipped whole
        todo = []
        for bi, b in enumerate(self.boxes):
            cx, cy, cz = b[0], b[1], b[2]
            if np.hypot(cx - ox, cz - oz) > 170.0:
                continue
            cc = (self.box_corners(b) - t) @ R  # world -> camera (R^T (p - t))
            if np.all(cc[:, 2] < 0.05):
                continue
            rect = self.screen_rect(cc)
            if rect is None:
                continue
            # ray parameter = camera depth, and depth is linear: the box's minimum is at a corner
            todo.append((max(float(cc[:, 2].min()), 0.0), bi, rect))
        todo.sort()
        for zmin, bi, rect in todo:
            b = self.boxes[bi]
            cx, cy, cz, hx, hy, hz, yaw = b[:7]
            r0, r1, c0, c1 = rect
            if tbest[r0:r1, c0:c1].max() <= zmin:
                continue
            c, s = np.float32(np.cos(yaw)), np.float32(np.sin(yaw))
            sx_ = dwx[r0:r1, c0:c1]
            sy_ = dwy[r0:r1, c0:c1]
            sz_ = dwz[r0:r1, c0:c1]
            # ray in box-local coordinates (inverse of the yaw rotation)
            lox = np.float32(np.cos(yaw) * (ox - cx) - np.sin(yaw) * (oz - cz))
            loz = np.float32(np.sin(yaw) * (ox - cx) + np.cos(yaw) * (oz - cz))
            loy = np.float32(oy - cy)
            ldx = c * sx_ - s * sz_
            ldz = s * sx_ + c * sz_
            ldy = sy_
            with np.errstate(divide="ignore", invalid="ignore"):
                inv = 1.0 / ldx
                t1 = (-hx - lox) * inv
                t2 = (hx - lox) * inv
                tnx = np.minimum(t1, t2)
                tfx = np.maximum(t1, t2)
                inv = 1.0 / ldz
                t1 = (-hz - loz) * inv
                t2 = (hz - loz) * inv
                tnz = np.minimum(t1, t2)
                tfz = np.maximum(t1, t2)
                inv = 1.0 / ldy
                t1 = (-hy - loy) * inv
                t2 = (hy - loy) * inv
                tny = np.minimum(t1, t2)
                tfy = np.maximum(t1, t2)
            tn = np.maximum(np.maximum(tnx, tnz), tny)
            tf = np.minimum(np.minimum(tfx, tfz), tfy)
            tb = tbest[r0:r1, c0:c1]
            m = (tn <= tf) & (tn > 0) & (tn < tb)
            if not np.any(m):
                continue
            tb[m] = tn[m]
            hit[r0:r1, c0:c1][m] = bi
            fc = np.where(tn == tnx, 0, np.where(tn == tnz, 1, 2)).astype(np.int8)
            face[r0:r1, c0:c1][m] = fc[m]
            sg = np.where(fc == 0, np.sign(-ldx), np.where(fc == 1, np.sign(-ldz), 1)).astype(np.int8)
            fsign[r0:r1, c0:c1][m] = sg[m]

        img = np.empty((hs, ws), dtype=np.float32)
        dnorm = np.sqrt(dwx * dwx + dwy * dwy + dwz * dwz)
        pix_ang = 1.0 / (FX * SS) * SS  # footprint measured in output pixels

        # sky
        sk = hit == -1
        if np.any(sk):
            elev = -dwy[sk] / dnorm[sk]
            sx = dwx[sk] / np.maximum(elev + 0.3, 0.05)
            sz = dwz[sk] / np.maximum(elev + 0.3, 0.05)
            img[sk] = 0.80 + 0.10 * np.clip(elev * 3, 0, 1) + 0.04 * self.noise.value(sx * 10, sz * 10, 0.2, 5.0)

        # ground
        gm = hit == -2
        if np.any(gm):
            tt = tbest[gm]
            x = ox + tt * dwx[gm]
            z = oz + tt * dwz[gm]
            dist = tt * dnorm[gm]
            cosi = np.maximum(dwy[gm] / dnorm[gm], 0.02)
            fp = dist * pix_ang / np.sqrt(cosi)  # geometric mean of the anisotropic footprint
            alb = tex_ground(self.noise, x.astype(np.float32), z.astype(np.float32), fp)
            # soft contact shadows of the buildings would need shadow rays; keep flat lighting
            img[gm] = alb * (0.55 + 0.45 * max(-SUN[1], 0))

        # boxes
        bm = hit >= 0
        if np.any(bm):
            ids = hit[bm]
            B = self.boxes
            tt = tbest[bm]
            px = ox + tt * dwx[bm]
            py = oy + tt * dwy[bm]
            pz = oz + tt * dwz[bm]
            cx, cy, cz = B[ids, 0].astype(np.float32), B[ids, 1].astype(np.float32), B[ids, 2].astype(np.float32)
            hx, hy, hz = B[ids, 3].astype(np.float32), B[ids, 4].astype(np.float32), B[ids, 5].astype(np.float32)
            yaw = B[ids, 6]
            c = np.cos(yaw).astype(np.float32)
            s = np.sin(yaw).astype(np.float32)
            lx = c * (px - cx) - s * (pz - cz)
            lz = s * (px - cx) + c * (pz - cz)
            ly = py - cy
            fc = face[bm]
            sg = fsign[bm].astype(np.float32)
            # surface coordinates: u horizontal along the face, v height above the ground
            u = np.where(fc == 0, lz * sg, np.where(fc == 1, -lx * sg, lx))
            u = u + np.where(fc == 0, 0.0, 500.0 + 50.0 * sg)  # different faces, different textures
            v = np.where(fc == 2, lz, hy - ly)
            # normal (world) for lighting and footprint
            nlx = np.where(fc == 0, sg, 0.0)
            nlz = np.where(fc == 1, sg, 0.0)
            nwx = c * nlx + s * nlz
            nwz = -s * nlx + c * nlz
            nwy = np.where(fc == 2, -1.0, 0.0)
            dn = dnorm[bm]
            cosi = np.abs(nwx * dwx[bm] + nwy * dwy[bm] + nwz * dwz[bm]) / dn
            dist = tt * dn
            fp = dist * pix_ang / np.sqrt(np.maximum(cosi, 0.02))
            kind = B[ids, 7].astype(np.int32)
            albedo = B[ids, 8].astype(np.float32)
            p1 = B[ids, 9].astype(np.float32)
            p2 = B[ids, 10].astype(np.float32)
            p3 = B[ids, 11].astype(np.float32)
            pu = np.where(kind == KIND_BUILDING, p1, 3.0).astype(np.float32)
            pv = np.where(kind == KIND_BUILDING, p2, 3.0).astype(np.float32)
            style = np.where(kind == KIND_BUILDING, p3, p1).astype(np.float32)
            alb = tex_facade(self.noise, u.astype(np.float32), v.astype(np.float32), fp, albedo, pu, pv, style, kind)
            lam = np.maximum(-(nwx * SUN[0] + nwy * SUN[1] + nwz * SUN[2]), 0.0)
            img[bm] = alb * (0.5 + 0.5 * lam)

        # 2x2 box filter down to the output resolution
        img = img.reshape(H, SS, W, SS).mean(axis=(1, 3))
        return img

    def frame_u8(self, i: int) -> np.ndarray:
        img = self.render(i) * 255.0
        rng = np.random.default_rng([self.seed, 3, i])
        img = img + rng.normal(0.0, 0.5, size=img.shape)
        return np.clip(np.rint(img), 0, 255).astype(np.uint8)


def pose_line(R, t) -> str:
    m = np.hstack([R, t.reshape(3, 1)])
    return " ".join("%.9e" % (v + 0.0) for v in m.ravel())


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", required=True, help="dataset root (gets gray/00/image_0 and poses/00.txt)")
    ap.add_argument("--frames", type=int, default=100)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--first", type=int, default=0, help="first frame to write (poses are always complete)")
    ap.add_argument("--last", type=int, default=None, help="last frame to write (inclusive)")
    ap.add_argument("--quiet", action="store_true")
    a = ap.parse_args(argv)
    import cv2  # PNG writer; imported late so --help works without OpenCV

    if a.frames < 1:
        ap.error("--frames must be >= 1")
    last = a.frames - 1 if a.last is None else min(a.last, a.frames - 1)
    img_dir = os.path.join(a.out, "gray", "00", "image_0")
    pose_dir = os.path.join(a.out, "poses")
    os.makedirs(img_dir, exist_ok=True)
    os.makedirs(pose_dir, exist_ok=True)
    r = Renderer(a.seed, a.frames)
    with open(os.path.join(pose_dir, "00.txt"), "w") as f:
        for R, t in r.poses:
            f.write(pose_line(R, t) + "\n")
    t0 = time.time()
    for i in range(a.first, last + 1):
        img = r.frame_u8(i)
        p = os.path.join(img_dir, "%06d.png" % i)
        ok = cv2.imwrite(p, img, [cv2.IMWRITE_PNG_COMPRESSION, 9])
        if not ok:
            print("error: cannot write %s" % p, file=sys.stderr)
            return 1
        if not a.quiet:
            print("frame %d/%d (%.2f s/frame)" % (i, last, (time.time() - t0) / (i - a.first + 1)), file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
