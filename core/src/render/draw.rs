//! Drawing primitives with OpenCV 4.8's integer arithmetic
//! (`modules/imgproc/src/drawing.cpp`), on `image::RgbImage`. Colours are
//! RGB here; OpenCV's `Scalar(b, g, r)` is `Rgb([r, g, b])`.

use image::{Rgb, RgbImage};

/// Sets one pixel if it lies inside the image.
#[inline]
pub fn put(img: &mut RgbImage, x: i64, y: i64, c: Rgb<u8>) {
    if x >= 0 && y >= 0 && (x as u64) < img.width() as u64 && (y as u64) < img.height() as u64 {
        img.put_pixel(x as u32, y as u32, c);
    }
}

/// A horizontal run `xl..=xr` on row `y`, clipped.
fn hline(img: &mut RgbImage, xl: i64, xr: i64, y: i64, c: Rgb<u8>) {
    if y < 0 || y >= img.height() as i64 {
        return;
    }
    let xl = xl.max(0);
    let xr = xr.min(img.width() as i64 - 1);
    for x in xl..=xr {
        img.put_pixel(x as u32, y as u32, c);
    }
}

/// `cv2.rectangle(img, p1, p2, color, -1)`: both corners inclusive.
pub fn fill_rect(img: &mut RgbImage, p1: (i64, i64), p2: (i64, i64), c: Rgb<u8>) {
    let (x0, x1) = (p1.0.min(p2.0), p1.0.max(p2.0));
    let (y0, y1) = (p1.1.min(p2.1), p1.1.max(p2.1));
    for y in y0..=y1.min(img.height() as i64 - 1) {
        hline(img, x0, x1, y, c);
    }
}

/// OpenCV's `Circle` (the path `cv2.circle` takes for thickness 1 or -1,
/// LINE_8, no shift): the midpoint algorithm with its exact error update, so
/// a radius-1 circle is the 4-neighbour cross without the centre.
pub fn circle8(img: &mut RgbImage, center: (i64, i64), radius: i64, c: Rgb<u8>, fill: bool) {
    let (cx, cy) = center;
    // OpenCV draws nothing for a circle entirely outside the image; checking
    // first also keeps the arithmetic below far from overflow.
    let (w, h) = (img.width() as i64, img.height() as i64);
    if !(0..=1 << 30).contains(&radius) || cx < -radius || cy < -radius || cx >= w + radius || cy >= h + radius {
        return;
    }
    let (mut err, mut dx, mut dy, mut plus, mut minus) = (0i64, radius, 0i64, 1i64, (radius << 1) - 1);
    while dx >= dy {
        let (y11, y12, y21, y22) = (cy - dy, cy + dy, cy - dx, cy + dx);
        let (x11, x12, x21, x22) = (cx - dx, cx + dx, cx - dy, cx + dy);
        if fill {
            hline(img, x11, x12, y11, c);
            hline(img, x11, x12, y12, c);
            hline(img, x21, x22, y21, c);
            hline(img, x21, x22, y22, c);
        } else {
            for (x, y) in
                [(x11, y11), (x11, y12), (x12, y11), (x12, y12), (x21, y21), (x21, y22), (x22, y21), (x22, y22)]
            {
                put(img, x, y, c);
            }
        }
        dy += 1;
        err += plus;
        plus += 2;
        let mask = if err <= 0 { 0 } else { -1 };
        err -= minus & mask;
        dx += mask;
        minus -= mask & 2;
    }
}

/// OpenCV's fixed-point drawing coordinates: 16 fractional bits.
pub const XY_SHIFT: u32 = 16;
pub const XY_ONE: i64 = 1 << XY_SHIFT;

/// C's `cvRound(double)`: round half to even (SSE2 `cvtsd2si`).
#[inline]
fn cv_round(v: f64) -> i64 {
    v.round_ties_even() as i64
}

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

