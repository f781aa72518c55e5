//! The lab's `view_info` composite (`visualiseFeatureInfo`): the
//! `drawMatchesKnn` image of the feature on top, and below it the two frames
//! side by side with green (0, 255, 0) circles of radius 10, thickness 2,
//! LINE_8 at the `matching_info` integer coordinates: the query point on the
//! previous frame, every matched point on the current one. With no match
//! the lower frames stay plain, as in the lab (`if len(cur_coords) > 0`).

use super::draw::circle;
use super::matches::draw_feature;
use crate::error::Result;
use crate::image::GrayImage;
use crate::matching::{DMatch, MatchInfo};
use crate::sift::KeyPoint;
use image::{Rgb, RgbImage};

/// The lab's `hl_colour = (0, 255, 0)`.
pub const HIGHLIGHT: Rgb<u8> = Rgb([0, 255, 0]);
pub const RADIUS: i64 = 10;
pub const THICKNESS: i64 = 2;

/// One frame in colour with `cv2.circle(img, p, 10, (0,255,0), 2)` at each
/// point (drawn on the frame alone, so circles clip at its border).
pub fn highlight(frame: &GrayImage, points: &[(i64, i64)]) -> RgbImage {
    let mut img = super::gray_to_rgb(frame);
    for &p in points {
        circle(&mut img, p, RADIUS, HIGHLIGHT, THICKNESS, false, 0);
    }
    img
}

/// The lower half: `cv2.hconcat([prev_image, cur_image])` with the circles.
/// Frames of different heights (the lab's hconcat would throw) are padded
/// with black at the bottom.
pub fn info_frames(prev_image: &GrayImage, cur_image: &GrayImage, info: &MatchInfo) -> RgbImage {
    let any = !info.points.is_empty();
    let a = highlight(prev_image, if any { std::slice::from_ref(&info.query) } else { &[] });
    let b = highlight(cur_image, &info.points);
    let mut out = RgbImage::new(a.width() + b.width(), a.height().max(b.height()));
    image::imageops::replace(&mut out, &a, 0, 0);
    image::imageops::replace(&mut out, &b, a.width() as i64, 0);
    out
}

/// The whole `custom_visual.png`: `cv2.vconcat([opencv_visual, custom_visual])`.
pub fn draw(
    prev_image: &GrayImage,
    prev: &[KeyPoint],
    cur_image: &GrayImage,
    cur: &[KeyPoint],
    feature_matches: &[DMatch],
    info: &MatchInfo,
) -> Result<RgbImage> {
    let top = draw_feature(prev_image, prev, cur_image, cur, feature_matches)?;
    let bottom = info_frames(prev_image, cur_image, info);
    Ok(stack(&top, &bottom))
}

/// `cv2.vconcat` of two images (narrower one padded with black on the right).
pub fn stack(top: &RgbImage, bottom: &RgbImage) -> RgbImage {
    let mut out = RgbImage::new(top.width().max(bottom.width()), top.height() + bottom.height());
    image::imageops::replace(&mut out, top, 0, 0);
    image::imageops::replace(&mut out, bottom, 0, top.height() as i64);
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::matching::matching_info;

    fn flat(w: usize, h: usize, v: u8) -> GrayImage {
        GrayImage::new(w, h, vec![v; w * h]).unwrap()
    }

    fn kp(x: f32, y: f32) -> KeyPoint {
        KeyPoint { x, y, size: 5.0, angle: -1.0, response: 0.0, octave: 0 }
    }

    #[test]
    fn composite_layout_circles_and_lines() {
        let (a, b) = (flat(120, 50, 40), flat(120, 50, 80));
        let prev = [kp(30.7, 20.2), kp(100.0, 10.0)];
        let cur = [kp(60.9, 25.5), kp(90.2, 30.0)];
        let m = [
            DMatch { query_idx: 0, train_idx: 0, distance: 10.0 },
            DMatch { query_idx: 0, train_idx: 1, distance: 20.0 },
        ];
        let info = matching_info(&prev, &cur, &m);
        assert_eq!(info.query, (30, 20));
        let img = draw(&a, &prev, &b, &cur, &m, &info).unwrap();
        assert_eq!(img.dimensions(), (240, 100));
        let g = [0, 255, 0];
        // Lower half starts at y = 50: rim of the query circle at (30, 20)
        // radius 10 -> (20, 70) and (40, 70), (30, 60), (30, 80).
        for (x, y) in [(20, 70), (40, 70), (30, 60), (30, 80)] {
            assert_eq!(img.get_pixel(x, y).0, g, "({x},{y})");
        }
        assert_eq!(img.get_pixel(30, 70).0, [40; 3], "centre untouched");
        // Matched points (60, 25) and (90, 30) on the current frame (x + 120).
        for (x, y) in [(170, 75), (190, 75), (200, 80), (220, 80), (210, 70)] {
            assert_eq!(img.get_pixel(x, y).0, g, "({x},{y})");
        }
        // Upper half: drawMatchesKnn; the first line runs from (30.7, 20.2)
        // to (180.9, 25.5): its midpoint (105.8, 22.85) is coloured, not gray.
        let mid = img.get_pixel(106, 23).0;
        assert_ne!(mid, [40; 3]);
        assert_ne!(mid, [80; 3]);
        // No green circles in the upper half, no lines in the lower half.
        assert_eq!(img.get_pixel(20, 20).0, [40; 3]);
        assert_eq!(img.get_pixel(106, 73).0, [40; 3]);
    }

    #[test]
    fn no_match_leaves_the_frames_plain() {
        let (a, b) = (flat(40, 30, 7), flat(40, 30, 9));
        let info = matching_info(&[kp(5.0, 5.0)], &[], &[]);
        let img = draw(&a, &[kp(5.0, 5.0)], &b, &[], &[], &info).unwrap();
        assert_eq!(img.dimensions(), (80, 60));
        assert!(img.enumerate_pixels().all(|(x, _, p)| p.0 == if x < 40 { [7; 3] } else { [9; 3] }));
    }

    #[test]
    fn circles_clip_at_each_frame_and_unequal_heights_pad() {
        let (a, b) = (flat(30, 20, 0), flat(30, 25, 0));
        let info =
            MatchInfo { query: (29, 10), points: vec![(0, 0), (-500, 9_000_000_000)], distances: vec![1.0, 2.0] };
        let low = info_frames(&a, &b, &info);
        assert_eq!(low.dimensions(), (60, 25));
        // The query circle at x=29 reaches x=39 on the previous frame only:
        // nothing spills into the current frame's left columns except its own circle.
        assert_eq!(low.get_pixel(19, 10).0, [0, 255, 0]);
        assert_eq!(low.get_pixel(30 + 10, 0).0, [0, 255, 0], "current (0,0) circle rim");
        // The query circle's right rim (39, 10) lies beyond the 30-pixel
        // previous frame: clipped there, not drawn into the current frame.
        assert_eq!(low.get_pixel(39, 10).0, [0, 0, 0], "no spill from prev");
        assert_eq!(low.get_pixel(29, 25 - 1).0, [0, 0, 0], "padding row is black");
    }
}
