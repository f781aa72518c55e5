//! OpenCV's LINE_8 lines: `Line` (an 8-connected `LineIterator` between
//! integer points, for thickness 1 without a shift) and `Line2` (between
//! fixed-point points, for polygon outlines).

use super::clip::clip_line;
use super::pixel::{put, XY_ONE, XY_SHIFT};
use image::{Rgb, RgbImage};

/// OpenCV's `Line` with an 8-connected `LineIterator` between integer points.
pub(super) fn line8(img: &mut RgbImage, p1: (i64, i64), p2: (i64, i64), c: Rgb<u8>) {
    let (w, h) = (img.width() as i64, img.height() as i64);
    let (mut a, mut b) = (p1, p2);
    if !clip_line(w, h, &mut a, &mut b) {
        return;
    }
    // Left to right, then Bresenham with OpenCV's error terms.
    if b.0 < a.0 {
        std::mem::swap(&mut a, &mut b);
    }
    let dx = b.0 - a.0;
    let (dy, sy) = if b.1 >= a.1 { (b.1 - a.1, 1) } else { (a.1 - b.1, -1) };
    let (mut x, mut y) = a;
    if dy > dx {
        let mut err = dy - (dx + dx);
        for _ in 0..=dy {
            put(img, x, y, c);
            let mask = if err < 0 { -1 } else { 0 };
            err += -(dx + dx) + ((dy + dy) & mask);
            y += sy;
            x += 1 & mask;
        }
    } else {
        let mut err = dx - (dy + dy);
        for _ in 0..=dx {
            put(img, x, y, c);
            let mask = if err < 0 { -1 } else { 0 };
            err += -(dy + dy) + ((dx + dx) & mask);
            x += 1;
            y += sy & mask;
        }
    }
}

/// OpenCV's `Line2`: a LINE_8 line between XY_SHIFT fixed-point points
/// (used for polygon edges), end pixel rounded, every pixel bounds-checked.
pub(super) fn line2(img: &mut RgbImage, p1: (i64, i64), p2: (i64, i64), c: Rgb<u8>) {
    let (w, h) = (img.width() as i64, img.height() as i64);
    let (mut pt1, mut pt2) = (p1, p2);
    if !clip_line(w << XY_SHIFT, h << XY_SHIFT, &mut pt1, &mut pt2) {
        return;
    }
    let (mut dx, mut dy) = (pt2.0 - pt1.0, pt2.1 - pt1.1);
    let j: i64 = if dx < 0 { -1 } else { 0 };
    let ax = (dx ^ j) - j;
    let i: i64 = if dy < 0 { -1 } else { 0 };
    let ay = (dy ^ i) - i;
    let (x_step, y_step, mut ecount);
    if ax > ay {
        dy = (dy ^ j) - j;
        if j != 0 {
            std::mem::swap(&mut pt1, &mut pt2);
        }
        x_step = XY_ONE;
        y_step = (dy << XY_SHIFT) / (ax | 1);
        ecount = (pt2.0 - pt1.0) >> XY_SHIFT;
    } else {
        dx = (dx ^ i) - i;
        if i != 0 {
            std::mem::swap(&mut pt1, &mut pt2);
        }
        x_step = (dx << XY_SHIFT) / (ay | 1);
        y_step = XY_ONE;
        ecount = (pt2.1 - pt1.1) >> XY_SHIFT;
    }
    pt1.0 += XY_ONE >> 1;
    pt1.1 += XY_ONE >> 1;
    put(img, (pt2.0 + (XY_ONE >> 1)) >> XY_SHIFT, (pt2.1 + (XY_ONE >> 1)) >> XY_SHIFT, c);
    if ax > ay {
        pt1.0 >>= XY_SHIFT;
        while ecount >= 0 {
            put(img, pt1.0, pt1.1 >> XY_SHIFT, c);
            pt1.0 += 1;
            pt1.1 += y_step;
            ecount -= 1;
        }
    } else {
        pt1.1 >>= XY_SHIFT;
        while ecount >= 0 {
            put(img, pt1.0 >> XY_SHIFT, pt1.1, c);
            pt1.0 += x_step;
            pt1.1 += 1;
            ecount -= 1;
        }
    }
}
