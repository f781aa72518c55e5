//! The whole-frame view's plain logic: the Sampson threshold and the rule it
//! states, the current strategy's matches and counts from the sweep, its two
//! layouts, the correct / wrong filter, which match a click picks, stepping
//! through matches with keys, the picked match (its descriptor distance, its Sampson distance to the
//! true geometry and its epipolar line) and that line clipped to the frame.

use nalgebra::Matrix3;
use siftlab_core::dataset::PoseRow;
use siftlab_core::matching::epipolar::{epipolar_line, fundamental, sampson, Verdicts};
use siftlab_core::matching::sweep::{range, Selected, Sweep};
use siftlab_core::matching::{explain, Strategy};
use siftlab_core::sift::{Features, KeyPoint};
use siftlab_core::vo::Camera;

/// The pair's true fundamental matrix from its ground-truth poses (none
/// without poses, or for poses that give no geometry).
pub fn true_fundamental(poses: Option<&[PoseRow; 2]>, camera: &Camera) -> Option<Matrix3<f64>> {
    poses.and_then(|ab| fundamental(&ab[0], &ab[1], camera).ok())
}

/// Everything the picked match's panel says.
#[derive(Clone, Debug, PartialEq)]
pub struct Pick {
    /// Its place among the matches shown, and how many are shown.
    pub index: usize,
    pub of: usize,
    pub query: u32,
    pub train: u32,
    /// The descriptor distance (the brute-force matcher's, as OpenCV gives it).
    pub distance: Option<f32>,
    /// Against the true geometry `F`, when the pair has poses.
    pub sampson: Option<f64>,
    pub line: Option<[f64; 3]>,
}

/// The match (query, train) among the `shown` pairs, with its distance and,
/// given `F`, its Sampson distance and epipolar line in the current frame.
pub fn pick_of(
    shown: &[[u32; 2]],
    picked: [u32; 2],
    prev: &Features,
    cur: &Features,
    f: Option<&Matrix3<f64>>,
) -> Option<Pick> {
    let [q, t] = picked;
    let index = shown.iter().position(|&p| p == picked)?;
    let (a, b) = (prev.keypoints.get(q as usize)?, cur.keypoints.get(t as usize)?);
    // Every train descriptor ranked by distance: the nn row has them all.
    let row = explain(&Strategy::Nn(None), prev, cur, q as usize).ok();
    let distance = row.and_then(|e| e.ranked.iter().find(|r| r.train_idx == t as usize).map(|r| r.distance));
    Some(Pick {
        index,
        of: shown.len(),
        query: q,
        train: t,
        distance,
        sampson: f.map(|f| sampson(f, [a.x, a.y], [b.x, b.y])),
        line: f.map(|f| epipolar_line(f, [a.x, a.y])),
    })
}

/// The picked match's verdict: its Sampson distance against the threshold.
pub fn verdict_text(sampson: Option<f64>, px: f64) -> String {
    match sampson {
        Some(d) => {
            let ok = d <= px;
            format!(
                "Sampson distance to the true epipolar geometry {d:.3} px {} {px} px: {}",
                if ok { "≤" } else { ">" },
                if ok { "correct" } else { "wrong" }
            )
        }
        None => "no ground-truth poses: not judged".into(),
    }
}

/// How the matches are drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Layout {
    /// On the current frame, each match a segment from where its point was
    /// in the previous frame to where it is now (`match_all --layout flow`).
    Flow,
    /// The two frames side by side, previous left (`--layout side`).
    Side,
}

impl Layout {
    pub fn name(self) -> &'static str {
        match self {
            Layout::Flow => "flow",
            Layout::Side => "side",
        }
    }
}

/// Which matches are shown.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Filter {
    All,
    Correct,
    Wrong,
}

impl Filter {
    pub const ALL: [Filter; 3] = [Filter::All, Filter::Correct, Filter::Wrong];

    pub fn name(self) -> &'static str {
        match self {
            Filter::All => "all",
            Filter::Correct => "correct",
            Filter::Wrong => "wrong",
        }
    }

    fn keeps(self, ok: Option<bool>) -> bool {
        match (self, ok) {
            (Filter::All, _) | (_, None) => true,
            (Filter::Correct, Some(ok)) => ok,
            (Filter::Wrong, Some(ok)) => !ok,
        }
    }
}

