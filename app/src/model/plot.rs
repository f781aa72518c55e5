//! The drawing arithmetic of the components, as plain functions: scales,
//! coordinates, SVG path text and the figures' captions. The components only
//! lay these out; everything here is tested natively.

use siftlab_core::matching::Verdict;
use siftlab_core::pyfmt::py_float;
use siftlab_core::render::palette::{hex, Marker, Style};
use siftlab_core::sift::KeyPoint;

/// How the app paints a style's marker path: (fill, stroke, stroke width).
/// Over photographs markers are outlines in the colour (a fill would hide the
/// point); on white they are filled and ringed in black as the core's figures
/// draw them. A cross is always strokes of its colour.
pub fn marker_paint(st: &Style, outline: bool) -> (String, String, &'static str) {
    match st.marker {
        Marker::None => ("none".into(), "none".into(), "0"),
        Marker::Cross => ("none".into(), hex(st.color), "2"),
        _ if outline => ("none".into(), hex(st.color), "1.5"),
        _ => (hex(st.color), "#000000".into(), "1"),
    }
}

/// The odometry's live progress: `frame n / total`, with the rate so far
/// while it runs (from two steps on).
pub fn vo_progress_text(n: usize, total: u32, running: bool, elapsed_ms: f64) -> String {
    let rate = if running && n >= 2 && elapsed_ms > 0.0 {
        format!(" · {:.1} frames/s", n as f64 * 1000.0 / elapsed_ms)
    } else {
        String::new()
    };
    format!("frame {n} / {total}{rate}")
}

/// The finished run's figure: ` over N frames · S s (R frames/s)`.
pub fn vo_done_text(n: usize, ms: f64) -> String {
    let fps = if ms > 0.0 { format!(" ({:.1} frames/s)", n as f64 * 1000.0 / ms) } else { String::new() };
    format!(" over {n} frames · {:.1} s{fps}", ms / 1000.0)
}

/// The progress bar's width, in percent.
pub fn percent(done: usize, total: u32) -> String {
    format!("{:.1}%", 100.0 * done as f64 / total.max(1) as f64)
}

/// One cell of the descriptor drawing (4×4 cells of 8 orientation bins).
#[derive(Clone, Debug, PartialEq)]
pub struct DescCell {
    pub row: usize,
    pub col: usize,
    /// Top-left corner.
    pub x0: f64,
    pub y0: f64,
    /// The cell's shade: its histogram's mass against the largest bin, ≤ 0.9.
    pub shade: f64,
    /// Per bin: the ray's end (from the cell's centre), bin·45° counter-clockwise.
    pub rays: [(f64, f64); 8],
}

/// The 16 cells of a descriptor drawn in cells of `cell` px; ray lengths are
/// proportional to the bin's value (the largest bin reaches the cell's edge less 3 px).
pub fn descriptor_cells(desc: &[u8; 128], cell: f64) -> Vec<DescCell> {
    let max = desc.iter().copied().max().unwrap_or(0).max(1) as f64;
    (0..16)
        .map(|c| {
            let (row, col) = (c / 4, c % 4);
            let (x0, y0) = (col as f64 * cell, row as f64 * cell);
            let (cx, cy) = (x0 + cell / 2.0, y0 + cell / 2.0);
            let sum: f64 = desc[c * 8..c * 8 + 8].iter().map(|&v| v as f64).sum();
            let shade = (sum / (max * 8.0) * 0.9).min(0.9);
            let rays = std::array::from_fn(|b| {
                let len = desc[c * 8 + b] as f64 / max * (cell / 2.0 - 3.0);
                let a = b as f64 * std::f64::consts::FRAC_PI_4;
                (cx + len * a.cos(), cy - len * a.sin())
            });
            DescCell { row, col, x0, y0, shade, rays }
        })
        .collect()
}