/// `cv::clipLine(Size2l, Point2l&, Point2l&)`: Cohen-Sutherland with
/// OpenCV's integer divisions (truncating), so clipped endpoints land on the
/// same pixels.
fn clip_line(width: i64, height: i64, p1: &mut (i64, i64), p2: &mut (i64, i64)) -> bool {
    let (right, bottom) = (width - 1, height - 1);
    if width <= 0 || height <= 0 {
        return false;
    }
    let code = |p: (i64, i64)| -> i32 {
        (p.0 < 0) as i32 + (p.0 > right) as i32 * 2 + (p.1 < 0) as i32 * 4 + (p.1 > bottom) as i32 * 8
    };
    let (mut c1, mut c2) = (code(*p1), code(*p2));
    if (c1 & c2) == 0 && (c1 | c2) != 0 {
        if c1 & 12 != 0 {
            let a = if c1 < 8 { 0 } else { bottom };
            p1.0 += (a - p1.1) * (p2.0 - p1.0) / (p2.1 - p1.1);
            p1.1 = a;
            c1 = (p1.0 < 0) as i32 + (p1.0 > right) as i32 * 2;
        }
        if c2 & 12 != 0 {
            let a = if c2 < 8 { 0 } else { bottom };
            p2.0 += (a - p2.1) * (p2.0 - p1.0) / (p2.1 - p1.1);
            p2.1 = a;
            c2 = (p2.0 < 0) as i32 + (p2.0 > right) as i32 * 2;
        }
        if (c1 & c2) == 0 && (c1 | c2) != 0 {
            if c1 != 0 {
                let a = if c1 == 1 { 0 } else { right };
                p1.1 += (a - p1.0) * (p2.1 - p1.1) / (p2.0 - p1.0);
                p1.0 = a;
                c1 = 0;
            }
            if c2 != 0 {
                let a = if c2 == 1 { 0 } else { right };
                p2.1 += (a - p2.0) * (p2.1 - p1.1) / (p2.0 - p1.0);
                p2.0 = a;
                c2 = 0;
            }
        }
    }
    (c1 | c2) == 0
}

/// OpenCV's slope correction for LINE_AA (index: 5 bits of the minor step).
const SLOPE_CORR: [i64; 32] = [
    181, 181, 181, 182, 182, 183, 184, 185, 187, 188, 190, 192, 194, 196, 198, 201, 203, 206, 209, 211, 214, 218, 221,
    224, 227, 231, 235, 238, 242, 246, 250, 254,
];

/// OpenCV's Gaussian filter for LINE_AA coverage by 1/32 pixel distance.
const FILTER: [i64; 64] = [
    168, 177, 185, 194, 202, 210, 218, 224, 231, 236, 241, 246, 249, 252, 254, 254, 254, 254, 252, 249, 246, 241, 236,
    231, 224, 218, 210, 202, 194, 185, 177, 168, 158, 149, 140, 131, 122, 114, 105, 97, 89, 82, 75, 68, 62, 56, 50, 45,
    40, 36, 32, 28, 25, 22, 19, 16, 14, 12, 11, 9, 8, 7, 5, 5,
];

/// One LINE_AA blend step; OpenCV applies it twice per pixel, which makes
/// the line more opaque than a single `a/256` blend.
#[inline]
fn blend_aa(img: &mut RgbImage, x: i64, y: i64, c: Rgb<u8>, a: i64) {
    if x < 0 || y < 0 || x >= img.width() as i64 || y >= img.height() as i64 {
        return;
    }
    let p = img.get_pixel_mut(x as u32, y as u32);
    for k in 0..3 {
        let mut v = p.0[k] as i64;
        v += ((c.0[k] as i64 - v) * a + 127) >> 8;
        v += ((c.0[k] as i64 - v) * a + 127) >> 8;
        p.0[k] = v as u8;
    }
}

