//! A [`Scene`] drawn into an RGB image with the crate's own primitives
//! (anti-aliased `cv2.line`-style strokes, the 5×7 font), for PNG: no
//! vector-graphics dependency.

use super::{dash::segments, Anchor, Color, Dash, Marker, Scene, Shape};
use crate::render::draw::{circle, fill_convex, fill_rect, line};
use crate::render::font::{draw_text, text_size};
use image::{Rgb, RgbImage};

/// Sub-pixel bits of the coordinates handed to `line` and `circle`.
const SHIFT: u32 = 4;

fn fixed(v: f64) -> i64 {
    (v * (1 << SHIFT) as f64).round() as i64
}

fn px(c: &Color) -> Rgb<u8> {
    Rgb(*c)
}

fn stroke(img: &mut RgbImage, a: (f64, f64), b: (f64, f64), c: &Color, width: f64) {
    let w = width.round().max(1.0) as i64;
    line(img, (fixed(a.0), fixed(a.1)), (fixed(b.0), fixed(b.1)), px(c), w, true, SHIFT);
}

/// A polyline with its dash. The lines end in round caps of half their width
/// where SVG's are flat, so each dash is shortened by the cap at both ends to
/// keep the SVG's pattern (a dash no longer than the width becomes a dot).
fn dashed(img: &mut RgbImage, points: &[(f64, f64)], c: &Color, width: f64, dash: Dash) {
    let cap = if dash.is_empty() { 0.0 } else { width.round().max(1.0) / 2.0 };
    for (a, b) in segments(points, dash) {
        let len = (b.0 - a.0).hypot(b.1 - a.1);
        let k = if len > 0.0 { (cap / len).min(0.5) } else { 0.0 };
        let (p, q) = ((a.0 + (b.0 - a.0) * k, a.1 + (b.1 - a.1) * k), (b.0 - (b.0 - a.0) * k, b.1 - (b.1 - a.1) * k));
        stroke(img, p, q, c, width);
    }
}

/// A marker as the SVG draws it: filled, ringed in black; the cross as two strokes.
fn mark(img: &mut RgbImage, center: (f64, f64), r: f64, marker: Marker, fill: &Color) {
    const BLACK: Color = [0, 0, 0];
    match marker {
        Marker::None => {}
        Marker::Circle => {
            let c = (fixed(center.0), fixed(center.1));
            circle(img, c, fixed(r), px(fill), -1, true, SHIFT);
            circle(img, c, fixed(r), px(&BLACK), 1, true, SHIFT);
        }
        Marker::Cross => {
            for (a, b) in Marker::cross(center, r) {
                stroke(img, a, b, fill, 2.0);
            }
        }
        m => {
            let pts = m.polygon(center, r);
            let v: Vec<(i64, i64)> = pts.iter().map(|p| (fixed(p.0), fixed(p.1))).collect();
            fill_convex(img, &v, px(fill), true, SHIFT);
            let mut ring = pts.clone();
            ring.extend(pts.first());
            for w in ring.windows(2) {
                stroke(img, w[0], w[1], &BLACK, 1.0);
            }
        }
    }
}

/// Draws every shape in order.
pub fn rasterize(scene: &Scene) -> RgbImage {
    let mut img = RgbImage::new(scene.width.max(1), scene.height.max(1));
    for s in &scene.shapes {
        match s {
            Shape::Rect { x, y, w, h, fill, stroke: edge } => {
                let (x0, y0, x1, y1) =
                    (x.round() as i64, y.round() as i64, (x + w).round() as i64 - 1, (y + h).round() as i64 - 1);
                fill_rect(&mut img, (x0, y0), (x1, y1), px(fill));
                if let Some(c) = edge {
                    let (a, b) = ((x0 as f64, y0 as f64), (x1 as f64, y1 as f64));
                    for (p, q) in [(a, (b.0, a.1)), ((b.0, a.1), b), (b, (a.0, b.1)), ((a.0, b.1), a)] {
                        line(&mut img, (p.0 as i64, p.1 as i64), (q.0 as i64, q.1 as i64), px(c), 1, false, 0);
                    }
                }
            }
            Shape::Line { from, to, color, width, dash } => dashed(&mut img, &[*from, *to], color, *width, dash),
            Shape::Polyline { points, color, width, dash } => dashed(&mut img, points, color, *width, dash),
            Shape::Mark { center, r, marker, fill } => mark(&mut img, *center, *r, *marker, fill),
            Shape::Circle { center, r, fill, stroke: edge } => {
                let c = (fixed(center.0), fixed(center.1));
                circle(&mut img, c, fixed(*r), px(fill), -1, true, SHIFT);
                if let Some(e) = edge {
                    circle(&mut img, c, fixed(*r), px(e), 1, true, SHIFT);
                }
            }
            Shape::Text { at, text, size, anchor, color } => {
                let scale = (size / 7.0).round().max(1.0) as u32;
                let w = text_size(text, scale).0 as f64;
                let x = match anchor {
                    Anchor::Start => at.0,
                    Anchor::Middle => at.0 - w / 2.0,
                    Anchor::End => at.0 - w,
                };
                draw_text(&mut img, text, x.round() as i64, at.1.round() as i64, scale, px(color));
            }
        }
    }
    img
}

#[cfg(test)]
mod tests {
    use super::super::{Anchor, Marker, Scene, Shape};
    use super::*;

    #[test]
    fn shapes_land_where_the_svg_puts_them() {
        let mut s = Scene::new(60, 40);
        s.shapes.push(Shape::Line { from: (5.0, 10.0), to: (55.0, 10.0), color: [255, 0, 0], width: 1.0, dash: &[] });
        // Dashed: 4 on, 4 off from x = 5 (each dash less its round caps), so x = 11
        // is in a gap and x = 15 on a dash.
        s.shapes.push(Shape::Line {
            from: (5.0, 38.0),
            to: (55.0, 38.0),
            color: [255, 0, 0],
            width: 1.0,
            dash: &[4.0, 4.0],
        });
        s.shapes.push(Shape::Mark { center: (15.0, 25.0), r: 4.0, marker: Marker::Square, fill: [0, 255, 0] });
        s.shapes.push(Shape::Circle { center: (30.0, 30.0), r: 4.0, fill: [0, 0, 255], stroke: None });
        s.shapes.push(Shape::text((59.0, 20.0), "1", 7.0, Anchor::End, [0, 0, 0]));
        let img = rasterize(&s);
        assert_eq!(img.dimensions(), (60, 40));
        assert_eq!(img.get_pixel(0, 0).0, [255, 255, 255]);
        // Anti-aliased: the row the line runs along is nearly pure red.
        let p = img.get_pixel(30, 10).0;
        assert!(p[0] == 255 && p[1] < 60 && p[1] == p[2], "{p:?}");
        assert_eq!(img.get_pixel(30, 30).0, [0, 0, 255]);
        // "1" ends at x = 59: its glyph (5 px wide) spans 54..58, rows 13..19.
        assert!((13..20).any(|y| img.get_pixel(56, y).0 == [0, 0, 0]));
        assert!((0..40).all(|y| img.get_pixel(53, y).0 != [0, 0, 0]));
        assert_eq!(img.get_pixel(11, 38).0, [255, 255, 255]);
        let d = img.get_pixel(15, 38).0;
        assert!(d[0] == 255 && d[1] < 100, "{d:?}");
        assert_eq!(img.get_pixel(15, 25).0, [0, 255, 0]);
    }
}
