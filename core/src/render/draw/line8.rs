//! OpenCV's LINE_8 lines: `Line` (an 8-connected `LineIterator` between
//! integer points, for thickness 1 without a shift) and `Line2` (between
//! fixed-point points, for polygon outlines).

use super::clip::{clip_line, Walk};
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
/// Walked once along the major axis ([`Walk`]).
pub(super) fn line2(img: &mut RgbImage, p1: (i64, i64), p2: (i64, i64), c: Rgb<u8>) {
    let (w, h) = (img.width() as i64, img.height() as i64);
    let Some(walk) = Walk::new(w, h, p1, p2) else {
        return;
    };
    let (a, b) = (walk.a, walk.b);
    let mut ecount = (b.0 - a.0) >> XY_SHIFT;
    let mut v = a.1 + (XY_ONE >> 1);
    // OpenCV plots the rounded end point first, then walks from the start.
    let (x, y) = walk.xy(((b.0 + (XY_ONE >> 1)) >> XY_SHIFT, (b.1 + (XY_ONE >> 1)) >> XY_SHIFT));
    put(img, x, y, c);
    let mut u = (a.0 + (XY_ONE >> 1)) >> XY_SHIFT;
    while ecount >= 0 {
        let (x, y) = walk.xy((u, v >> XY_SHIFT));
        put(img, x, y, c);
        u += 1;
        v += walk.v_step;
        ecount -= 1;
    }
}