/// The 128 numbers, one line per cell: `cell (r, c):   v   v …`.
pub fn descriptor_rows(desc: &[u8; 128]) -> String {
    (0..16)
        .map(|r| {
            let vals: Vec<String> = desc[r * 8..r * 8 + 8].iter().map(|v| format!("{v:>3}")).collect();
            format!("cell ({}, {}): {}", r / 4, r % 4, vals.join(" "))
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// What the rule compares a distance against (as a distance), and its label;
/// `None` for nn without a threshold.
pub fn threshold_line(v: &Verdict) -> (Option<f64>, String) {
    match *v {
        Verdict::Dt { t, .. } | Verdict::Nn { t: Some(t), .. } => (Some(t), format!("t = {}", py_float(t))),
        Verdict::Nn { t: None, .. } => (None, String::new()),
        Verdict::Nndr { t, d2, .. } => (Some(t * d2 as f64), format!("t·d2 = {}", py_float(t * d2 as f64))),
    }
}

/// The bar chart's vertical scale: the nearest `shown` distances (ending at
/// `top`) and the threshold line if it is not far above them, 8 % headroom.
pub fn chart_ymax(top: f64, line: Option<f64>) -> f64 {
    (top.max(line.unwrap_or(0.0).min(top * 1.6)) * 1.08).max(1.0)
}

/// A bar chart of height `h` scaled to `ymax`: the y of distance `d` (clipped at the top).
pub fn bar_y(d: f64, ymax: f64, h: f64) -> f64 {
    h - (d / ymax).min(1.0) * h
}

/// The small chart of all sorted distances: `x,y ` points over `w`×52 px,
/// about 400 of them at most.
pub fn curve_points(distances: &[f32], w: f64) -> String {
    let n = distances.len();
    let Some(&last) = distances.last() else { return String::new() };
    let dmax = last.max(1.0) as f64;
    distances
        .iter()
        .enumerate()
        .step_by((n / 400).max(1))
        .map(|(i, &d)| format!("{:.1},{:.1} ", i as f64 / (n.max(2) - 1) as f64 * w, curve_y(d as f64, dmax)))
        .collect()
}

/// The small chart's y for distance `d` when the largest is `dmax`.
pub fn curve_y(d: f64, dmax: f64) -> f64 {
    50.0 - d / dmax * 46.0
}

/// One SVG path drawing every keypoint as a circle of radius size/2 (at least
/// 1), shifted by (dx, dy): one element instead of thousands keeps the toggle instant.
pub fn keypoint_path(kps: &[KeyPoint], dx: f64, dy: f64) -> String {
    let mut d = String::with_capacity(kps.len() * 40);
    for k in kps {
        let r = (k.size as f64 / 2.0).max(1.0);
        let (x, y) = (k.x as f64 + dx, k.y as f64 + dy);
        d.push_str(&format!(
            "M{:.1} {:.1}a{r:.1} {r:.1} 0 1 0 {:.1} 0a{r:.1} {r:.1} 0 1 0 {:.1} 0",
            x - r,
            y,
            2.0 * r,
            -2.0 * r
        ));
    }
    d
}

/// The selected keypoint as drawKeypoints' rich flag draws it: the circle's
/// radius (size/2, at least 2) and the end of the orientation line from the
/// centre at `angle` degrees (image y points down).
pub fn orientation(k: &KeyPoint) -> (f64, (f64, f64)) {
    let r = (k.size as f64 / 2.0).max(2.0);
    let a = (k.angle as f64).to_radians();
    (r, (k.x as f64 + r * a.cos(), k.y as f64 + r * a.sin()))
}

/// A click at (`x`, `y`) px from the top-left of an element `rect_w`×`rect_h`
/// px showing a `w`×`h` composite: the composite's coordinates, if the element
/// has a size.
pub fn to_composite(x: f64, y: f64, rect_w: f64, rect_h: f64, w: usize, h: usize) -> Option<(f64, f64)> {
    (rect_w > 0.0 && rect_h > 0.0).then(|| (x * w as f64 / rect_w, y * h as f64 / rect_h))
}

/// The feature id after a step of `delta` from `current`, kept in 0 … n−1
/// (`None` when there are no keypoints).
pub fn step_feature(current: usize, delta: i64, n: usize) -> Option<usize> {
    (n > 0).then(|| (current as i64 + delta).clamp(0, n as i64 - 1) as usize)
}

/// The feature-stepping keys of the frames view: the step they take
/// (Home/End go to the first/last feature of `n`).
pub fn key_step(key: &str, current: usize, n: usize) -> Option<i64> {
    let f = current as i64;
    Some(match key {
        "ArrowRight" | "ArrowDown" => 1,
        "ArrowLeft" | "ArrowUp" => -1,
        "PageDown" => 10,
        "PageUp" => -10,
        "Home" => -f,
        "End" => n as i64 - 1 - f,
        _ => return None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn kp(x: f32, y: f32, size: f32, angle: f32) -> KeyPoint {
        KeyPoint { x, y, size, angle, response: 0.0, octave: 0 }
    }

    #[test]
    fn markers_are_outlined_over_photographs() {
        use siftlab_core::render::palette::{CORRECT, TRACKERS, WRONG};
        assert_eq!(marker_paint(&CORRECT, true), ("none".into(), "#56b4e9".into(), "1.5"));
        assert_eq!(marker_paint(&TRACKERS[1], false), ("#0072b2".into(), "#000000".into(), "1"));
        assert_eq!(marker_paint(&WRONG, false).0, "none");
    }

    #[test]
    fn odometry_figures() {
        assert_eq!(vo_progress_text(0, 100, true, 0.0), "frame 0 / 100");
        assert_eq!(vo_progress_text(10, 100, true, 4000.0), "frame 10 / 100 · 2.5 frames/s");
        assert_eq!(vo_progress_text(10, 100, false, 4000.0), "frame 10 / 100");
        assert_eq!(vo_done_text(100, 25_000.0), " over 100 frames · 25.0 s (4.0 frames/s)");
        assert_eq!(vo_done_text(3, 0.0), " over 3 frames · 0.0 s");
        assert_eq!(percent(1, 3), "33.3%");
        assert_eq!(percent(0, 0), "0.0%");
    }

    #[test]
    fn descriptor_cells_and_rows() {
        let mut d = [0u8; 128];
        d[0] = 200; // cell (0, 0), bin 0: the largest, a ray to the right
        d[8 * 5 + 2] = 100; // cell (1, 1), bin 2 (90°): half as long, upwards
        let cells = descriptor_cells(&d, 44.0);
        assert_eq!(cells.len(), 16);
        assert_eq!(cells[0].rays[0], (22.0 + 19.0, 22.0));
        assert_eq!(cells[0].rays[1], (22.0, 22.0));
        let c = &cells[5];
        assert_eq!((c.row, c.col, c.x0, c.y0), (1, 1, 44.0, 44.0));
        assert!((c.rays[2].0 - 66.0).abs() < 1e-9 && (c.rays[2].1 - (66.0 - 9.5)).abs() < 1e-9, "{:?}", c.rays[2]);
        assert!((cells[0].shade - 200.0 / 1600.0 * 0.9).abs() < 1e-12);
        assert_eq!(cells[15].shade, 0.0);
        let rows = descriptor_rows(&d);
        assert_eq!(rows.lines().count(), 16);
        assert_eq!(rows.lines().next(), Some("cell (0, 0): 200   0   0   0   0   0   0   0"));
        assert_eq!(rows.lines().nth(5), Some("cell (1, 1):   0   0 100   0   0   0   0   0"));
    }

    #[test]
    fn chart_scales() {
        assert_eq!(threshold_line(&Verdict::Dt { t: 100.0, passed: 3 }), (Some(100.0), "t = 100.0".into()));
        assert_eq!(threshold_line(&Verdict::Nn { t: None, d1: 1.0, kept: true }).0, None);
        let (l, label) = threshold_line(&Verdict::Nndr { t: 0.5, d1: 1.0, d2: 4.0, ratio: 0.25, kept: true });
        assert_eq!((l, label.as_str()), (Some(2.0), "t·d2 = 2.0"));
        // A far threshold does not squash the bars: at most 1.6 × the top.
        assert!((chart_ymax(100.0, Some(1000.0)) - 172.8).abs() < 1e-9);
        assert!((chart_ymax(100.0, None) - 108.0).abs() < 1e-9);
        assert_eq!(chart_ymax(0.0, None), 1.0);
        assert_eq!(bar_y(0.0, 100.0, 190.0), 190.0);
        assert_eq!(bar_y(50.0, 100.0, 190.0), 95.0);
        assert_eq!(bar_y(500.0, 100.0, 190.0), 0.0);
        assert_eq!(curve_points(&[0.0, 10.0], 560.0), "0.0,50.0 560.0,4.0 ");
        assert_eq!(curve_points(&[], 560.0), "");
        assert_eq!(curve_points(&vec![1.0; 1200], 100.0).split(' ').filter(|s| !s.is_empty()).count(), 400);
    }

    #[test]
    fn keypoints_and_clicks() {
        assert_eq!(
            keypoint_path(&[kp(10.0, 20.0, 4.0, 0.0)], 0.0, 0.0),
            "M8.0 20.0a2.0 2.0 0 1 0 4.0 0a2.0 2.0 0 1 0 -4.0 0"
        );
        assert_eq!(
            keypoint_path(&[kp(0.0, 0.0, 1.0, 0.0)], 5.0, 1.0),
            "M4.0 1.0a1.0 1.0 0 1 0 2.0 0a1.0 1.0 0 1 0 -2.0 0"
        );
        let (r, (x, y)) = orientation(&kp(10.0, 10.0, 8.0, 90.0));
        assert_eq!(r, 4.0);
        assert!((x - 10.0).abs() < 1e-9 && (y - 14.0).abs() < 1e-9, "{x} {y}");
        assert_eq!(orientation(&kp(0.0, 0.0, 1.0, 0.0)), (2.0, (2.0, 0.0)));
        assert_eq!(to_composite(50.0, 25.0, 100.0, 50.0, 1241, 752), Some((620.5, 376.0)));
        assert_eq!(to_composite(1.0, 1.0, 0.0, 50.0, 1241, 752), None);
    }

    #[test]
    fn feature_steps_stay_in_range() {
        assert_eq!(step_feature(0, -1, 10), Some(0));
        assert_eq!(step_feature(5, 10, 10), Some(9));
        assert_eq!(step_feature(5, 1, 0), None);
        assert_eq!(key_step("PageDown", 3, 10), Some(10));
        assert_eq!(key_step("Home", 3, 10), Some(-3));
        assert_eq!(key_step("End", 3, 10).and_then(|d| step_feature(3, d, 10)), Some(9));
        assert_eq!(key_step("ArrowUp", 3, 10), Some(-1));
        assert_eq!(key_step("a", 3, 10), None);
    }
}
