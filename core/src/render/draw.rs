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
            for (x, y) in [(x11, y11), (x11, y12), (x12, y11), (x12, y12), (x21, y21), (x21, y22), (x22, y21), (x22, y22)] {
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
}
