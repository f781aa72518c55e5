//! The marker's picture of a wrong value (PrairieLearn's `images[]`): both
//! frames side by side at half size (what fits a results file of 1 MB four
//! times over, as a JPEG), a title, a legend, and
//! - for dt / nn / nndr, one query feature's matches: those in the
//!   reference and the returned list ([`BOTH`], solid, circled ends), the
//!   reference's alone ([`MISSED`], dotted) and the returned alone
//!   ([`EXTRA`], dashed, crossed ends): three classes apart in colour *and*
//!   dash, as every figure of siftlab's;
//! - for matching_info, the reference's points (circles) and the returned
//!   ones (crosses).
//!
//! What it draws comes from a submission: indices that name no keypoint and
//! points off the frames are counted in the legend, never drawn.

use super::palette::{Marker, Style, SKY_BLUE, VERMILLION, YELLOW};
use super::whole_frame::{dashed_segment, end_marker};
use super::RgbImage;
use crate::image::GrayImage;
use crate::sift::KeyPoint;
use image::Rgb;

/// In the reference and returned.
pub const BOTH: Style = Style { color: SKY_BLUE, dash: &[], marker: Marker::Circle };
/// In the reference, not returned.
pub const MISSED: Style = Style { color: YELLOW, dash: &[3.0, 3.0], marker: Marker::Circle };
/// Returned, not in the reference.
pub const EXTRA: Style = Style { color: VERMILLION, dash: &[8.0, 5.0], marker: Marker::Cross };

const WHITE: Rgb<u8> = Rgb([255, 255, 255]);
/// Caption lines: 5x7 glyphs at scale 2, 6 px apart.
const LINE: i64 = 20;
/// A point on a frame or the canvas, in pixels.
type Point = (f64, f64);

/// How far past a frame's border a returned point may lie and still be drawn.
const MARGIN: f64 = 20.0;

/// The frame at half size: each 2 x 2 block's mean, rounded (odd edges dropped).
fn half(img: &GrayImage) -> RgbImage {
    let (w, h) = ((img.width() / 2).max(1), (img.height() / 2).max(1));
    let (sw, sh) = (img.width(), img.height());
    let px = |x: usize, y: usize| img.data()[y.min(sh - 1) * sw + x.min(sw - 1)] as u32;
    RgbImage::from_fn(w as u32, h as u32, |x, y| {
        let (x, y) = (2 * x as usize, 2 * y as usize);
        let v = ((px(x, y) + px(x + 1, y) + px(x, y + 1) + px(x + 1, y + 1) + 2) / 4) as u8;
        Rgb([v, v, v])
    })
}

/// The canvas: the caption's `lines` above both frames at half size; the
/// frames' origin (y) and the current frame's x offset.
fn canvas(prev: &GrayImage, cur: &GrayImage, lines: &[(String, Rgb<u8>)]) -> (RgbImage, i64, i64) {
    let (a, b) = (half(prev), half(cur));
    let top = LINE * lines.len() as i64 + 6;
    let mut out = RgbImage::new(a.width() + b.width(), top as u32 + a.height().max(b.height()));
    for (i, (text, colour)) in lines.iter().enumerate() {
        super::font::draw_text(&mut out, text, 6, LINE * (i as i64 + 1), 2, *colour);
    }
    image::imageops::replace(&mut out, &a, 0, top);
    image::imageops::replace(&mut out, &b, a.width() as i64, top);
    (out, top, a.width() as i64)
}

/// Where a point of a frame of size `w` x `h` lands on the canvas, if on
/// (or near) the frame: `None` for NaN, infinities and far-off values.
fn place(p: (f64, f64), w: usize, h: usize, x0: i64, y0: i64) -> Option<(f64, f64)> {
    let on = |v: f64, n: usize| v.is_finite() && v >= -MARGIN && v <= n as f64 + MARGIN;
    (on(p.0, w) && on(p.1, h)).then(|| (x0 as f64 + p.0 / 2.0, y0 as f64 + p.1 / 2.0))
}

