//! "See inside": the state of the two views that open SIFT and the matcher
//! up (SIFT's anatomy, whole-frame matching with its trade-off chart), and
//! the plain functions their components delegate to (tested natively).

use crate::protocol::inside::LevelThumb;
use leptos::prelude::*;
use siftlab_core::matching::epipolar::Verdicts;
use siftlab_core::matching::sweep::{range, Curve, Selected, Sweep};
use siftlab_core::matching::{Strategy, StrategyKind};
use siftlab_core::sift::anatomy::values_to_gray;

/// Which "see inside" view is open.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum InsideView {
    Anatomy,
    Matches,
}

impl InsideView {
    /// The URL's `see=` value.
    pub fn name(self) -> &'static str {
        match self {
            InsideView::Anatomy => "anatomy",
            InsideView::Matches => "matches",
        }
    }

    pub fn parse(s: &str) -> Option<InsideView> {
        [InsideView::Anatomy, InsideView::Matches].into_iter().find(|v| v.name() == s)
    }
}

/// The views' state (part of the URL: `see`, `px`, `kp`).
#[derive(Clone, Copy)]
pub struct Inside {
    pub view: RwSignal<Option<InsideView>>,
    /// The Sampson threshold in pixels, as typed.
    pub px: RwSignal<String>,
    /// The anatomy's selected keypoint (an index into the frame's keypoints).
    pub kp: RwSignal<Option<usize>>,
}

impl Inside {
    pub fn new() -> Self {
        Inside { view: RwSignal::new(None), px: RwSignal::new("2".into()), kp: RwSignal::new(None) }
    }
}

impl Default for Inside {
    fn default() -> Self {
        Self::new()
    }
}

/// The Sampson threshold typed by the user.
pub fn parse_px(text: &str) -> Result<f64, String> {
    match text.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v >= 0.0 => Ok(v),
        _ => Err(format!("the epipolar threshold {text:?} must be a distance in pixels >= 0 (2 is usual)")),
    }
}

/// The rule the view states, with the threshold in use.
pub fn rule_text(px: f64) -> String {
    format!(
        "A match x₁ → x₂ is correct when its Sampson distance to the true epipolar geometry, \
         |x₂ᵀFx₁| / √((Fx₁)₁² + (Fx₁)₂² + (Fᵀx₂)₁² + (Fᵀx₂)₂²), is at most {px} px, with \
         F = K⁻ᵀ[t]ₓR K⁻¹ from the ground-truth poses ([R|t] = P_cur⁻¹·P_prev, KITTI 00's camera)."
    )
}

/// The counts of the current strategy from the sweep, and its matches
/// (query, train) with their verdicts.
pub fn current<'s>(sweep: &'s Sweep, s: &Strategy) -> Result<(Verdicts, Selected<'s>), String> {
    let kind = s.kind();
    let curve = sweep.curve(kind);
    let (pairs, ok) = match s.threshold() {
        None => curve.all_matches(),
        Some(t) => curve.matches_at(t).ok_or_else(|| {
            format!("the whole-frame view covers dt thresholds up to {}: pick a lower one", range(kind).1)
        })?,
    };
    let v = Verdicts { matches: pairs.len(), correct: ok.map(|o| o.iter().filter(|&&b| b).count()) };
    Ok((v, (pairs, ok)))
}

/// "700 matches, 672 correct, precision 0.9600" (counts only without ground truth).
pub fn counts_text(v: &Verdicts) -> String {
    match (v.correct, v.precision()) {
        (Some(c), Some(p)) => format!("{} matches, {c} correct, {} wrong, precision {p:.4}", v.matches, v.matches - c),
        (Some(_), None) => "no matches".into(),
        _ => format!("{} matches (no ground truth: frames picked one by one)", v.matches),
    }
}

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

