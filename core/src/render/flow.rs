//! The whole-frame matches as flow: the current frame only, and each match a
//! short segment from where its point was in the previous frame to where it
//! is now, in the palette's styles (correct solid sky blue, wrong dashed
//! vermillion, unjudged yellow), with a marker at the current end only
//! (circle, or cross for wrong). Hundreds of matches stay readable: a correct
//! match moves the way its neighbours do (outwards from the focus of
//! expansion as the car drives forward), and a wrong one jumps across the
//! frame against that field, drawn last so nothing covers it.

use super::whole_frame::{dashed_segment, end_marker, styled};
use super::RgbImage;
use crate::error::Result;
use crate::image::GrayImage;
use crate::matching::DMatch;
use crate::sift::KeyPoint;

/// The current end's marker: a circle of radius 2 (a cross of radius 3 for
/// wrong matches), smaller than the side-by-side picture's 3 because the
/// markers of neighbouring matches lie closer here.
const MARKER_RADIUS: f64 = 2.0;

/// Draws `matches` (query in `prev`, the previous frame's keypoints; train in
/// `cur`, the current frame's) over `cur_image`, as a segment from
/// `prev[query]` to `cur[train]` with a marker at `cur[train]`. `verdicts[i]`
/// says whether match i is correct (`None`: no ground truth, all yellow).
/// Wrong matches are drawn last. Errors when the verdicts are not one per
/// match or a match names a keypoint the frames do not have (as
/// [`whole_frame`](super::whole_frame::draw)).
pub fn draw(
    cur_image: &GrayImage,
    prev: &[KeyPoint],
    cur: &[KeyPoint],
    matches: &[DMatch],
    verdicts: Option<&[bool]>,
) -> Result<RgbImage> {
    let drawn = styled(prev, cur, matches, verdicts)?;
    let mut out = super::gray_to_rgb(cur_image);
    for (_, st, a, b) in drawn {
        let (from, to) = ((a.x as f64, a.y as f64), (b.x as f64, b.y as f64));
        dashed_segment(&mut out, from, to, &st);
        end_marker(&mut out, to, &st, MARKER_RADIUS);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn kp(x: f32, y: f32) -> KeyPoint {
        KeyPoint { x, y, size: 2.0, angle: 0.0, response: 0.0, octave: 0 }
    }

    fn m(q: usize, t: usize) -> DMatch {
        DMatch { query_idx: q, train_idx: t, distance: 0.0 }
    }

    /// Sky blue is blue > green > red, vermillion red > green > blue, over
    /// black at any anti-aliasing coverage.
    fn hue(out: &RgbImage, x: u32, y: u32) -> &'static str {
        let [r, g, b] = out.get_pixel(x, y).0;
        if b > g && g > r {
            "sky blue"
        } else if r > g && g > b {
            "vermillion"
        } else if [r, g, b] == [0, 0, 0] {
            "black"
        } else {
            "other"
        }
    }

    #[test]
    fn segments_run_from_the_previous_position_to_a_marker_at_the_current_one() {
        let img = GrayImage::new(60, 20, vec![0; 1200]).unwrap();
        // Both points move 30 px to the right, along rows 3 and 14.
        let (prev, cur) = (vec![kp(10.0, 3.0), kp(10.0, 14.0)], vec![kp(40.0, 3.0), kp(40.0, 14.0)]);
        let out = draw(&img, &prev, &cur, &[m(0, 0), m(1, 1)], Some(&[true, false])).unwrap();
        // The current frame only.
        assert_eq!((out.width(), out.height()), (60, 20));
        // The correct segment is solid from x = 10 to its circle at 40.
        for x in [11, 20, 25, 33] {
            assert_eq!(hue(&out, x, 3), "sky blue", "x = {x}");
        }
        // The wrong one dashed 8 on, 5 off from x = 10: on 10-18, off 18-23, on 23-31, off 31-36.
        assert_eq!(hue(&out, 14, 14), "vermillion");
        assert_eq!(hue(&out, 20, 14), "black", "a gap of the dashed line");
        assert_eq!(hue(&out, 27, 14), "vermillion");
        assert_eq!(hue(&out, 33, 14), "black", "a gap of the dashed line");
        // Markers at the current end only: a circle of radius 2 around (40, 3)
        // (its top at (40, 1), nothing at its centre's ring inside), a cross
        // of radius 3 at (40, 14) (a corner at (37.75, 11.75)).
        assert_eq!(hue(&out, 40, 1), "sky blue");
        assert_eq!(hue(&out, 42, 3), "sky blue");
        assert_eq!(hue(&out, 38, 12), "vermillion");
        assert_eq!(hue(&out, 42, 16), "vermillion");
        assert_eq!(hue(&out, 42, 12), "vermillion");
        // No marker where the points were: above and below the start of each segment is black.
        for (x, y) in [(10, 1), (10, 5), (8, 12), (12, 16), (8, 16)] {
            assert_eq!(hue(&out, x, y), "black", "({x}, {y})");
        }
        // Past the current end, nothing.
        assert_eq!(hue(&out, 50, 3), "black");
    }

    #[test]
    fn wrong_matches_are_drawn_over_correct_ones() {
        let img = GrayImage::new(40, 10, vec![0; 400]).unwrap();
        // Two matches along the same row: the wrong one listed first still ends on top.
        let (prev, cur) = (vec![kp(5.0, 5.0)], vec![kp(30.0, 5.0)]);
        for verdicts in [[false, true], [true, false]] {
            let out = draw(&img, &prev, &cur, &[m(0, 0), m(0, 0)], Some(&verdicts)).unwrap();
            assert_eq!(hue(&out, 8, 5), "vermillion", "{verdicts:?}");
            // Where the dash leaves a gap, the correct line beneath shows.
            assert_eq!(hue(&out, 15, 5), "sky blue", "{verdicts:?}");
        }
    }

    #[test]
    fn unjudged_is_yellow_over_the_gray_frame_and_bad_input_is_an_error() {
        let img = GrayImage::new(30, 10, vec![50; 300]).unwrap();
        let (prev, cur) = (vec![kp(2.0, 5.0)], vec![kp(20.0, 5.0)]);
        let out = draw(&img, &prev, &cur, &[m(0, 0)], None).unwrap();
        let [r, g, b] = out.get_pixel(10, 5).0;
        assert!(r > b && g > b && r > 200 && g > 200 && b < 100, "yellow: {r} {g} {b}");
        assert_eq!(out.get_pixel(10, 1).0, [50, 50, 50], "the frame elsewhere, in gray");
        let e = draw(&img, &prev, &cur, &[m(0, 5)], None).unwrap_err().to_string();
        assert!(e.contains("match 0 names keypoints 0 / 5 but the frames have 1 / 1"), "{e}");
        assert!(draw(&img, &prev, &cur, &[m(3, 0)], Some(&[true])).is_err());
        let e = draw(&img, &prev, &cur, &[m(0, 0)], Some(&[])).unwrap_err().to_string();
        assert!(e.contains("one verdict per match"), "{e}");
        // No matches: the frame alone.
        assert_eq!(draw(&img, &prev, &cur, &[], Some(&[])).unwrap(), super::super::gray_to_rgb(&img));
    }
}