/// One query feature's matches as (queryIdx, trainIdx) into `prev` and
/// `cur`: in both lists, the reference's only, the returned one's only
/// (what is drawn); `counts` the whole lists' three numbers, for the
/// legend. `title` is the call.
#[allow(clippy::too_many_arguments)]
pub fn matches(
    prev_image: &GrayImage,
    prev: &[KeyPoint],
    cur_image: &GrayImage,
    cur: &[KeyPoint],
    title: &str,
    feature: usize,
    shown: [&[(i64, i64)]; 3],
    counts: (usize, usize, usize),
) -> RgbImage {
    let key =
        |kps: &[KeyPoint], i: i64| usize::try_from(i).ok().and_then(|i| kps.get(i)).map(|k| (k.x as f64, k.y as f64));
    // Reference first, the returned-only last: the student's extra lines on top.
    let mut lines: Vec<(Point, Point, Style)> = Vec::new();
    let mut nowhere = 0;
    for (list, st) in shown.iter().zip([BOTH, MISSED, EXTRA]) {
        for &(q, t) in *list {
            match (key(prev, q), key(cur, t)) {
                (Some(a), Some(b)) => lines.push((a, b, st)),
                _ => nowhere += 1,
            }
        }
    }
    let (both, missed, extra) = counts;
    let mut legend =
        format!("blue: expected and returned ({both})  yellow dots: expected only ({missed})  red dashes: returned only ({extra})");
    if nowhere > 0 {
        legend.push_str(&format!(", {nowhere} naming no keypoint"));
    }
    let head = format!("{title}: feature {feature} (white square)");
    let caption = [(head, WHITE), (legend, WHITE)];
    let (mut out, top, x1) = canvas(prev_image, cur_image, &caption);
    let (pw, ph, cw, ch) = (prev_image.width(), prev_image.height(), cur_image.width(), cur_image.height());
    // The query feature, whether or not any list has a match for it.
    if let Some(c) = key(prev, feature as i64).and_then(|p| place(p, pw, ph, 0, top)) {
        let (x, y) = (c.0.round() as i64, c.1.round() as i64);
        let c = [(x - 6, y - 6), (x + 6, y - 6), (x + 6, y + 6), (x - 6, y + 6)];
        for i in 0..4 {
            super::draw::line(&mut out, c[i], c[(i + 1) % 4], WHITE, 1, false, 0);
        }
    }
    for (a, b, st) in &lines {
        if let (Some(a), Some(b)) = (place(*a, pw, ph, 0, top), place(*b, cw, ch, x1, top)) {
            dashed_segment(&mut out, a, b, st);
            end_marker(&mut out, a, st, 3.0);
            end_marker(&mut out, b, st, 3.0);
        }
    }
    out
}