/// OpenCV's `LineAA`: a 3-pixel-wide Gaussian-filtered line between two
/// points in XY_SHIFT fixed point, with its end-point coverage table. The
/// segment is clipped to the image and every pixel of the footprint is
/// bounds-checked (OpenCV 4.x; older releases clipped 2 pixels inside).
pub fn line_aa(img: &mut RgbImage, p1: (i64, i64), p2: (i64, i64), c: Rgb<u8>) {
    let (w, h) = (img.width() as i64, img.height() as i64);
    let (mut pt1, mut pt2) = (p1, p2);
    if !clip_line(w << XY_SHIFT, h << XY_SHIFT, &mut pt1, &mut pt2) {
        return;
    }
    let (mut dx, mut dy) = (pt2.0 - pt1.0, pt2.1 - pt1.1);
    let mut j: i64 = if dx < 0 { -1 } else { 0 };
    let ax = (dx ^ j) - j;
    let mut i: i64 = if dy < 0 { -1 } else { 0 };
    let ay = (dy ^ i) - i;
    let (x_step, y_step, mut ecount, slope0);
    if ax > ay {
        dy = (dy ^ j) - j;
        if j != 0 {
            std::mem::swap(&mut pt1, &mut pt2);
        }
        x_step = XY_ONE;
        y_step = (dy << XY_SHIFT) / (ax | 1);
        pt2.0 += XY_ONE;
        ecount = (pt2.0 >> XY_SHIFT) - (pt1.0 >> XY_SHIFT);
        j = -(pt1.0 & (XY_ONE - 1));
        pt1.1 += ((y_step * j) >> XY_SHIFT) + (XY_ONE >> 1);
        let s = (y_step >> (XY_SHIFT - 5)) & 0x3f;
        slope0 = s ^ if y_step < 0 { 0x3f } else { 0 };
        i = (pt1.0 >> (XY_SHIFT - 7)) & 0x78;
        j = (pt2.0 >> (XY_SHIFT - 7)) & 0x78;
    } else {
        dx = (dx ^ i) - i;
        if i != 0 {
            std::mem::swap(&mut pt1, &mut pt2);
        }
        x_step = (dx << XY_SHIFT) / (ay | 1);
        y_step = XY_ONE;
        pt2.1 += XY_ONE;
        ecount = (pt2.1 >> XY_SHIFT) - (pt1.1 >> XY_SHIFT);
        j = -(pt1.1 & (XY_ONE - 1));
        pt1.0 += ((x_step * j) >> XY_SHIFT) + (XY_ONE >> 1);
        let s = (x_step >> (XY_SHIFT - 5)) & 0x3f;
        slope0 = s ^ if x_step < 0 { 0x3f } else { 0 };
        i = (pt1.1 >> (XY_SHIFT - 7)) & 0x78;
        j = (pt2.1 >> (XY_SHIFT - 7)) & 0x78;
    }
    let slope = if slope0 & 0x20 != 0 { 0x100 } else { SLOPE_CORR[slope0 as usize] };
    // End-point correction: partial coverage of the first and last two
    // pixels from the 4-bit sub-pixel fractions of the ends.
    let mut ep = [0i64; 9];
    {
        let t0 = slope << 7;
        let t1 = ((0x78 - i) | 4) * slope;
        let t2 = (j | 4) * slope;
        ep[0] = 0;
        ep[8] = slope;
        ep[1] = (((((j - i) & 0x78) | 4) * slope) >> 8) & 0x1ff;
        ep[3] = ep[1];
        ep[2] = (t1 >> 8) & 0x1ff;
        ep[4] = (((((j - i) + 0x80) | 4) * slope) >> 8) & 0x1ff;
        ep[5] = ((t1 + t0) >> 8) & 0x1ff;
        ep[6] = (t2 >> 8) & 0x1ff;
        ep[7] = ((t2 + t0) >> 8) & 0x1ff;
    }
    let mut scount: i64 = 0;
    let sel = |n: i64| ((n >= 2) as i64 + 1) & (n | 2);
    if ax > ay {
        let mut x = pt1.0 >> XY_SHIFT;
        while ecount >= 0 {
            let y = (pt1.1 >> XY_SHIFT) - 1;
            let ep_corr = ep[(sel(scount) * 3 + sel(ecount)) as usize];
            let dist = ((pt1.1 >> (XY_SHIFT - 5)) & 31) as usize;
            blend_aa(img, x, y, c, ((ep_corr * FILTER[dist + 32]) >> 8) & 0xff);
            blend_aa(img, x, y + 1, c, ((ep_corr * FILTER[dist]) >> 8) & 0xff);
            blend_aa(img, x, y + 2, c, ((ep_corr * FILTER[63 - dist]) >> 8) & 0xff);
            pt1.1 += y_step;
            x += 1;
            scount += 1;
            ecount -= 1;
        }
    } else {
        let mut y = pt1.1 >> XY_SHIFT;
        while ecount >= 0 {
            let x = (pt1.0 >> XY_SHIFT) - 1;
            let ep_corr = ep[(sel(scount) * 3 + sel(ecount)) as usize];
            let dist = ((pt1.0 >> (XY_SHIFT - 5)) & 31) as usize;
            blend_aa(img, x, y, c, ((ep_corr * FILTER[dist + 32]) >> 8) & 0xff);
            blend_aa(img, x + 1, y, c, ((ep_corr * FILTER[dist]) >> 8) & 0xff);
            blend_aa(img, x + 2, y, c, ((ep_corr * FILTER[63 - dist]) >> 8) & 0xff);
            pt1.0 += x_step;
            y += 1;
            scount += 1;
            ecount -= 1;
        }
    }
}

