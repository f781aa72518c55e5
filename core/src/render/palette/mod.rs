//! The one palette of siftlab's figures for people: the CLI's `--plot` and
//! `matches.png`, and everything the app draws or colours in its styles.
//! Colours are Okabe & Ito's eight ("Color Universal Design", 2008), chosen so
//! that the pairs that carry meaning stay apart for protanopes and
//! deuteranopes too (`cvd.rs` checks it with Machado et al.'s simulation).
//! Colour is never the only cue: every set that carries meaning also differs
//! in line dash or marker shape, and the legends show both (WCAG 1.4.1).
//!
//! The lab's own pictures (`view_feature`, `view_info`, `view_trajectory`)
//! do not use this palette: they are OpenCV's, byte for byte.

#[cfg(test)]
mod cvd;

use crate::matching::StrategyKind;

/// An sRGB colour.
pub type Color = [u8; 3];

/// A dash pattern in px (on, off, on, …) for a line 2 px wide; empty is solid.
pub type Dash = &'static [f64];

/// Okabe & Ito's colours, by their names.
pub const BLACK: Color = [0x00, 0x00, 0x00];
pub const ORANGE: Color = [0xe6, 0x9f, 0x00];
pub const SKY_BLUE: Color = [0x56, 0xb4, 0xe9];
pub const BLUISH_GREEN: Color = [0x00, 0x9e, 0x73];
pub const YELLOW: Color = [0xf0, 0xe4, 0x42];
pub const BLUE: Color = [0x00, 0x72, 0xb2];
pub const VERMILLION: Color = [0xd5, 0x5e, 0x00];
pub const REDDISH_PURPLE: Color = [0xcc, 0x79, 0xa7];

/// Vermillion darkened for text: the plain one reads at 3.4:1 on the page's
/// error background, below WCAG's 4.5:1; this one at 5.0:1, same hue.
pub const VERMILLION_TEXT: Color = [0xa8, 0x4a, 0x00];

/// The light grey the highlighted members of a chart stand out from (the
/// distances a strategy did not keep): apart from [`BLUE`] in lightness.
pub const REST: Color = [0xc4, 0xcc, 0xd6];

pub const SOLID: Dash = &[];

/// A point's symbol.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Marker {
    None,
    Circle,
    Square,
    Triangle,
    Diamond,
    /// An × of two strokes (no fill).
    Cross,
}

impl Marker {
    /// The corners of a polygon marker of "radius" `r` around `c` (a square's
    /// half side, the others' circumradius), clockwise on screen; empty for the
    /// circle, the cross and none, which are not polygons.
    pub fn polygon(self, c: (f64, f64), r: f64) -> Vec<(f64, f64)> {
        let (x, y) = c;
        match self {
            // The square a little smaller: at the same r it looks heavier than the rest.
            Marker::Square => {
                let s = r * 0.85;
                vec![(x - s, y - s), (x + s, y - s), (x + s, y + s), (x - s, y + s)]
            }
            Marker::Triangle => {
                let (dx, dy) = (r * 0.866, r * 0.5);
                vec![(x, y - r), (x + dx, y + dy), (x - dx, y + dy)]
            }
            Marker::Diamond => vec![(x, y - r), (x + r, y), (x, y + r), (x - r, y)],
            Marker::None | Marker::Circle | Marker::Cross => Vec::new(),
        }
    }

    /// The two strokes of the cross of radius `r` around `c`.
    pub fn cross(c: (f64, f64), r: f64) -> [((f64, f64), (f64, f64)); 2] {
        let s = r * 0.75;
        [((c.0 - s, c.1 - s), (c.0 + s, c.1 + s)), ((c.0 - s, c.1 + s), (c.0 + s, c.1 - s))]
    }

    /// An SVG path of this marker at every (x, y) in `xy` (one element for
    /// thousands of points), outlines only: the app's overlays stroke it.
    pub fn svg_path(self, xy: &[f32], r: f64) -> String {
        let mut d = String::with_capacity(xy.len() * 24);
        for p in xy.chunks_exact(2) {
            let c = (p[0] as f64, p[1] as f64);
            match self {
                Marker::None => {}
                Marker::Circle => d.push_str(&format!(
                    "M{:.1} {:.1}a{r} {r} 0 1 0 {:.1} 0a{r} {r} 0 1 0 {:.1} 0",
                    c.0 - r,
                    c.1,
                    2.0 * r,
                    -2.0 * r
                )),
                Marker::Cross => {
                    for (a, b) in Marker::cross(c, r) {
                        d.push_str(&format!("M{:.1} {:.1}L{:.1} {:.1}", a.0, a.1, b.0, b.1));
                    }
                }
                m => {
                    for (k, q) in m.polygon(c, r).iter().enumerate() {
                        d.push_str(&format!("{}{:.1} {:.1}", if k == 0 { 'M' } else { 'L' }, q.0, q.1));
                    }
                    d.push('Z');
                }
            }
        }
        d
    }

