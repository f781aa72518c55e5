//! Plots for people rather than for fidelity: the trajectory seen from above
//! and the error per frame, with axes, ticks, grid and legend. A figure is
//! built once as a [`Scene`] of simple shapes in pixel coordinates
//! ([`figures`]), then written as SVG text ([`svg`]) or drawn into an RGB
//! image for PNG ([`raster`]), so the CLI's `--plot` and the app's figures
//! and exports are the same drawing. [`axes`] holds the scale arithmetic
//! (nice numbers, ticks, equal-axis fitting). The lab's own window stays in
//! `render::trajectory`.

pub mod axes;
pub mod dash;
pub mod figures;
pub mod raster;
pub mod svg;

pub use super::palette::{Color, Dash, Marker};

/// Where a text's x is: its start, middle or end (SVG's `text-anchor`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Anchor {
    Start,
    Middle,
    End,
}

/// One drawing element, in pixels from the top-left corner.
#[derive(Clone, Debug, PartialEq)]
pub enum Shape {
    /// A filled rectangle (x, y, w, h), optionally outlined.
    Rect {
        x: f64,
        y: f64,
        w: f64,
        h: f64,
        fill: Color,
        stroke: Option<Color>,
    },
    Line {
        from: (f64, f64),
        to: (f64, f64),
        color: Color,
        width: f64,
        dash: Dash,
    },
    Polyline {
        points: Vec<(f64, f64)>,
        color: Color,
        width: f64,
        dash: Dash,
    },
    /// A filled disc, optionally ringed.
    Circle {
        center: (f64, f64),
        r: f64,
        fill: Color,
        stroke: Option<Color>,
    },
    /// A point symbol of "radius" `r`, filled and ringed in black (a cross:
    /// strokes of `fill`'s colour).
    Mark {
        center: (f64, f64),
        r: f64,
        marker: Marker,
        fill: Color,
    },
    /// Text whose baseline starts, centres or ends at `at`; `size` is the
    /// glyph height in px (the raster font is 7 px a scale step).
    Text {
        at: (f64, f64),
        text: String,
        size: f64,
        anchor: Anchor,
        color: Color,
    },
}

/// A figure: its size and shapes in drawing order, plus what hover needs.
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    pub width: u32,
    pub height: u32,
    pub shapes: Vec<Shape>,
}

impl Scene {
    pub fn new(width: u32, height: u32) -> Scene {
        Scene {
            width,
            height,
            shapes: vec![Shape::Rect { x: 0.0, y: 0.0, w: width as f64, h: height as f64, fill: WHITE, stroke: None }],
        }
    }

    /// `other` placed below this scene (the CLI's one-file figure).
    pub fn stack(mut self, other: &Scene) -> Scene {
        let dy = self.height as f64;
        self.width = self.width.max(other.width);
        self.height += other.height;
        self.shapes.extend(other.shapes.iter().map(|s| s.shifted(0.0, dy)));
        self
    }
}

impl Shape {
    /// A [`Shape::Text`].
    pub fn text(at: (f64, f64), text: impl Into<String>, size: f64, anchor: Anchor, color: Color) -> Shape {
        Shape::Text { at, text: text.into(), size, anchor, color }
    }

    fn shifted(&self, dx: f64, dy: f64) -> Shape {
        let p = |(x, y): (f64, f64)| (x + dx, y + dy);
        match self.clone() {
            Shape::Rect { x, y, w, h, fill, stroke } => Shape::Rect { x: x + dx, y: y + dy, w, h, fill, stroke },
            Shape::Line { from, to, color, width, dash } => {
                Shape::Line { from: p(from), to: p(to), color, width, dash }
            }
            Shape::Polyline { points, color, width, dash } => {
                Shape::Polyline { points: points.into_iter().map(p).collect(), color, width, dash }
            }
            Shape::Circle { center, r, fill, stroke } => Shape::Circle { center: p(center), r, fill, stroke },
            Shape::Mark { center, r, marker, fill } => Shape::Mark { center: p(center), r, marker, fill },
            Shape::Text { at, text, size, anchor, color } => Shape::Text { at: p(at), text, size, anchor, color },
        }
    }
}

pub const WHITE: Color = [255, 255, 255];
pub const BLACK: Color = [0, 0, 0];
pub const GRID: Color = [222, 222, 222];
pub const AXIS: Color = [90, 90, 90];
