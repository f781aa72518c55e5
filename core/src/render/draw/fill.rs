//! OpenCV's `FillConvexPoly`: a convex polygon's outline, then scanlines
//! between its two edge walkers (the thick lines' bodies and the filled
//! circles of LINE_AA).

use super::line8::line2;
use super::line_aa::line_aa;
use super::pixel::{hline, XY_ONE, XY_SHIFT};
use image::{Rgb, RgbImage};

/// OpenCV's `FillConvexPoly` for points with `shift` fractional bits:
/// outline first (LINE_AA or Line2), then scanlines between the two edge
/// walkers, rounded as OpenCV rounds (half-pixel for LINE_8).
pub(super) fn fill_convex_poly(img: &mut RgbImage, v: &[(i64, i64)], c: Rgb<u8>, aa: bool, shift: u32) {
    let npts = v.len();
    if npts == 0 {
        return;
    }
    let (w, h) = (img.width() as i64, img.height() as i64);
    let delta: i64 = (1i64 << shift) >> 1;
    let (delta1, delta2) = if aa { (XY_ONE - 1, 0) } else { (XY_ONE >> 1, XY_ONE >> 1) };
    let up = XY_SHIFT - shift;
    let mut p0 = (v[npts - 1].0 << up, v[npts - 1].1 << up);
    let (mut xmin, mut xmax, mut ymin, mut ymax) = (v[0].0, v[0].0, v[0].1, v[0].1);
    let mut imin = 0usize;
    for (k, &p) in v.iter().enumerate() {
        if p.1 < ymin {
            ymin = p.1;
            imin = k;
        }
        ymax = ymax.max(p.1);
        xmax = xmax.max(p.0);
        xmin = xmin.min(p.0);
        let q = (p.0 << up, p.1 << up);
        if aa {
            line_aa(img, p0, q, c);
        } else {
            line2(img, p0, q, c);
        }
        p0 = q;
    }
    xmin = (xmin + delta) >> shift;
    xmax = (xmax + delta) >> shift;
    ymin = (ymin + delta) >> shift;
    ymax = (ymax + delta) >> shift;
    if npts < 3 || xmax < 0 || ymax < 0 || xmin >= w || ymin >= h {
        return;
    }
    ymax = ymax.min(h - 1);
    #[derive(Clone, Copy)]
    struct Edge {
        idx: usize,
        di: usize,
        x: i64,
        dx: i64,
        ye: i64,
    }
    let mut edge = [Edge { idx: imin, di: 1, x: -XY_ONE, dx: 0, ye: ymin }; 2];
    edge[1].di = npts - 1;
    let mut edges = npts as i64;
    let mut y = ymin;
    loop {
        if !aa || y < ymax || y == ymin {
            for e in edge.iter_mut() {
                if y >= e.ye {
                    let mut idx0 = e.idx;
                    let mut idx = idx0 + e.di;
                    if idx >= npts {
                        idx -= npts;
                    }
                    loop {
                        let more = edges > 0;
                        edges -= 1;
                        if !more {
                            break;
                        }
                        let ty = (v[idx].1 + delta) >> shift;
                        if ty > y {
                            let xs = v[idx0].0 << up;
                            let xe = v[idx].0 << up;
                            e.ye = ty;
                            e.dx = ((xe - xs) * 2 + (ty - y)) / (2 * (ty - y));
                            e.x = xs;
                            e.idx = idx;
                            break;
                        }
                        idx0 = idx;
                        idx += e.di;
                        if idx >= npts {
                            idx -= npts;
                        }
                    }
                }
            }
        }
        if edges < 0 {
            break;
        }
        if y >= 0 {
            let (l, r) = if edge[0].x > edge[1].x { (1, 0) } else { (0, 1) };
            let xx1 = (edge[l].x + delta1) >> XY_SHIFT;
            let xx2 = (edge[r].x + delta2) >> XY_SHIFT;
            if xx2 >= 0 && xx1 < w {
                hline(img, xx1, xx2, y, c);
            }
        }
        edge[0].x += edge[0].dx;
        edge[1].x += edge[1].dx;
        y += 1;
        if y > ymax {
            break;
        }
    }
}
