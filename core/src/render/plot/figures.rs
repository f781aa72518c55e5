//! The two figures: the trajectory from above and the position error per
//! frame, for any number of runs over the same ground truth.

use super::axes::{tick_label, tick_step, ticks, top_down, Map, TopDown};
use super::{Anchor, Color, Marker, Scene, Shape, AXIS, BLACK, GRID, WHITE};
use crate::render::palette::{self, Style, TRUTH};

/// One estimated trajectory and how to draw it.
#[derive(Clone, Debug, PartialEq)]
pub struct Run {
    pub name: String,
    pub style: Style,
    pub positions: Vec<[f64; 3]>,
}

/// Width of the figures' data lines (px).
const LINE: f64 = 2.0;
/// About this many markers along each run's line.
const MARKS: usize = 8;

/// Text size (px): the raster font at scale 2.
pub const TEXT: f64 = 14.0;
const MARGIN: (f64, f64, f64, f64) = (64.0, 16.0, 36.0, 48.0); // left, right, top, bottom

fn text(at: (f64, f64), s: impl Into<String>, anchor: Anchor, color: Color) -> Shape {
    Shape::text(at, s, TEXT, anchor, color)
}

/// The plot box inside a `w`×`h` figure: (left, top, width, height).
fn plot_box(w: u32, h: u32) -> (f64, f64, f64, f64) {
    let (l, r, t, b) = MARGIN;
    (l, t, (w as f64 - l - r).max(10.0), (h as f64 - t - b).max(10.0))
}

/// Width of `s` in px at the figures' text size (the raster font's advance,
/// which the SVG's sans-serif roughly matches).
pub fn text_width(s: &str) -> f64 {
    crate::render::font::text_size(s, (TEXT / 7.0) as u32).0 as f64
}

/// One axis of a plot box: its mapping, ticks and tick step.
struct Axis<'a> {
    map: &'a Map,
    ticks: &'a [f64],
    step: f64,
}

/// Grid, frame and tick labels of a plot box.
fn axes(s: &mut Scene, bx: (f64, f64, f64, f64), x: Axis, y: Axis) {
    let (l, t, w, h) = bx;
    for &v in x.ticks {
        let px = x.map.px(v);
        s.shapes.push(Shape::Line { from: (px, t), to: (px, t + h), color: GRID, width: 1.0, dash: &[] });
        s.shapes.push(text((px, t + h + 20.0), tick_label(v, x.step), Anchor::Middle, AXIS));
    }
    for &v in y.ticks {
        let py = y.map.px(v);
        s.shapes.push(Shape::Line { from: (l, py), to: (l + w, py), color: GRID, width: 1.0, dash: &[] });
        s.shapes.push(text((l - 6.0, py + TEXT / 2.0), tick_label(v, y.step), Anchor::End, AXIS));
    }
    let (r, b) = (l + w, t + h);
    for (from, to) in [((l, t), (r, t)), ((r, t), (r, b)), ((r, b), (l, b)), ((l, b), (l, t))] {
        s.shapes.push(Shape::Line { from, to, color: AXIS, width: 1.0, dash: &[] });
    }
}

/// A legend box in the top-left corner of the plot box: per entry a sample
/// of the line with its dash and marker, then the name.
fn legend(s: &mut Scene, bx: (f64, f64, f64, f64), entries: &[(String, Style)]) {
    let width = entries.iter().map(|(n, _)| text_width(n)).fold(0.0, f64::max) + 58.0;
    let (x, y) = (bx.0 + 8.0, bx.1 + 8.0);
    let row = TEXT + 8.0;
    s.shapes.push(Shape::Rect { x, y, w: width, h: row * entries.len() as f64 + 6.0, fill: WHITE, stroke: Some(AXIS) });
    for (k, (name, st)) in entries.iter().enumerate() {
        let cy = y + 4.0 + row * (k as f64 + 0.5);
        let (from, to) = ((x + 6.0, cy), (x + 42.0, cy));
        s.shapes.push(Shape::Line { from, to, color: st.color, width: LINE, dash: st.dash });
        s.shapes.push(mark((x + 24.0, cy), st));
        s.shapes.push(text((x + 50.0, cy + TEXT / 2.0), name.clone(), Anchor::Start, BLACK));
    }
}

fn mark(center: (f64, f64), st: &Style) -> Shape {
    Shape::Mark { center, r: 4.5, marker: st.marker, fill: st.color }
}

fn polyline(points: impl Iterator<Item = (f64, f64)>, st: &Style) -> Shape {
    let points = points.filter(|p| p.0.is_finite() && p.1.is_finite()).collect();
    Shape::Polyline { points, color: st.color, width: LINE, dash: st.dash }
}

/// A run's line, and its marker every few points: about [`MARKS`] of them,
/// run `k` of `n` shifted by k/n of a step so that runs that stay close do
/// not stack their markers.
fn run_line(s: &mut Scene, points: &[(f64, f64)], st: &Style, k: usize, n: usize) {
    s.shapes.push(polyline(points.iter().copied(), st));
    if st.marker == Marker::None {
        return;
    }
    let step = points.len().div_ceil(MARKS).max(2);
    let phase = step * k / n.max(1);
    for (i, p) in points.iter().enumerate().skip(1) {
        if i % step == phase && p.0.is_finite() && p.1.is_finite() {
            s.shapes.push(mark(*p, st));
        }
    }
}