/// OpenCV's `Line2`: a LINE_8 line between XY_SHIFT fixed-point points
/// (used for polygon edges), end pixel rounded, every pixel bounds-checked.
fn line2(img: &mut RgbImage, p1: (i64, i64), p2: (i64, i64), c: Rgb<u8>) {
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

/// OpenCV's `FillConvexPoly` for points with `shift` fractional bits:
/// outline first (LINE_AA or Line2), then scanlines between the two edge
/// walkers, rounded as OpenCV rounds (half-pixel for LINE_8).
fn fill_convex_poly(img: &mut RgbImage, v: &[(i64, i64)], c: Rgb<u8>, aa: bool, shift: u32) {
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

/// OpenCV's `ThickLine` (XY_SHIFT output, `shift` input bits). Thickness 1:
/// LineAA, or a LINE_8 line; thicker: a filled quad of half-width
/// thickness/2 plus round caps on the ends selected by `flags` (bit 0:
/// start, bit 1: end).
#[allow(clippy::too_many_arguments)] // OpenCV's ThickLine signature, kept for traceability
fn thick_line(
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

/// OpenCV's `Line` with an 8-connected `LineIterator` between integer points.
fn line8(img: &mut RgbImage, p1: (i64, i64), p2: (i64, i64), c: Rgb<u8>) {
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
fn ellipse_ex(img: &mut RgbImage, center: (i64, i64), r: i64, c: Rgb<u8>, thickness: i64, aa: bool) {
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

/// `cv2.circle(img, center, radius, color, thickness, lineType, shift)`:
/// center and radius carry `shift` fractional bits. Thickness 1 or -1 with
/// LINE_8 and no shift takes OpenCV's midpoint `Circle`; everything else
/// (LINE_AA, thicker rims, sub-pixel centres) the polygon path.
pub fn circle(img: &mut RgbImage, center: (i64, i64), radius: i64, c: Rgb<u8>, thickness: i64, aa: bool, shift: u32) {
    if radius < 0 || shift > XY_SHIFT || thickness > 32767 {
        return;
    }
    if thickness > 1 || aa || shift > 0 {
        let up = XY_SHIFT - shift;
        let (w, h) = (img.width() as i64, img.height() as i64);
        // Far-away circles draw nothing; bail out before fixed-point overflow.
        let lim = (w + h + radius + thickness) << shift;
        if center.0.abs() > lim * 4 || center.1.abs() > lim * 4 || radius > 1 << 24 {
            return;
        }
        ellipse_ex(img, (center.0 << up, center.1 << up), radius << up, c, thickness, aa);
    } else {
        circle8(img, center, radius, c, thickness < 0);
    }
}

/// `cv2.line(img, pt1, pt2, color, thickness, lineType, shift)`.
pub fn line(img: &mut RgbImage, p1: (i64, i64), p2: (i64, i64), c: Rgb<u8>, thickness: i64, aa: bool, shift: u32) {
    if shift > XY_SHIFT || !(0..=32767).contains(&thickness) {
        return;
    }
    let lim = 1i64 << 40;
    if [p1.0, p1.1, p2.0, p2.1].iter().any(|v| v.abs() > lim) {
        return;
    }
    thick_line(img, p1, p2, c, thickness, aa, 3, shift);
}

#[cfg(test)]
mod tests {
    use super::*;

    const W: Rgb<u8> = Rgb([255, 255, 255]);

    fn lit(img: &RgbImage) -> Vec<(u32, u32)> {
        img.enumerate_pixels().filter(|(_, _, p)| p.0 != [0, 0, 0]).map(|(x, y, _)| (x, y)).collect()
    }

    #[test]
    fn radius_one_circle_is_the_cross_cv2_draws() {
        // cv2.circle(np.zeros((20,20,3)), (10,10), 1, c, 1) lights exactly
        // (y,x) = (9,10), (10,9), (10,11), (11,10).
        let mut img = RgbImage::new(20, 20);
        circle8(&mut img, (10, 10), 1, W, false);
        let mut px = lit(&img);
        px.sort();
        assert_eq!(px, vec![(9, 10), (10, 9), (10, 11), (11, 10)]);
    }

    #[test]
    fn filled_rectangle_is_inclusive_and_clipped() {
        let mut img = RgbImage::new(30, 30);
        fill_rect(&mut img, (10, 20), (600, 25), W);
        assert_eq!(lit(&img).len(), 20 * 6);
        assert_eq!(img.get_pixel(10, 20).0, [255; 3]);
        assert_eq!(img.get_pixel(9, 20).0, [0; 3]);
        assert_eq!(img.get_pixel(29, 25).0, [255; 3]);
        assert_eq!(img.get_pixel(29, 26).0, [0; 3]);
    }

    /// The 80x60 gradient gen_refs.py draws on, as BGR→RGB gray.
    fn base() -> RgbImage {
        RgbImage::from_fn(80, 60, |x, y| {
            let v = ((x * 3 + y * 2) % 256) as u8;
            Rgb([v, v, v])
        })
    }

    fn reference(name: &str) -> RgbImage {
        let path = format!("{}/src/render/testdata/{name}", env!("CARGO_MANIFEST_DIR"));
        image::open(&path).unwrap_or_else(|e| panic!("{path}: {e}")).to_rgb8()
    }

    fn assert_same(out: &RgbImage, want: &RgbImage) {
        let d: Vec<_> = out
            .enumerate_pixels()
            .filter(|(x, y, p)| p.0 != want.get_pixel(*x, *y).0)
            .map(|(x, y, p)| (x, y, p.0, want.get_pixel(x, y).0))
            .collect();
        assert!(d.is_empty(), "{} pixels differ from OpenCV, first: {:?}", d.len(), &d[..d.len().min(6)]);
    }

    /// BGR Scalar from gen_refs.py as RGB.
    fn bgr(b: i64, g: i64, r: i64) -> Rgb<u8> {
        Rgb([r as u8, g as u8, b as u8])
    }

    #[test]
    fn line_aa_with_shift_matches_opencv() {
        let mut img = base();
        let segs = [
            ((5, 7), (1200, 300)),
            ((1000, 900), (80, 20)),
            ((300, 40), (310, 900)),
            ((1270, 10), (-40, 950)),
            ((-100, 500), (2000, 480)),
            ((640, 480), (640, 481)),
        ];
        for (i, (p, q)) in segs.iter().enumerate() {
            let i = i as i64;
            line(&mut img, *p, *q, bgr(30 * i, 255 - 40 * i, 90), 1, true, 4);
        }
        assert_same(&img, &reference("lines_aa.png"));
        // The first segment (0.3125, 0.4375) -> (75, 18.75) is drawn: its
        // midpoint pixel took the colour (R=90 dominates the gray there).
        let mid = img.get_pixel(37, 10).0;
        assert_ne!(mid, base().get_pixel(37, 10).0);
    }

    #[test]
    fn circle_aa_radius_three_matches_opencv() {
        let mut img = base();
        for (i, c) in [(325, 491), (8, 8), (1260, 950), (640, 300)].iter().enumerate() {
            let i = i as i64;
            circle(&mut img, *c, 48, bgr(0, 40 * i, 255 - 50 * i), 1, true, 4);
        }
        assert_same(&img, &reference("circles_aa.png"));
    }

    #[test]
    fn thick_circle_line8_matches_opencv() {
        let mut img = base();
        for c in [(20, 30), (75, 2), (50, 45)] {
            circle(&mut img, c, 10, Rgb([0, 255, 0]), 2, false, 0);
        }
        let want = reference("circles_thick2.png");
        assert_same(&img, &want);
        // Rim pixels: radius 10 left/right of (20, 30) are green, the centre is not.
        assert_eq!(img.get_pixel(10, 30).0, [0, 255, 0]);
        assert_eq!(img.get_pixel(30, 30).0, [0, 255, 0]);
        assert_eq!(img.get_pixel(20, 20).0, [0, 255, 0]);
        assert_ne!(img.get_pixel(20, 30).0, [0, 255, 0]);
    }
}