    /// The name a legend may say ("circle", …).
    pub fn name(self) -> &'static str {
        match self {
            Marker::None => "no marker",
            Marker::Circle => "circle",
            Marker::Square => "square",
            Marker::Triangle => "triangle",
            Marker::Diamond => "diamond",
            Marker::Cross => "cross",
        }
    }
}

/// How one member of a set is drawn: colour, dash and marker.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Style {
    pub color: Color,
    pub dash: Dash,
    pub marker: Marker,
}

impl Style {
    /// The dash as SVG's `stroke-dasharray` value (`None` when solid).
    pub fn dasharray(&self) -> Option<String> {
        (!self.dash.is_empty()).then(|| self.dash.iter().map(|v| format!("{v}")).collect::<Vec<_>>().join(" "))
    }
}

const fn style(color: Color, dash: Dash, marker: Marker) -> Style {
    Style { color, dash, marker }
}

/// Whole-frame matches the true geometry calls correct: solid, circled ends.
pub const CORRECT: Style = style(SKY_BLUE, SOLID, Marker::Circle);
/// … and wrong: dashed, crossed ends.
pub const WRONG: Style = style(VERMILLION, &[8.0, 5.0], Marker::Cross);
/// Matches of a pair without ground truth (never shown beside the other two).
pub const UNJUDGED: Style = style(YELLOW, SOLID, Marker::Circle);

/// The odometry's own view, over the camera frame: each point's flow from
/// the previous frame, solid with a circle where findEssentialMat's RANSAC
/// kept it, dashed with a cross where it did not (the whole-frame view's
/// correct and wrong, as the same idea: consistent with one motion or not),
/// and the points the loop re-detected on this frame as small diamonds.
pub const INLIER: Style = style(SKY_BLUE, SOLID, Marker::Circle);
pub const OUTLIER: Style = style(VERMILLION, &[4.0, 3.0], Marker::Cross);
pub const REDETECTED: Style = style(YELLOW, SOLID, Marker::Diamond);

/// The whole-frame view's picked match (drawn over the others) and its
/// epipolar line in the current frame: yellow, the line dashed.
pub const PICKED: Style = style(YELLOW, SOLID, Marker::Square);
pub const EPIPOLAR: Style = style(YELLOW, &[10.0, 6.0], Marker::None);

/// The ground-truth trajectory: black and solid, the one line without dashes.
pub const TRUTH: Style = style(BLACK, SOLID, Marker::None);
/// The odometry's trackers in the comparison's order, LK, dt, nn, nndr: four
/// colours, four dashes (long, dotted, dash-dot, short) and four markers. The
/// strategies wear the same style wherever they appear (the trade-off chart).
pub const TRACKERS: [Style; 4] = [
    style(VERMILLION, &[12.0, 4.0], Marker::Circle),
    style(BLUE, &[2.0, 3.0], Marker::Square),
    style(BLUISH_GREEN, &[9.0, 3.0, 2.0, 3.0], Marker::Triangle),
    style(SKY_BLUE, &[6.0, 3.0], Marker::Diamond),
];

/// The style of a tracker: `None` for the lab's LK, else its strategy's.
pub fn tracker(kind: Option<StrategyKind>) -> Style {
    match kind {
        None => TRACKERS[0],
        Some(k) => strategy(k),
    }
}

/// A strategy's style (dt, nn, nndr): the tracker's of the same name.
pub fn strategy(kind: StrategyKind) -> Style {
    match kind {
        StrategyKind::Dt => TRACKERS[1],
        StrategyKind::Nn => TRACKERS[2],
        StrategyKind::Nndr => TRACKERS[3],
    }
}