/// The trajectory seen from above (x right, z forward up, equal metres),
/// truth and runs with a legend, the start and each run's current position.
/// Returns the scene and its mapping (for hover).
pub fn trajectory_figure(truth: &[[f64; 3]], runs: &[Run], w: u32, h: u32) -> (Scene, TopDown) {
    let mut s = Scene::new(w, h);
    let bx = plot_box(w, h);
    let all: Vec<[f64; 3]> = truth.iter().chain(runs.iter().flat_map(|r| &r.positions)).copied().collect();
    let td = top_down(&all, bx);
    let (xa, za) = (
        Axis { map: &td.x, ticks: &td.x_ticks, step: td.step },
        Axis { map: &td.z, ticks: &td.z_ticks, step: td.step },
    );
    axes(&mut s, bx, xa, za);
    s.shapes.push(text((bx.0 + bx.2 / 2.0, h as f64 - 10.0), "x (m)", Anchor::Middle, BLACK));
    s.shapes.push(text((bx.0, 24.0), "z (m), forward", Anchor::Start, BLACK));
    s.shapes.push(text((bx.0 + bx.2, 24.0), "trajectory, top view", Anchor::End, BLACK));
    let xz = |p: &[f64; 3]| (td.x.px(p[0]), td.z.px(p[2]));
    s.shapes.push(polyline(truth.iter().map(xz), &TRUTH));
    for (k, r) in runs.iter().enumerate() {
        let pts: Vec<(f64, f64)> = r.positions.iter().map(xz).collect();
        run_line(&mut s, &pts, &r.style, k, runs.len());
    }
    if let Some(p) = truth.first() {
        let c = xz(p);
        s.shapes.push(Shape::Circle { center: c, r: 6.0, fill: WHITE, stroke: Some(BLACK) });
        s.shapes.push(text((c.0 + 10.0, c.1 - 8.0), "start", Anchor::Start, BLACK));
    }
    // Each run's current position: its marker, larger.
    for r in runs {
        if let Some(p) = r.positions.last().filter(|p| p[0].is_finite() && p[2].is_finite()) {
            let m = if r.style.marker == Marker::None { Marker::Circle } else { r.style.marker };
            s.shapes.push(Shape::Mark { center: xz(p), r: 7.0, marker: m, fill: r.style.color });
        }
    }
    let mut entries = vec![("ground truth".to_string(), TRUTH)];
    entries.extend(runs.iter().map(|r| (r.name.clone(), r.style)));
    legend(&mut s, bx, &entries);
    (s, td)
}

/// The position error (m) of each run per frame. Returns the scene and its
/// (frame, error) mappings.
pub fn error_figure(errors: &[(String, Style, Vec<f64>)], w: u32, h: u32) -> (Scene, Map, Map) {
    let mut s = Scene::new(w, h);
    let bx = plot_box(w, h);
    let n = errors.iter().map(|e| e.2.len()).max().unwrap_or(0).max(2);
    let emax = errors.iter().flat_map(|e| e.2.iter().copied()).filter(|v| v.is_finite()).fold(0.0, f64::max);
    let (fstep, estep) = (tick_step(0.0, (n - 1) as f64, 8).max(1.0), tick_step(0.0, emax.max(1e-3), 5));
    let (ft, et) = (ticks(0.0, (n - 1) as f64, fstep), ticks(0.0, emax.max(1e-3), estep));
    let (ftop, etop) = (*ft.last().unwrap_or(&1.0), *et.last().unwrap_or(&1.0));
    let x = Map { offset: bx.0, scale: bx.2 / ftop };
    let y = Map { offset: bx.1 + bx.3, scale: -bx.3 / etop };
    axes(&mut s, bx, Axis { map: &x, ticks: &ft, step: fstep }, Axis { map: &y, ticks: &et, step: estep });
    s.shapes.push(text((bx.0 + bx.2 / 2.0, h as f64 - 10.0), "frame", Anchor::Middle, BLACK));
    s.shapes.push(text((bx.0, 24.0), "position error (m)", Anchor::Start, BLACK));
    for (k, (_, st, e)) in errors.iter().enumerate() {
        let pts: Vec<(f64, f64)> = e.iter().enumerate().map(|(i, v)| (x.px(i as f64), y.px(*v))).collect();
        run_line(&mut s, &pts, st, k, errors.len());
    }
    let entries: Vec<(String, Style)> = errors.iter().map(|e| (e.0.clone(), e.1)).collect();
    if entries.len() > 1 {
        legend(&mut s, bx, &entries);
    }
    (s, x, y)
}

