//! The trade-off chart under the whole-frame view: precision against the
//! number of matches as each strategy's threshold sweeps its range, on a log
//! axis, with the points where two curves cross.

use siftlab_core::matching::sweep::{range, Curve, Sweep};
use siftlab_core::matching::StrategyKind;

/// Thresholds per curve on the chart.
pub const CHART_STEPS: usize = 200;

/// The chart's x axis: matches on a log scale from 1 to `xmax`, so nn's
/// 1500 and dt's hundreds of thousands fit on one axis.
pub fn chart_x(matches: usize, xmax: usize, w: f64) -> f64 {
    let lm = (xmax.max(2) as f64).log10();
    (matches.max(1) as f64).log10() / lm * w
}

/// Precision 0..1 upwards.
pub fn chart_y(precision: f64, h: f64) -> f64 {
    (1.0 - precision) * h
}

/// The largest number of matches any curve reaches in its range.
pub fn chart_xmax(sweep: &Sweep) -> usize {
    StrategyKind::ALL
        .iter()
        .filter_map(|&k| {
            let c = sweep.curve(k);
            c.at(range(k).1).map(|v| v.matches)
        })
        .max()
        .unwrap_or(1)
        .max(2)
}

/// A curve's points in the chart (points without matches or truth are skipped).
pub fn chart_xy(curve: &Curve, xmax: usize, w: f64, h: f64) -> Vec<(f64, f64)> {
    curve
        .sample(CHART_STEPS)
        .iter()
        .filter_map(|(_, v)| Some((chart_x(v.matches, xmax, w), chart_y(v.precision()?, h))))
        .collect()
}

/// A curve's polyline "x,y x,y …".
pub fn chart_points(curve: &Curve, xmax: usize, w: f64, h: f64) -> String {
    chart_xy(curve, xmax, w, h).iter().map(|(x, y)| format!("{x:.1},{y:.1}")).collect::<Vec<_>>().join(" ")
}

/// Where a curve's markers go: `n` of its points, evenly spaced, curve `k`
/// of three shifted by k/3 of a spacing so that curves that run together do
/// not stack their markers. As x, y pairs for `Marker::svg_path`.
pub fn marker_points(xy: &[(f64, f64)], n: usize, k: usize) -> Vec<f32> {
    let step = xy.len().div_ceil(n.max(1)).max(1);
    let phase = step * k / 3;
    xy.iter().enumerate().filter(|(i, _)| i % step == phase).flat_map(|(_, p)| [p.0 as f32, p.1 as f32]).collect()
}

/// Where the curves cross (matches ≥ 20, to skip the noise of the first
/// few), as text: "nn × nndr at 612 matches (precision 0.953)".
pub fn crossings_text(sweep: &Sweep) -> Vec<String> {
    let mut out = Vec::new();
    let k = StrategyKind::ALL;
    for (i, &a) in k.iter().enumerate() {
        for &b in &k[i + 1..] {
            for (m, p) in sweep.curve(a).crossings(sweep.curve(b), 20) {
                out.push(format!("{} × {} at {m} matches (precision {p:.3})", a.name(), b.name()));
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chart_axes() {
        assert_eq!(chart_x(1, 1000, 300.0), 0.0);
        assert_eq!(chart_x(1000, 1000, 300.0), 300.0);
        assert!((chart_x(10, 1000, 300.0) - 100.0).abs() < 1e-9);
        assert_eq!(chart_y(1.0, 200.0), 0.0);
        assert_eq!(chart_y(0.25, 200.0), 150.0);
        let xy: Vec<(f64, f64)> = (0..12).map(|i| (i as f64, 0.0)).collect();
        let at = |k| marker_points(&xy, 4, k).chunks(2).map(|p| p[0]).collect::<Vec<f32>>();
        assert_eq!(at(0), [0.0, 3.0, 6.0, 9.0]);
        assert_eq!(at(2), [2.0, 5.0, 8.0, 11.0]);
    }
}
