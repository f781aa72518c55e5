//! The whole-frame matching picture: both frames side by side (previous
//! left, current right, as `drawMatches` lays them out) and one line per
//! match, green when the ground-truth geometry calls it correct, red when
//! wrong, blue when there is no ground truth.

use super::draw::{circle, line};
use super::RgbImage;
use crate::error::{Error, Result};
use crate::image::GrayImage;
use crate::matching::DMatch;
use crate::sift::KeyPoint;
use image::Rgb;

pub const CORRECT: Rgb<u8> = Rgb([40, 200, 60]);
pub const WRONG: Rgb<u8> = Rgb([230, 40, 40]);
pub const UNJUDGED: Rgb<u8> = Rgb([60, 140, 255]);

/// Draws `matches` (query in `prev`, train in `cur`); `verdicts[i]` says
/// whether match i is correct. Wrong matches are drawn first, so the
/// correct ones stay visible where they cross.
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
    if verdicts.is_some_and(|v| v.len() != matches.len()) {
        return Err(Error::InvalidArgument("one verdict per match is needed".into()));
    }
    let colour = |i: usize| match verdicts {
        None => UNJUDGED,
        Some(v) if v[i] => CORRECT,
        Some(_) => WRONG,
    };
    let mut order: Vec<usize> = (0..matches.len()).collect();
    order.sort_by_key(|&i| verdicts.is_some_and(|v| v[i]));
    // 4 fractional bits, as drawMatches draws.
    let fx = |v: f32| (v * 16.0).round() as i64;
    for i in order {
        let m = matches[i];
        let (Some(a), Some(b)) = (prev.get(m.query_idx), cur.get(m.train_idx)) else {
            return Err(Error::InvalidArgument(format!(
                "match {i} names keypoints {} / {} but the frames have {} / {}",
                m.query_idx,
                m.train_idx,
                prev.len(),
                cur.len()
            )));
        };
        let c = colour(i);
        let (pa, pb) = ((fx(a.x), fx(a.y)), (fx(b.x + w1 as f32), fx(b.y)));
        circle(&mut out, pa, 3 * 16, c, 1, true, 4);
        circle(&mut out, pb, 3 * 16, c, 1, true, 4);
        line(&mut out, pa, pb, c, 1, true, 4);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lines_take_the_verdicts_colour() {
        let img = GrayImage::new(20, 10, vec![0; 200]).unwrap();
        let kp = |x: f32, y: f32| KeyPoint { x, y, size: 2.0, angle: 0.0, response: 0.0, octave: 0 };
        let (prev, cur) = (vec![kp(10.0, 2.0), kp(10.0, 7.0)], vec![kp(10.0, 2.0), kp(10.0, 7.0)]);
        let m = |q, t| DMatch { query_idx: q, train_idx: t, distance: 0.0 };
        let out = draw(&img, &prev, &img, &cur, &[m(0, 0), m(1, 1)], Some(&[true, false])).unwrap();
        assert_eq!((out.width(), out.height()), (40, 10));
        // Midway along each horizontal line (x = 20, the frames' seam): the
        // anti-aliased line over black is the colour scaled by its coverage.
        let hue = |p: &Rgb<u8>| {
            let [r, g, b] = p.0;
            if g > r && g > b {
                "green"
            } else if r > g && r > b {
                "red"
            } else if b > r && b > g {
                "blue"
            } else {
                "none"
            }
        };
        assert_eq!(hue(out.get_pixel(20, 2)), "green");
        assert_eq!(hue(out.get_pixel(20, 7)), "red");
        let plain = draw(&img, &prev, &img, &cur, &[m(0, 0)], None).unwrap();
        assert_eq!(hue(plain.get_pixel(20, 2)), "blue");
        assert!(draw(&img, &prev, &img, &cur, &[m(0, 5)], None).is_err());
    }
}