/// Per frame, each run's distance to the truth (NaN where a run has no position).
pub fn run_errors(truth: &[[f64; 3]], runs: &[Run]) -> Vec<(String, Style, Vec<f64>)> {
    runs.iter()
        .map(|r| {
            let e = crate::vo::metrics::position_differences(&r.positions, truth);
            (r.name.clone(), r.style, e)
        })
        .collect()
}

/// The CLI's `--plot` figure and the app's export: the top view above the
/// error per frame, `w` px wide.
pub fn report_figure(truth: &[[f64; 3]], runs: &[Run], w: u32) -> Scene {
    let (top, _) = trajectory_figure(truth, runs, w, w);
    let (bottom, _, _) = error_figure(&run_errors(truth, runs), w, w * 3 / 8);
    top.stack(&bottom)
}

/// The name and style of a run: "LK" for the lab's tracker, else the
/// strategy as the lab writes it (`dt 200`, `nn`, `nndr 0.8`); the style is
/// the palette's for that tracker (colour, dash, marker).
pub fn run_style(strategy: Option<&crate::matching::Strategy>) -> (String, Style) {
    use crate::pyfmt::py_float;
    let style = palette::tracker(strategy.map(|s| s.kind()));
    match strategy {
        None => ("LK".into(), style),
        Some(s) => {
            let name = match s.threshold() {
                Some(t) => format!("{} {}", s.name(), py_float(t).trim_end_matches(".0")),
                None => s.name().to_string(),
            };
            (name, style)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn texts(s: &Scene) -> Vec<&str> {
        s.shapes
            .iter()
            .filter_map(|x| if let Shape::Text { text, .. } = x { Some(text.as_str()) } else { None })
            .collect()
    }

    #[test]
    fn trajectory_figure_has_axes_legend_start_and_current_position() {
        let truth: Vec<[f64; 3]> = (0..50).map(|i| [0.1 * i as f64, 0.0, i as f64]).collect();
        let est: Vec<[f64; 3]> = truth.iter().map(|p| [p[0] + 1.0, 0.0, p[2] * 0.9]).collect();
        let run = Run { name: "LK".into(), style: palette::TRACKERS[0], positions: est.clone() };
        let (s, td) = trajectory_figure(&truth, &[run], 640, 640);
        let t = texts(&s);
        for want in ["ground truth", "LK", "start", "x (m)", "0", "20", "40"] {
            assert!(t.contains(&want), "{want} in {t:?}");
        }
        // The current position: the run's marker at the estimate's last point.
        let last = (td.x.px(est[49][0]), td.z.px(est[49][2]));
        assert!(s
            .shapes
            .iter()
            .any(|x| matches!(x, Shape::Mark { center, marker: Marker::Circle, .. } if *center == last)));
        // The truth solid and black, the run dashed, with markers along it and in the legend.
        let lines: Vec<(Color, usize)> = s
            .shapes
            .iter()
            .filter_map(|x| if let Shape::Polyline { color, dash, .. } = x { Some((*color, dash.len())) } else { None })
            .collect();
        assert_eq!(lines, [(palette::BLACK, 0), (palette::VERMILLION, 2)]);
        let marks = s.shapes.iter().filter(|x| matches!(x, Shape::Mark { marker: Marker::Circle, .. })).count();
        assert!((8..=10).contains(&marks), "{marks} markers");
        // Every drawn point inside the figure.
        for sh in &s.shapes {
            if let Shape::Polyline { points, .. } = sh {
                assert!(points.iter().all(|p| (0.0..=640.0).contains(&p.0) && (0.0..=640.0).contains(&p.1)));
            }
        }
    }

    #[test]
    fn run_names_and_the_report() {
        use crate::matching::Strategy;
        assert_eq!(run_style(None).0, "LK");
        assert_eq!(run_style(Some(&Strategy::Dt(200.0))).0, "dt 200");
        assert_eq!(run_style(Some(&Strategy::Nndr(0.8))).0, "nndr 0.8");
        assert_eq!(run_style(Some(&Strategy::Nn(None))), ("nn".into(), palette::TRACKERS[2]));
        assert_eq!(run_style(None).1, palette::TRACKERS[0]);
        let truth = [[0.0, 0.0, 0.0], [0.0, 0.0, 1.0]];
        let run = Run { name: "LK".into(), style: palette::TRACKERS[0], positions: vec![[0.0; 3], [0.0, 0.0, 0.5]] };
        assert_eq!(run_errors(&truth, std::slice::from_ref(&run))[0].2, vec![0.0, 0.5]);
        let s = report_figure(&truth, &[run], 640);
        assert_eq!((s.width, s.height), (640, 880));
    }

    #[test]
    fn error_figure_scales_to_the_largest_error() {
        let (s, x, y) = error_figure(&[("LK".into(), palette::TRACKERS[0], vec![0.0, 0.5, 1.3])], 640, 240);
        assert_eq!(x.px(0.0), 64.0);
        assert_eq!(y.px(0.0), 240.0 - 48.0);
        assert!(y.px(1.3) > 36.0, "1.3 m below the top tick (1.5 m)");
        assert!(texts(&s).contains(&"1.5") && texts(&s).contains(&"frame"));
    }
}