/// SIFT's anatomy: the points of a stage, then the refinement's four reasons
/// to drop a candidate (no convergence, left the border, low contrast,
/// edge-like), shown together over the frame.
pub const STAGE_POINTS: Style = style(BLUISH_GREEN, SOLID, Marker::Circle);
pub const DROPS: [Style; 4] = [
    style(BLUE, SOLID, Marker::Square),
    style(YELLOW, SOLID, Marker::Triangle),
    style(SKY_BLUE, SOLID, Marker::Diamond),
    style(VERMILLION, SOLID, Marker::Cross),
];

/// The frames view, over the photographs: the selected keypoint (a circle
/// with its orientation line) and `view_info`'s points (dashed circles, so
/// the two differ in more than colour where they meet at the query).
pub const SELECTED: Style = style(YELLOW, SOLID, Marker::Circle);
pub const INFO: Style = style(BLUISH_GREEN, &[4.0, 3.0], Marker::Circle);

/// Match lines of the selected keypoint in the frames view, one colour per
/// successive match: they only tell lines apart, as drawMatchesKnn's random colours.
pub const SERIES: [Color; 5] = [VERMILLION, SKY_BLUE, ORANGE, REDDISH_PURPLE, BLUISH_GREEN];

/// The colours `www/styles.css` declares as custom properties, by name, for
/// what the page colours through its stylesheet (the figures' lines and
/// markers take the styles above directly). A test reads the stylesheet and
/// checks each value against these.
pub const CSS: &[(&str, Color)] = &[
    // The frames view: the selected keypoint, view_info's points, all keypoints.
    ("--c-selected", SELECTED.color),
    ("--c-info", INFO.color),
    ("--c-keypoints", SKY_BLUE),
    // Charts: the kept distances and the histogram's peaks against the rest
    // and the thresholds (dark blue against light grey: apart in lightness).
    ("--c-kept", BLUE),
    ("--c-rest", REST),
    ("--c-threshold", VERMILLION),
    // Text that says right or wrong, beside a ✓ or ✗ (readable at ≥ 4.5:1).
    ("--c-ok-text", BLUE),
    ("--c-bad-text", VERMILLION_TEXT),
];

/// `#rrggbb`.
pub fn hex(c: Color) -> String {
    format!("#{:02x}{:02x}{:02x}", c[0], c[1], c[2])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn markers_and_dashes_as_svg() {
        assert_eq!(Marker::Circle.svg_path(&[10.0, 5.0], 2.0), "M8.0 5.0a2 2 0 1 0 4.0 0a2 2 0 1 0 -4.0 0");
        assert_eq!(Marker::Diamond.svg_path(&[10.0, 5.0], 2.0), "M10.0 3.0L12.0 5.0L10.0 7.0L8.0 5.0Z");
        assert_eq!(Marker::Cross.svg_path(&[0.0, 0.0], 2.0), "M-1.5 -1.5L1.5 1.5M-1.5 1.5L1.5 -1.5");
        assert_eq!(Marker::Square.svg_path(&[], 2.0), "");
        assert_eq!(Marker::Triangle.polygon((0.0, 0.0), 2.0).len(), 3);
        assert_eq!(TRACKERS[2].dasharray().as_deref(), Some("9 3 2 3"));
        assert_eq!(TRUTH.dasharray(), None);
        assert_eq!(hex(VERMILLION), "#d55e00");
    }

    /// Colour is never the only cue: within each set every member differs
    /// from every other in dash or marker (both, for the trackers).
    #[test]
    fn every_set_differs_in_more_than_hue() {
        let sets: [&[Style]; 6] = [
            &[CORRECT, WRONG],
            &[TRUTH, TRACKERS[0], TRACKERS[1], TRACKERS[2], TRACKERS[3]],
            &DROPS,
            &[INLIER, OUTLIER, REDETECTED],
            &[PICKED, CORRECT, WRONG],
            &[PICKED, EPIPOLAR],
        ];
        for set in sets {
            for (i, a) in set.iter().enumerate() {
                for b in &set[i + 1..] {
                    assert!(a.dash != b.dash || a.marker != b.marker, "{a:?} vs {b:?}");
                }
            }
        }
        for (i, a) in TRACKERS.iter().enumerate() {
            assert!(!a.dash.is_empty(), "a tracker is dashed, the truth solid");
            for b in &TRACKERS[i + 1..] {
                assert!(a.dash != b.dash && a.marker != b.marker, "{a:?} vs {b:?}");
            }
        }
        assert!(DROPS.iter().all(|d| d.marker != STAGE_POINTS.marker));
        assert_ne!(SELECTED.dash, INFO.dash);
    }
}
