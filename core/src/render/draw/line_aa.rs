//! OpenCV's `LineAA`: a 3-pixel-wide, Gaussian-filtered anti-aliased line
//! between fixed-point points (the LINE_AA of `drawMatchesKnn`,
//! docs/fidelity.md §LAB-4).

use super::clip::Walk;
use super::pixel::{XY_ONE, XY_SHIFT};
use image::{Rgb, RgbImage};

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
/// Walked once along the major axis ([`Walk`]).
pub fn line_aa(img: &mut RgbImage, p1: (i64, i64), p2: (i64, i64), c: Rgb<u8>) {
    let (w, h) = (img.width() as i64, img.height() as i64);
    let Some(walk) = Walk::new(w, h, p1, p2) else {
        return;
    };
    let (mut a, mut b, v_step) = (walk.a, walk.b, walk.v_step);
    b.0 += XY_ONE;
    let mut ecount = (b.0 >> XY_SHIFT) - (a.0 >> XY_SHIFT);
    a.1 += ((v_step * -(a.0 & (XY_ONE - 1))) >> XY_SHIFT) + (XY_ONE >> 1);
    let slope0 = ((v_step >> (XY_SHIFT - 5)) & 0x3f) ^ if v_step < 0 { 0x3f } else { 0 };
    let i = (a.0 >> (XY_SHIFT - 7)) & 0x78;
    let j = (b.0 >> (XY_SHIFT - 7)) & 0x78;
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
    let mut u = a.0 >> XY_SHIFT;
    while ecount >= 0 {
        // The three pixels across the line at v − 1, v, v + 1.
        let v = (a.1 >> XY_SHIFT) - 1;
        let ep_corr = ep[(sel(scount) * 3 + sel(ecount)) as usize];
        let dist = ((a.1 >> (XY_SHIFT - 5)) & 31) as usize;
        for (k, f) in [FILTER[dist + 32], FILTER[dist], FILTER[63 - dist]].into_iter().enumerate() {
            let (x, y) = walk.xy((u, v + k as i64));
            blend_aa(img, x, y, c, ((ep_corr * f) >> 8) & 0xff);
        }
        a.1 += v_step;
        u += 1;
        scount += 1;
        ecount -= 1;
    }
}