/// The value of a thumbnail under the cursor at fractions (fx, fy) of its
/// size: the octave pixel (column, row) and the level's value there.
pub fn level_value(l: &LevelThumb, fx: f64, fy: f64) -> Option<(u32, u32, f32)> {
    if !(0.0..1.0).contains(&fx) || !(0.0..1.0).contains(&fy) {
        return None;
    }
    let (c, r) = ((fx * l.width as f64) as u32, (fy * l.height as f64) as u32);
    let v = *l.values.get((r * l.width + c) as usize)?;
    Some((c * l.step, r * l.step, v))
}

/// A level as 8-bit gray for a canvas: Gaussian values as they are, DoG
/// centred on 128 and scaled by its largest |value| (as the CLI's PNGs).
pub fn level_rgba(l: &LevelThumb) -> Vec<u8> {
    values_to_gray(&l.values, l.dog).into_iter().flat_map(|g| [g, g, g, 255]).collect()
}

/// Bars of a 36-bin histogram in a `w`×`h` box scaled to `ymax`: (x, y, width, height) each.
pub fn hist_bars(bins: &[f32], w: f64, h: f64, ymax: f64) -> Vec<(f64, f64, f64, f64)> {
    let bw = w / bins.len().max(1) as f64;
    bins.iter()
        .enumerate()
        .map(|(i, &v)| {
            let bh = if ymax > 0.0 { (v as f64 / ymax).clamp(0.0, 1.0) * h } else { 0.0 };
            (i as f64 * bw, h - bh, bw, bh)
        })
        .collect()
}

/// The pyramid position of a keypoint: "octave −1 (the doubled image), layer 2, scale σ = 3.20".
pub fn keypoint_place(k: &siftlab_core::sift::KeyPoint) -> String {
    let o = k.octave_index();
    let doubled = if o == -1 { " (the doubled image)" } else { "" };
    format!(
        "octave {o}{doubled}, DoG layer {}, size {:.2} px (σ = {:.2} in image pixels), response {:.5}",
        k.layer(),
        k.size,
        k.size / 2.0,
        k.response
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn px_and_views_parse() {
        assert_eq!(parse_px(" 2.5 "), Ok(2.5));
        assert!(parse_px("-1").is_err() && parse_px("x").is_err() && parse_px("inf").is_err());
        assert_eq!(InsideView::parse("matches"), Some(InsideView::Matches));
        assert_eq!(InsideView::parse(InsideView::Anatomy.name()), Some(InsideView::Anatomy));
        assert_eq!(InsideView::parse("x"), None);
    }

    #[test]
    fn counts_read_like_the_cli() {
        let v = Verdicts { matches: 700, correct: Some(672) };
        assert_eq!(counts_text(&v), "700 matches, 672 correct, 28 wrong, precision 0.9600");
        assert_eq!(counts_text(&Verdicts { matches: 0, correct: Some(0) }), "no matches");
        assert!(counts_text(&Verdicts { matches: 5, correct: None }).starts_with("5 matches (no ground truth"));
        assert!(rule_text(2.0).contains("at most 2 px"));
    }

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

    #[test]
    fn level_values_and_bars() {
        let l = LevelThumb {
            octave: 0,
            index: 1,
            dog: true,
            step: 4,
            width: 2,
            height: 2,
            values: vec![-2.0, 0.0, 1.0, 2.0],
        };
        assert_eq!(level_value(&l, 0.6, 0.1), Some((4, 0, 0.0)));
        assert_eq!(level_value(&l, 0.0, 0.9), Some((0, 4, 1.0)));
        assert_eq!(level_value(&l, 1.0, 0.0), None);
        let px: Vec<u8> = level_rgba(&l).chunks(4).map(|c| c[0]).collect();
        assert_eq!(px, vec![1, 128, 192, 255]);
        let bars = hist_bars(&[0.0, 5.0, 10.0], 30.0, 100.0, 10.0);
        assert_eq!(bars[1], (10.0, 50.0, 10.0, 50.0));
        assert_eq!(bars[2].3, 100.0);
    }
}