/// The matches the filter keeps, with their verdicts (without verdicts, all).
pub fn filter_pairs(pairs: &[[u32; 2]], ok: Option<&[bool]>, f: Filter) -> (Vec<[u32; 2]>, Option<Vec<bool>>) {
    let keep: Vec<usize> = (0..pairs.len()).filter(|&i| f.keeps(ok.map(|o| o[i]))).collect();
    (keep.iter().map(|&i| pairs[i]).collect(), ok.map(|o| keep.iter().map(|&i| o[i]).collect()))
}

/// A match's two ends in picture pixels: (previous frame's point, current
/// frame's point), the current frame offset by `prev_width` side by side.
pub fn ends(layout: Layout, prev: &KeyPoint, cur: &KeyPoint, prev_width: f64) -> ((f64, f64), (f64, f64)) {
    let dx = if layout == Layout::Side { prev_width } else { 0.0 };
    ((prev.x as f64, prev.y as f64), (cur.x as f64 + dx, cur.y as f64))
}

/// Distance from p to the segment a–b.
pub fn segment_distance(p: (f64, f64), a: (f64, f64), b: (f64, f64)) -> f64 {
    let (vx, vy) = (b.0 - a.0, b.1 - a.1);
    let len2 = vx * vx + vy * vy;
    let t = if len2 == 0.0 { 0.0 } else { (((p.0 - a.0) * vx + (p.1 - a.1) * vy) / len2).clamp(0.0, 1.0) };
    let (x, y) = (a.0 + t * vx, a.1 + t * vy);
    ((p.0 - x).powi(2) + (p.1 - y).powi(2)).sqrt()
}

/// The index of the match nearest to a click at `p` (picture pixels), if one
/// lies within `reach` pixels. In the flow layout the current end counts
/// double, so a click on a point picks the match that ends there.
pub fn nearest_match(
    pairs: &[[u32; 2]],
    prev: &[KeyPoint],
    cur: &[KeyPoint],
    layout: Layout,
    prev_width: f64,
    p: (f64, f64),
    reach: f64,
) -> Option<usize> {
    let mut best: Option<(f64, usize)> = None;
    for (i, &[q, t]) in pairs.iter().enumerate() {
        let (Some(a), Some(b)) = (prev.get(q as usize), cur.get(t as usize)) else { continue };
        let (pa, pb) = ends(layout, a, b, prev_width);
        let end = ((p.0 - pb.0).powi(2) + (p.1 - pb.1).powi(2)).sqrt() / 2.0;
        let d = segment_distance(p, pa, pb).min(end);
        if d <= reach && best.is_none_or(|(bd, _)| d < bd) {
            best = Some((d, i));
        }
    }
    best.map(|(_, i)| i)
}

/// The next index when stepping by `delta` through `n` matches from `cur`
/// (none picked: the first or the last), wrapping around.
pub fn step_pick(cur: Option<usize>, delta: i64, n: usize) -> Option<usize> {
    if n == 0 {
        return None;
    }
    let n = n as i64;
    Some(match cur {
        None if delta >= 0 => 0,
        None => (n - 1) as usize,
        Some(c) => (c as i64 + delta).rem_euclid(n) as usize,
    })
}

