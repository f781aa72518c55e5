//! OpenCV's `Circle`: the midpoint circle `cv2.circle` draws for thickness
//! 1 or −1 with LINE_8 and no shift (the lab's `view_info` and trajectory
//! dots, docs/fidelity.md §LAB-4).

use super::pixel::{hline, put};
use image::{Rgb, RgbImage};

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
