//! Drawing primitives with OpenCV 4.8's integer arithmetic
//! (`modules/imgproc/src/drawing.cpp`), on `image::RgbImage`, one module per
//! operation as OpenCV splits them: `pixel` (pixels, runs, rectangles and
//! fixed point), `clip` (`clipLine`), `line8` (LINE_8 lines), `line_aa`
//! (`LineAA`), `circle8` (the midpoint `Circle`), `fill`
//! (`FillConvexPoly`) and `thick` (`ThickLine`, `PolyLine`, `EllipseEx`).
//! [`circle`] and [`line`] are `cv2.circle` and `cv2.line`. Colours are RGB
//! here; OpenCV's `Scalar(b, g, r)` is `Rgb([r, g, b])`. Which line type
//! each lab picture uses is in docs/fidelity.md §LAB-4.

mod circle8;
mod clip;
mod fill;
mod line8;
mod line_aa;
mod pixel;
mod thick;

pub use circle8::circle8;

pub use pixel::{fill_rect, put, XY_SHIFT};

use image::{Rgb, RgbImage};

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
        thick::ellipse_ex(img, (center.0 << up, center.1 << up), radius << up, c, thickness, aa);
    } else {
        circle8(img, center, radius, c, thickness < 0);
    }
}

/// `cv2.fillConvexPoly(img, points, color, lineType, shift)`: the points
/// carry `shift` fractional bits.
pub fn fill_convex(img: &mut RgbImage, points: &[(i64, i64)], c: Rgb<u8>, aa: bool, shift: u32) {
    let lim = 1i64 << 40;
    if shift > XY_SHIFT || points.iter().any(|p| p.0.abs() > lim || p.1.abs() > lim) {
        return;
    }
    fill::fill_convex_poly(img, points, c, aa, shift);
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
    thick::thick_line(img, p1, p2, c, thickness, aa, 3, shift);
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
