//! OpenCV's `ThickLine`, `PolyLine` and `EllipseEx`: lines of any
//! thickness with round caps, and circles drawn as polygons from OpenCV's
//! sine table. They call each other (a thick line's caps are filled circles,
//! a circle's rim is a polyline), so they share this module.

use super::circle8::circle8;
use super::fill::fill_convex_poly;
use super::line8::{line2, line8};
use super::line_aa::line_aa;
use super::pixel::{cv_round, XY_ONE, XY_SHIFT};
use image::{Rgb, RgbImage};

/// OpenCV's `SinTable` for 0..=90 degrees: sin rounded to 7 decimals, as
/// float literals (these, not libm's sin, decide where circle vertices land).
// The literals are OpenCV's table text; each parses to the same f32 it does.
#[rustfmt::skip]
#[allow(clippy::excessive_precision, clippy::approx_constant)]
const SIN_QUADRANT: [f32; 91] = [0.0000000, 0.0174524, 0.0348995, 0.0523360, 0.0697565, 0.0871557, 0.1045285, 0.1218693, 0.1391731, 0.1564345, 0.1736482, 0.1908090, 0.2079117, 0.2249511, 0.2419219, 0.2588190, 0.2756374, 0.2923717, 0.3090170, 0.3255682, 0.3420201, 0.3583679, 0.3746066, 0.3907311, 0.4067366, 0.4226183, 0.4383711, 0.4539905, 0.4694716, 0.4848096, 0.5000000, 0.5150381, 0.5299193, 0.5446390, 0.5591929, 0.5735764, 0.5877853, 0.6018150, 0.6156615, 0.6293204, 0.6427876, 0.6560590, 0.6691306, 0.6819984, 0.6946584, 0.7071068, 0.7193398, 0.7313537, 0.7431448, 0.7547096, 0.7660444, 0.7771460, 0.7880108, 0.7986355, 0.8090170, 0.8191520, 0.8290376, 0.8386706, 0.8480481, 0.8571673, 0.8660254, 0.8746197, 0.8829476, 0.8910065, 0.8987940, 0.9063078, 0.9135455, 0.9205049, 0.9271839, 0.9335804, 0.9396926, 0.9455186, 0.9510565, 0.9563048, 0.9612617, 0.9659258, 0.9702957, 0.9743701, 0.9781476, 0.9816272, 0.9848078, 0.9876883, 0.9902681, 0.9925462, 0.9945219, 0.9961947, 0.9975641, 0.9986295, 0.9993908, 0.9998477, 1.0000000];

/// `SinTable[i]` for 0 <= i <= 450 (the table repeats the first quadrant at
/// the end so `SinTable[450 - a]` is cos a).
fn sin_table(i: i64) -> f32 {
    let a = i.rem_euclid(360) as usize;
    let (q, r) = (a / 90, a % 90);
    match q {
        0 => SIN_QUADRANT[r],
        1 => SIN_QUADRANT[90 - r],
        2 => -SIN_QUADRANT[r],
        _ => -SIN_QUADRANT[90 - r],
    }
}

