//! The whole-frame matching picture: both frames side by side (previous
//! left, current right, as `drawMatches` lays them out) and one line per
//! match in the palette's styles: solid with circled ends when the
//! ground-truth geometry calls it correct, dashed with crossed ends when
//! wrong (so the two differ in more than colour), yellow when there is no
//! ground truth.

use super::draw::{circle, line};
use super::palette::{Marker, Style, CORRECT, UNJUDGED, WRONG};
use super::plot::dash::segments;
use super::RgbImage;
use crate::error::{Error, Result};
use crate::image::GrayImage;
use crate::matching::DMatch;
use crate::sift::KeyPoint;
use image::Rgb;

/// 4 fractional bits, as drawMatches draws.
fn fx(v: f64) -> i64 {
    (v * 16.0).round() as i64
}

/// The segment from `a` to `b` in the style's colour and dash (1 px, anti-aliased).
pub(super) fn dashed_segment(out: &mut RgbImage, a: (f64, f64), b: (f64, f64), st: &Style) {
    for (p, q) in segments(&[a, b], st.dash) {
        line(out, (fx(p.0), fx(p.1)), (fx(q.0), fx(q.1)), Rgb(st.color), 1, true, 4);
    }
}

/// The style's marker at `e`: a circle of radius `r`, or a cross of radius
/// `r + 1` ([`Marker::cross`]: strokes ±0.75·(r + 1) on each axis), the pair
/// whole_frame has always drawn at r = 3.
pub(super) fn end_marker(out: &mut RgbImage, e: (f64, f64), st: &Style, r: f64) {
    let c = Rgb(st.color);
    match st.marker {
        Marker::Cross => {
            for (p, q) in Marker::cross(e, r + 1.0) {
                line(out, (fx(p.0), fx(p.1)), (fx(q.0), fx(q.1)), c, 1, true, 4);
            }
        }
        _ => circle(out, (fx(e.0), fx(e.1)), fx(r), c, 1, true, 4),
    }
}

/// One match: its line with the style's dash and a marker of radius 3 at each end.
fn draw_match(out: &mut RgbImage, a: (f64, f64), b: (f64, f64), st: &Style) {
    dashed_segment(out, a, b, st);
    for e in [a, b] {
        end_marker(out, e, st, 3.0);
    }
}

/// The matches in drawing order with their styles and keypoints: correct
/// (or unjudged) first, wrong last, each as (index, style, query keypoint,
/// train keypoint). Errors when the verdicts are not one per match or a
/// match names a keypoint the frames do not have.
pub(super) fn styled<'k>(
    prev: &'k [KeyPoint],
    cur: &'k [KeyPoint],
    matches: &[DMatch],
    verdicts: Option<&[bool]>,
) -> Result<Vec<(usize, Style, &'k KeyPoint, &'k KeyPoint)>> {
    if verdicts.is_some_and(|v| v.len() != matches.len()) {
        return Err(Error::InvalidArgument("one verdict per match is needed".into()));
    }
    let style = |i: usize| match verdicts {
        None => UNJUDGED,
        Some(v) if v[i] => CORRECT,
        Some(_) => WRONG,
    };
    let mut order: Vec<usize> = (0..matches.len()).collect();
    order.sort_by_key(|&i| verdicts.is_none_or(|v| !v[i]));
    order
        .into_iter()
        .map(|i| {
            let m = matches[i];
            match (prev.get(m.query_idx), cur.get(m.train_idx)) {
                (Some(a), Some(b)) => Ok((i, style(i), a, b)),
                _ => Err(Error::InvalidArgument(format!(
                    "match {i} names keypoints {} / {} but the frames have {} / {}",
                    m.query_idx,
                    m.train_idx,
                    prev.len(),
                    cur.len()
                ))),
            }
        })
        .collect()
}

/// Draws `matches` (query in `prev`, train in `cur`); `verdicts[i]` says
/// whether match i is correct. Wrong matches are drawn last: they are the
/// few a student looks for among hundreds of correct ones, and their dashes
/// leave gaps through which the correct lines beneath still show.
pub fn draw(
    prev_image: &GrayImage,
    prev: &[KeyPoint],
    cur_image: &GrayImage,
    cur: &[KeyPoint],
    matches: &[DMatch],
    verdicts: Option<&[bool]>,
) -> Result<RgbImage> {
    let (w1, w2) = (prev_image.width() as u32, cur_image.width() as u32);
    let h = prev_image.height().max(cur_image.height()) as u32;
    let mut out = RgbImage::new(w1 + w2, h);
    image::imageops::replace(&mut out, &super::gray_to_rgb(prev_image), 0, 0);
    image::imageops::replace(&mut out, &super::gray_to_rgb(cur_image), w1 as i64, 0);
    for (_, st, a, b) in styled(prev, cur, matches, verdicts)? {
        let (pa, pb) = ((a.x as f64, a.y as f64), (b.x as f64 + w1 as f64, b.y as f64));
        draw_match(&mut out, pa, pb, &st);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lines_take_the_verdicts_style() {
        let img = GrayImage::new(60, 20, vec![0; 1200]).unwrap();
        let kp = |x: f32, y: f32| KeyPoint { x, y, size: 2.0, angle: 0.0, response: 0.0, octave: 0 };
        let (prev, cur) = (vec![kp(10.0, 3.0), kp(10.0, 14.0)], vec![kp(10.0, 3.0), kp(10.0, 14.0)]);
        let m = |q, t| DMatch { query_idx: q, train_idx: t, distance: 0.0 };
        let out = draw(&img, &prev, &img, &cur, &[m(0, 0), m(1, 1)], Some(&[true, false])).unwrap();
        assert_eq!((out.width(), out.height()), (120, 20));
        // Along each horizontal line from x = 10 to 70, the anti-aliased line
        // over black is the colour scaled by its coverage: sky blue is blue >
        // green > red, vermillion red > green > blue.
        let order = |x: u32, y: u32| {
            let [r, g, b] = out.get_pixel(x, y).0;
            if b > g && g > r {
                "sky blue"
            } else if r > g && g > b {
                "vermillion"
            } else {
                "none"
            }
        };
        // The correct line is solid; the wrong one dashed 8 on, 5 off from x = 10.
        for x in [20, 33, 52] {
            assert_eq!(order(x, 3), "sky blue", "x = {x}");
        }
        assert_eq!(order(27, 14), "vermillion");
        assert_eq!(out.get_pixel(33, 14).0, [0, 0, 0], "a gap of the dashed line");
        // Crossed ends for the wrong match (a corner of the ×), circled for the correct one.
        assert_eq!(order(7, 17), "vermillion");
        assert_eq!(order(10, 0), "sky blue");
        let plain = draw(&img, &prev, &img, &cur, &[m(0, 0)], None).unwrap();
        let [r, g, b] = plain.get_pixel(38, 3).0;
        assert!(r > b && g > b && b < 100, "yellow: {r} {g} {b}");
        assert!(draw(&img, &prev, &img, &cur, &[m(0, 5)], None).is_err());
    }
}