/// The line a·x + b·y + c = 0 clipped to the frame [0, w] × [0, h]: its two
/// ends, or `None` if it misses the frame.
pub fn clip_line(l: [f64; 3], w: f64, h: f64) -> Option<((f64, f64), (f64, f64))> {
    let [a, b, c] = l;
    let mut pts: Vec<(f64, f64)> = Vec::new();
    let mut push = |x: f64, y: f64| {
        if (-1e-9..=w + 1e-9).contains(&x)
            && (-1e-9..=h + 1e-9).contains(&y)
            && !pts.iter().any(|q| (q.0 - x).abs() + (q.1 - y).abs() < 1e-9)
        {
            pts.push((x, y));
        }
    };
    if b != 0.0 {
        push(0.0, -c / b);
        push(w, -(a * w + c) / b);
    }
    if a != 0.0 {
        push(-c / a, 0.0);
        push(-(b * h + c) / a, h);
    }
    (pts.len() >= 2).then(|| (pts[0], pts[1]))
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn px_parses() {
        assert_eq!(parse_px(" 2.5 "), Ok(2.5));
        assert!(parse_px("-1").is_err() && parse_px("x").is_err() && parse_px("inf").is_err());
    }

    #[test]
    fn counts_read_like_the_cli() {
        let v = Verdicts { matches: 700, correct: Some(672) };
        assert_eq!(counts_text(&v), "700 matches, 672 correct, 28 wrong, precision 0.9600");
        assert_eq!(counts_text(&Verdicts { matches: 0, correct: Some(0) }), "no matches");
        assert!(counts_text(&Verdicts { matches: 5, correct: None }).starts_with("5 matches (no ground truth"));
        assert!(rule_text(2.0).contains("at most 2 px"));
    }

    fn kp(x: f32, y: f32) -> KeyPoint {
        KeyPoint { x, y, size: 2.0, angle: 0.0, response: 0.0, octave: 0 }
    }

    #[test]
    fn the_verdict_says_which_side_of_the_threshold() {
        assert_eq!(
            verdict_text(Some(1.25), 2.0),
            "Sampson distance to the true epipolar geometry 1.250 px ≤ 2 px: correct"
        );
        assert_eq!(
            verdict_text(Some(2.5), 2.0),
            "Sampson distance to the true epipolar geometry 2.500 px > 2 px: wrong"
        );
        assert_eq!(verdict_text(None, 2.0), "no ground-truth poses: not judged");
    }

    #[test]
    fn the_filter_keeps_by_verdict() {
        let pairs = [[0, 1], [1, 2], [2, 3]];
        let ok = [true, false, true];
        assert_eq!(filter_pairs(&pairs, Some(&ok), Filter::Correct), (vec![[0, 1], [2, 3]], Some(vec![true, true])));
        assert_eq!(filter_pairs(&pairs, Some(&ok), Filter::Wrong), (vec![[1, 2]], Some(vec![false])));
        assert_eq!(filter_pairs(&pairs, Some(&ok), Filter::All).0.len(), 3);
        assert_eq!(
            filter_pairs(&pairs, None, Filter::Wrong),
            (pairs.to_vec(), None),
            "no verdicts: nothing to filter by"
        );
    }

    #[test]
    fn a_click_picks_the_nearest_match_within_reach() {
        let prev = [kp(10.0, 10.0), kp(100.0, 50.0)];
        let cur = [kp(20.0, 10.0), kp(104.0, 52.0)];
        let pairs = [[0, 0], [1, 1]];
        // Flow: on the first segment, near the second's current end.
        assert_eq!(nearest_match(&pairs, &prev, &cur, Layout::Flow, 200.0, (15.0, 11.0), 5.0), Some(0));
        assert_eq!(nearest_match(&pairs, &prev, &cur, Layout::Flow, 200.0, (105.0, 53.0), 5.0), Some(1));
        assert_eq!(nearest_match(&pairs, &prev, &cur, Layout::Flow, 200.0, (60.0, 200.0), 5.0), None);
        // Side by side: the current end is 200 px to the right.
        assert_eq!(nearest_match(&pairs, &prev, &cur, Layout::Side, 200.0, (220.0, 10.0), 5.0), Some(0));
        assert_eq!(segment_distance((5.0, 3.0), (0.0, 0.0), (10.0, 0.0)), 3.0);
        assert_eq!(segment_distance((-4.0, 3.0), (0.0, 0.0), (10.0, 0.0)), 5.0);
    }

    #[test]
    fn keys_step_and_wrap() {
        assert_eq!(step_pick(None, 1, 3), Some(0));
        assert_eq!(step_pick(None, -1, 3), Some(2));
        assert_eq!(step_pick(Some(2), 1, 3), Some(0));
        assert_eq!(step_pick(Some(0), -1, 3), Some(2));
        assert_eq!(step_pick(Some(0), 1, 0), None);
    }

    #[test]
    fn lines_are_clipped_to_the_frame() {
        // y = 5 across a 100 × 50 frame.
        assert_eq!(clip_line([0.0, 1.0, -5.0], 100.0, 50.0), Some(((0.0, 5.0), (100.0, 5.0))));
        // x = 30.
        assert_eq!(clip_line([1.0, 0.0, -30.0], 100.0, 50.0), Some(((30.0, 0.0), (30.0, 50.0))));
        // The diagonal through two corners is found once per corner.
        assert_eq!(clip_line([1.0, -2.0, 0.0], 100.0, 50.0), Some(((0.0, 0.0), (100.0, 50.0))));
        assert_eq!(clip_line([0.0, 1.0, 10.0], 100.0, 50.0), None, "y = -10 misses the frame");
    }
}
