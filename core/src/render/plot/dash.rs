//! Dashed strokes for the pictures drawn into pixels (an SVG says
//! `stroke-dasharray` and lets the viewer dash): a polyline cut into the "on"
//! pieces of a pattern that runs on across its corners, as SVG's does.

/// The visible pieces of `points` stroked with `dash` (on, off, … in px; an
/// odd-length pattern repeats twice, as in SVG). Solid when `dash` is empty.
pub fn segments(points: &[(f64, f64)], dash: &[f64]) -> Vec<((f64, f64), (f64, f64))> {
    let whole = || points.windows(2).map(|w| (w[0], w[1])).collect();
    if dash.is_empty() || dash.iter().any(|v| !v.is_finite() || *v < 0.0) || dash.iter().sum::<f64>() <= 0.0 {
        return whole();
    }
    let pattern: Vec<f64> =
        if dash.len() % 2 == 1 { dash.iter().chain(dash).copied().collect() } else { dash.to_vec() };
    let mut out = Vec::new();
    let (mut k, mut left) = (0usize, pattern[0]);
    for w in points.windows(2) {
        let (a, b) = (w[0], w[1]);
        let len = (b.0 - a.0).hypot(b.1 - a.1);
        if !len.is_finite() {
            continue;
        }
        let at = |t: f64| (a.0 + (b.0 - a.0) * t / len, a.1 + (b.1 - a.1) * t / len);
        let mut t = 0.0;
        while t < len {
            let step = left.min(len - t);
            if k % 2 == 0 && step > 0.0 {
                out.push((at(t), at(t + step)));
            }
            t += step;
            left -= step;
            if left <= 1e-9 {
                k = (k + 1) % pattern.len();
                left = pattern[k];
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::segments;

    #[test]
    fn the_pattern_runs_on_across_corners() {
        assert_eq!(segments(&[(0.0, 0.0), (10.0, 0.0)], &[]), vec![((0.0, 0.0), (10.0, 0.0))]);
        assert_eq!(
            segments(&[(0.0, 0.0), (10.0, 0.0)], &[4.0, 2.0]),
            vec![((0.0, 0.0), (4.0, 0.0)), ((6.0, 0.0), (10.0, 0.0))]
        );
        // 3 on at the corner: 1 px before it, 2 after.
        let s = segments(&[(0.0, 0.0), (6.0, 0.0), (6.0, 5.0)], &[5.0, 2.0]);
        assert_eq!(s, vec![((0.0, 0.0), (5.0, 0.0)), ((6.0, 1.0), (6.0, 5.0))]);
        // An odd pattern doubles: 3 on, 3 off, 3 on.
        assert_eq!(segments(&[(0.0, 0.0), (9.0, 0.0)], &[3.0]).len(), 2);
        assert_eq!(segments(&[(0.0, 0.0)], &[3.0, 1.0]), vec![]);
    }
}