/// matching_info's points: the reference's query and matched points
/// (circles) and the returned ones (crosses), or the returned value's
/// shape is not the tuple's (`returned` None).
pub fn info(
    prev_image: &GrayImage,
    cur_image: &GrayImage,
    title: &str,
    expected: ((i64, i64), &[(i64, i64)]),
    returned: Option<(Point, &[Point])>,
) -> RgbImage {
    let (pw, ph, cw, ch) = (prev_image.width(), prev_image.height(), cur_image.width(), cur_image.height());
    let mut legend = format!("blue circles: expected (the query and {} points)", expected.1.len());
    if let Some((q, pts)) = returned {
        let far = |p: &(f64, f64), w, h| place(*p, w, h, 0, 0).is_none();
        let off = usize::from(far(&q, pw, ph)) + pts.iter().filter(|p| far(p, cw, ch)).count();
        legend.push_str(&format!("  red crosses: returned (the query and {} points", pts.len()));
        legend.push_str(&if off > 0 { format!(", {off} off the frames)") } else { ")".into() });
    } else {
        legend.push_str("  returned: not ((x, y), [(x, y), ...], [d, ...])");
    }
    let mut caption = vec![(title.to_string(), WHITE), (legend, WHITE)];
    // A coordinate off by one is a pixel at half size: the first that
    // differs, in numbers.
    if let Some((q, pts)) = returned {
        let f = |(x, y): (i64, i64)| (x as f64, y as f64);
        let show = |p: (f64, f64)| format!("({}, {})", p.0, p.1);
        let first = std::iter::once((f(expected.0), Some(q), "query".to_string()))
            .chain((0..expected.1.len().max(pts.len())).map(|i| {
                (expected.1.get(i).map_or((f64::NAN, f64::NAN), |&p| f(p)), pts.get(i).copied(), format!("point {i}"))
            }))
            .find(|(e, g, _)| g.is_none_or(|g| g.0.to_bits() != e.0.to_bits() || g.1.to_bits() != e.1.to_bits()));
        if let Some((e, g, what)) = first {
            let e = if e.0.is_nan() { "none".to_string() } else { show(e) };
            caption.push((format!("{what}: expected {e}, returned {}", g.map_or("none".to_string(), show)), WHITE));
        }
    }
    let (mut out, top, x1) = canvas(prev_image, cur_image, &caption);
    let mark = |out: &mut RgbImage, p: (f64, f64), w, h, x0, st: &Style| {
        if let Some(c) = place(p, w, h, x0, top) {
            end_marker(out, c, st, 5.0);
        }
    };
    let f = |(x, y): (i64, i64)| (x as f64, y as f64);
    mark(&mut out, f(expected.0), pw, ph, 0, &BOTH);
    for &p in expected.1 {
        mark(&mut out, f(p), cw, ch, x1, &BOTH);
    }
    if let Some((q, pts)) = returned {
        mark(&mut out, q, pw, ph, 0, &EXTRA);
        for &p in pts {
            mark(&mut out, p, cw, ch, x1, &EXTRA);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::palette::Color;

    fn frame(w: usize, h: usize) -> GrayImage {
        GrayImage::new(w, h, (0..w * h).map(|i| (i % 7 * 10) as u8).collect()).unwrap()
    }

    fn kp(x: f32, y: f32) -> KeyPoint {
        KeyPoint { x, y, size: 2.0, angle: 0.0, response: 0.0, octave: 0 }
    }

    /// Whether any pixel has `c`'s hue (the frames are grey, the captions
    /// white; anti-aliasing blends a line's colour with the grey beneath):
    /// its channels in the colour's order and far apart as in the colour.
    fn has(img: &RgbImage, c: Color) -> bool {
        let order = |p: [u8; 3]| {
            let mut i = [0usize, 1, 2];
            i.sort_by_key(|&k| std::cmp::Reverse(p[k]));
            i
        };
        let spread = |p: [u8; 3]| p.iter().max().unwrap() - p.iter().min().unwrap();
        img.pixels().any(|p| {
            order(p.0) == order(c) && spread(p.0) as u32 * 2 > spread(c) as u32 && {
                // Yellow's two high channels stay close; vermillion's do not.
                let (hi, mid) = (p.0[order(c)[0]] as i32, p.0[order(c)[1]] as i32);
                let (chi, cmid) = (c[order(c)[0]] as i32, c[order(c)[1]] as i32);
                ((hi - mid) - (chi - cmid)).abs() < 40
            }
        })
    }

    #[test]
    fn halves_by_block_means() {
        let img = GrayImage::new(4, 2, vec![0, 2, 10, 10, 4, 6, 10, 11]).unwrap();
        let h = half(&img);
        assert_eq!((h.width(), h.height()), (2, 1));
        assert_eq!((h.get_pixel(0, 0).0[0], h.get_pixel(1, 0).0[0]), (3, 10));
    }

    #[test]
    fn three_classes_of_matches_and_nothing_from_bad_indices() {
        let (prev, cur) = (frame(200, 100), frame(200, 100));
        let kps = vec![kp(20.0, 20.0), kp(100.0, 50.0), kp(180.0, 80.0)];
        let both = matches(&prev, &kps, &cur, &kps, "dt", 0, [&[(0, 1)], &[], &[]], (1, 0, 0));
        assert!(has(&both, SKY_BLUE) && !has(&both, YELLOW) && !has(&both, VERMILLION));
        let all = matches(&prev, &kps, &cur, &kps, "dt", 0, [&[(0, 1)], &[(0, 2)], &[(0, 0)]], (1, 1, 1));
        assert!(has(&all, SKY_BLUE) && has(&all, YELLOW) && has(&all, VERMILLION));
        // Indices past the keypoints (or negative) draw nothing.
        let bad = matches(&prev, &kps, &cur, &kps, "dt", 0, [&[], &[], &[(0, 99), (-1, 0), (i64::MAX, 1)]], (0, 0, 3));
        assert!(!has(&bad, VERMILLION));
        // Two caption lines over the half-size frames side by side.
        assert_eq!((bad.width(), bad.height()), (200, 2 * LINE as u32 + 6 + 50));
    }

    #[test]
    fn info_draws_points_on_the_frames_only() {
        let (prev, cur) = (frame(200, 100), frame(200, 100));
        let ok = info(&prev, &cur, "matching_info", ((20, 20), &[(50, 50)]), Some(((20.0, 21.0), &[(60.0, 50.0)])));
        assert!(has(&ok, SKY_BLUE) && has(&ok, VERMILLION));
        let far = [(f64::NAN, 1.0), (1e300, 5.0), (-1e9, 0.0)];
        let off = info(&prev, &cur, "matching_info", ((20, 20), &[]), Some(((f64::INFINITY, 0.0), &far)));
        assert!(has(&off, SKY_BLUE) && !has(&off, VERMILLION));
        let none = info(&prev, &cur, "matching_info", ((20, 20), &[]), None);
        assert!(!has(&none, VERMILLION));
    }
}