/// OpenCV's `ThickLine` (XY_SHIFT output, `shift` input bits). Thickness 1:
/// LineAA, or a LINE_8 line; thicker: a filled quad of half-width
/// thickness/2 plus round caps on the ends selected by `flags` (bit 0:
/// start, bit 1: end).
#[allow(clippy::too_many_arguments)] // OpenCV's ThickLine signature, kept for traceability
pub(super) fn thick_line(
    img: &mut RgbImage,
    p0: (i64, i64),
    p1: (i64, i64),
    c: Rgb<u8>,
    thickness: i64,
    aa: bool,
    flags: u32,
    shift: u32,
) {
    let up = XY_SHIFT - shift;
    let mut p0 = (p0.0 << up, p0.1 << up);
    let p1 = (p1.0 << up, p1.1 << up);
    if thickness <= 1 {
        if aa {
            line_aa(img, p0, p1, c);
        } else if shift == 0 {
            let r = |v: i64| (v + (XY_ONE >> 1)) >> XY_SHIFT;
            line8(img, (r(p0.0), r(p0.1)), (r(p1.0), r(p1.1)), c);
        } else {
            line2(img, p0, p1, c);
        }
        return;
    }
    let inv = 1.0 / XY_ONE as f64;
    let dx = (p0.0 - p1.0) as f64 * inv;
    let dy = (p1.1 - p0.1) as f64 * inv;
    let mut r = dx * dx + dy * dy;
    let odd = thickness & 1;
    let t = thickness << (XY_SHIFT - 1);
    if r.abs() > f64::EPSILON {
        r = (t as f64 + odd as f64 * XY_ONE as f64 * 0.5) / r.sqrt();
        let dp = (cv_round(dy * r), cv_round(dx * r));
        let pt = [
            (p0.0 + dp.0, p0.1 + dp.1),
            (p0.0 - dp.0, p0.1 - dp.1),
            (p1.0 - dp.0, p1.1 - dp.1),
            (p1.0 + dp.0, p1.1 + dp.1),
        ];
        fill_convex_poly(img, &pt, c, aa, XY_SHIFT);
    }
    for k in 0..2 {
        if flags & (k + 1) != 0 {
            if aa {
                ellipse_ex(img, p0, t, c, -1, true);
            } else {
                let center = ((p0.0 + (XY_ONE >> 1)) >> XY_SHIFT, (p0.1 + (XY_ONE >> 1)) >> XY_SHIFT);
                circle8(img, center, (t + (XY_ONE >> 1)) >> XY_SHIFT, c, true);
            }
        }
        p0 = p1;
    }
}

/// OpenCV's `PolyLine` (open or closed) in XY_SHIFT-`shift` fixed point:
/// caps on both ends of the first segment and the end of every other one.
fn poly_line(img: &mut RgbImage, v: &[(i64, i64)], closed: bool, c: Rgb<u8>, thickness: i64, aa: bool, shift: u32) {
    if v.is_empty() {
        return;
    }
    let start = if closed { v.len() - 1 } else { 0 };
    let mut flags = 2 + (!closed) as u32;
    let mut p0 = v[start];
    for &p in &v[(!closed) as usize..] {
        thick_line(img, p0, p, c, thickness, aa, flags, shift);
        p0 = p;
        flags = 2;
    }
}

/// OpenCV's `EllipseEx` for a full circle of radius `r` (XY_SHIFT fixed
/// point): `ellipse2Poly` vertices every `delta` degrees (90/30/18/5 by
/// size, from the float SinTable), rounded to fixed point, then a polyline
/// (thickness >= 0) or a filled convex polygon (thickness < 0).
pub(super) fn ellipse_ex(img: &mut RgbImage, center: (i64, i64), r: i64, c: Rgb<u8>, thickness: i64, aa: bool) {
    let r = r.abs();
    let d = (r + (XY_ONE >> 1)) >> XY_SHIFT;
    let delta = if d < 3 {
        90
    } else if d < 10 {
        30
    } else if d < 15 {
        18
    } else {
        5
    };
    let (cx, cy) = (center.0 as f64, center.1 as f64);
    let mut v: Vec<(i64, i64)> = Vec::with_capacity(360 / delta as usize + 2);
    let mut prev: Option<(i64, i64)> = None;
    let mut a = 0i64;
    while a < 360 + delta {
        let ang = a.min(360);
        // alpha = cos 0 = 1 and beta = sin 0 = 0 exactly, so the rotation
        // in ellipse2Poly leaves the point unchanged.
        let x = r as f64 * sin_table(450 - ang) as f64;
        let y = r as f64 * sin_table(ang) as f64;
        let (px, py) = (cx + x, cy + y);
        let mut pt = (cv_round(px / XY_ONE as f64) << XY_SHIFT, cv_round(py / XY_ONE as f64) << XY_SHIFT);
        pt.0 += cv_round(px - pt.0 as f64);
        pt.1 += cv_round(py - pt.1 as f64);
        if prev != Some(pt) {
            v.push(pt);
            prev = Some(pt);
        }
        a += delta;
    }
    if v.len() == 1 {
        v = vec![center, center];
    }
    if thickness >= 0 {
        poly_line(img, &v, false, c, thickness, aa, XY_SHIFT);
    } else {
        fill_convex_poly(img, &v, c, aa, XY_SHIFT);
    }
}
