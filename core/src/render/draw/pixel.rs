//! Pixels and OpenCV's fixed-point drawing coordinates: a clipped pixel
//! write, a clipped horizontal run, the filled rectangle, `cvRound`.

use image::{Rgb, RgbImage};

/// Sets one pixel if it lies inside the image.
#[inline]
pub fn put(img: &mut RgbImage, x: i64, y: i64, c: Rgb<u8>) {
    if x >= 0 && y >= 0 && (x as u64) < img.width() as u64 && (y as u64) < img.height() as u64 {
        img.put_pixel(x as u32, y as u32, c);
    }
}

/// A horizontal run `xl..=xr` on row `y`, clipped.
pub(super) fn hline(img: &mut RgbImage, xl: i64, xr: i64, y: i64, c: Rgb<u8>) {
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

/// OpenCV's fixed-point drawing coordinates: 16 fractional bits.
pub const XY_SHIFT: u32 = 16;
pub const XY_ONE: i64 = 1 << XY_SHIFT;

/// C's `cvRound(double)`: round half to even (SSE2 `cvtsd2si`).
#[inline]
pub(super) fn cv_round(v: f64) -> i64 {
    v.round_ties_even() as i64
}
