//! A [`Scene`] drawn into an RGB image with the crate's own primitives
//! (anti-aliased `cv2.line`-style strokes, the 5×7 font), for PNG: no
//! vector-graphics dependency.

use super::{Anchor, Color, Scene, Shape};
use crate::render::draw::{circle, fill_rect, line};
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
            Shape::Line { from, to, color, width } => stroke(&mut img, *from, *to, color, *width),
            Shape::Polyline { points, color, width } => {
                for w in points.windows(2) {
                    stroke(&mut img, w[0], w[1], color, *width);
                }
            }
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
    use super::super::{Anchor, Scene, Shape};
    use super::*;

    #[test]
    fn shapes_land_where_the_svg_puts_them() {
        let mut s = Scene::new(60, 40);
        s.shapes.push(Shape::Line { from: (5.0, 10.0), to: (55.0, 10.0), color: [255, 0, 0], width: 1.0 });
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
    }
}
