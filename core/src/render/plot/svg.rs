//! A [`Scene`] as a standalone SVG document (the app shows and exports the
//! same text the CLI writes).

use super::{Anchor, Color, Dash, Marker, Scene, Shape};
use std::fmt::Write as _;

/// `&`, `<`, `>` and `"` as XML entities, for text and attribute values.
pub fn escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            c => out.push(c),
        }
    }
    out
}

fn rgb(c: &Color) -> String {
    format!("#{:02x}{:02x}{:02x}", c[0], c[1], c[2])
}

/// Coordinates with two decimals: sub-pixel is plenty, and the file stays small.
fn n(v: f64) -> String {
    let s = format!("{v:.2}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" {
        "0".into()
    } else {
        s.to_string()
    }
}

/// ` stroke-dasharray="…"`, or nothing for a solid line.
fn dasharray(dash: Dash) -> String {
    if dash.is_empty() {
        return String::new();
    }
    let v: Vec<String> = dash.iter().map(|d| n(*d)).collect();
    format!(" stroke-dasharray=\"{}\"", v.join(" "))
}

/// A marker: ringed in black like the figures' other discs, the cross as
/// two strokes of its colour.
fn mark(o: &mut String, center: (f64, f64), r: f64, marker: Marker, fill: &Color) {
    let _ = match marker {
        Marker::None => Ok(()),
        Marker::Circle => write!(
            o,
            "<circle cx=\"{}\" cy=\"{}\" r=\"{}\" fill=\"{}\" stroke=\"#000000\" stroke-width=\"1\"/>",
            n(center.0),
            n(center.1),
            n(r),
            rgb(fill)
        ),
        Marker::Cross => {
            let d: Vec<String> = Marker::cross(center, r)
                .iter()
                .map(|(a, b)| format!("M{} {}L{} {}", n(a.0), n(a.1), n(b.0), n(b.1)))
                .collect();
            write!(o, "<path d=\"{}\" fill=\"none\" stroke=\"{}\" stroke-width=\"2.5\"/>", d.concat(), rgb(fill))
        }
        m => {
            let pts: Vec<String> = m.polygon(center, r).iter().map(|p| format!("{},{}", n(p.0), n(p.1))).collect();
            write!(
                o,
                "<polygon points=\"{}\" fill=\"{}\" stroke=\"#000000\" stroke-width=\"1\"/>",
                pts.join(" "),
                rgb(fill)
            )
        }
    };
}

/// The SVG text of `scene`; `test_id` (if any) becomes the root's `data-testid`.
pub fn to_svg(scene: &Scene, test_id: Option<&str>) -> String {
    let mut o = String::new();
    let id = test_id.map_or(String::new(), |t| format!(" data-testid=\"{}\"", escape(t)));
    let _ = write!(
        o,
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" viewBox=\"0 0 {w} {h}\"{id} \
         font-family=\"DejaVu Sans Mono, Menlo, Consolas, monospace\">",
        w = scene.width,
        h = scene.height
    );
    for s in &scene.shapes {
        match s {
            Shape::Rect { x, y, w, h, fill, stroke } => {
                let st = stroke.map_or(String::new(), |c| format!(" stroke=\"{}\"", rgb(&c)));
                let _ = write!(
                    o,
                    "<rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\" fill=\"{}\"{st}/>",
                    n(*x),
                    n(*y),
                    n(*w),
                    n(*h),
                    rgb(fill)
                );
            }
            Shape::Line { from, to, color, width, dash } => {
                let _ = write!(
                    o,
                    "<line x1=\"{}\" y1=\"{}\" x2=\"{}\" y2=\"{}\" stroke=\"{}\" stroke-width=\"{}\"{}/>",
                    n(from.0),
                    n(from.1),
                    n(to.0),
                    n(to.1),
                    rgb(color),
                    n(*width),
                    dasharray(dash)
                );
            }
            Shape::Polyline { points, color, width, dash } => {
                let pts: Vec<String> = points.iter().map(|p| format!("{},{}", n(p.0), n(p.1))).collect();
                let _ = write!(
                    o,
                    "<polyline points=\"{}\" fill=\"none\" stroke=\"{}\" stroke-width=\"{}\" stroke-linejoin=\"round\"{}/>",
                    pts.join(" "),
                    rgb(color),
                    n(*width),
                    dasharray(dash)
                );
            }
            Shape::Mark { center, r, marker, fill } => mark(&mut o, *center, *r, *marker, fill),
            Shape::Circle { center, r, fill, stroke } => {
                let st = stroke.map_or(String::new(), |c| format!(" stroke=\"{}\" stroke-width=\"1.5\"", rgb(&c)));
                let _ = write!(
                    o,
                    "<circle cx=\"{}\" cy=\"{}\" r=\"{}\" fill=\"{}\"{st}/>",
                    n(center.0),
                    n(center.1),
                    n(*r),
                    rgb(fill)
                );
            }
            Shape::Text { at, text, size, anchor, color } => {
                let a = match anchor {
                    Anchor::Start => "start",
                    Anchor::Middle => "middle",
                    Anchor::End => "end",
                };
                let _ = write!(
                    o,
                    "<text x=\"{}\" y=\"{}\" font-size=\"{}\" text-anchor=\"{a}\" fill=\"{}\">{}</text>",
                    n(at.0),
                    n(at.1),
                    n(*size),
                    rgb(color),
                    escape(text)
                );
            }
        }
    }
    o.push_str("</svg>\n");
    o
}

#[cfg(test)]
mod tests {
    use super::super::{Anchor, Marker, Scene, Shape};
    use super::*;

    #[test]
    fn svg_text_is_escaped_and_compact() {
        let mut s = Scene::new(100, 50);
        s.shapes.push(Shape::text((10.0, 20.5), "a<b & \"c\"", 14.0, Anchor::End, [0, 0, 0]));
        s.shapes.push(Shape::Polyline {
            points: vec![(0.0, -0.001), (1.25, 2.0)],
            color: [255, 0, 16],
            width: 2.0,
            dash: &[9.0, 3.5],
        });
        s.shapes.push(Shape::Mark { center: (5.0, 5.0), r: 2.0, marker: Marker::Diamond, fill: [0, 114, 178] });
        let svg = to_svg(&s, Some("plot"));
        assert!(svg.starts_with("<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"100\" height=\"50\" viewBox=\"0 0 100 50\" data-testid=\"plot\""), "{svg}");
        assert!(svg.contains("<rect x=\"0\" y=\"0\" width=\"100\" height=\"50\" fill=\"#ffffff\"/>"), "{svg}");
        assert!(svg.contains(">a&lt;b &amp; &quot;c&quot;</text>") && svg.contains("x=\"10\" y=\"20.5\""), "{svg}");
        assert!(svg.contains("points=\"0,0 1.25,2\"") && svg.contains("stroke=\"#ff0010\""), "{svg}");
        assert!(svg.contains("stroke-linejoin=\"round\" stroke-dasharray=\"9 3.5\"/>"), "{svg}");
        assert!(svg.contains("<polygon points=\"5,3 7,5 5,7 3,5\" fill=\"#0072b2\""), "{svg}");
        assert!(svg.ends_with("</svg>\n"));
    }
}
