//! Axis arithmetic: "nice" tick steps (1, 2 or 5 × 10ⁿ), tick positions and
//! labels, and the equal-scale mapping of the top-down trajectory.

/// The nice number (1, 2, 5 or 10 × 10ⁿ) closest to `x` (`round`) or the
/// smallest not below it (Heckbert, Graphics Gems 1990). `x` > 0.
pub fn nice_number(x: f64, round: bool) -> f64 {
    let exp = x.log10().floor();
    let f = x / 10f64.powf(exp);
    let nf = if round {
        match f {
            f if f < 1.5 => 1.0,
            f if f < 3.0 => 2.0,
            f if f < 7.0 => 5.0,
            _ => 10.0,
        }
    } else {
        match f {
            f if f <= 1.0 => 1.0,
            f if f <= 2.0 => 2.0,
            f if f <= 5.0 => 5.0,
            _ => 10.0,
        }
    };
    nf * 10f64.powf(exp)
}

/// A tick step for about `target` ticks over [lo, hi] (a span of 0 counts as 1).
pub fn tick_step(lo: f64, hi: f64, target: usize) -> f64 {
    let span = nice_number(if hi > lo { hi - lo } else { 1.0 }, false);
    nice_number(span / (target.max(2) - 1) as f64, true)
}

/// The multiples of `step` from the one at or below `lo` to the one at or above `hi`.
pub fn ticks(lo: f64, hi: f64, step: f64) -> Vec<f64> {
    let (a, b) = ((lo / step).floor() as i64, (hi / step).ceil() as i64);
    // Multiplying the index (not accumulating) keeps 0.1·3 = 0.30000000000000004 out of labels.
    (a..=b.max(a + 1)).map(|k| k as f64 * step).collect()
}

/// A tick label with as many decimals as the step needs ("-0" printed as "0").
pub fn tick_label(v: f64, step: f64) -> String {
    let decimals = if step >= 1.0 { 0 } else { (-step.log10().floor()) as usize };
    let s = format!("{v:.decimals$}");
    if s.trim_start_matches('-').chars().all(|c| c == '0' || c == '.') {
        s.trim_start_matches('-').to_string()
    } else {
        s
    }
}

/// A linear map from data to pixels: `px = offset + scale·v`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Map {
    pub offset: f64,
    pub scale: f64,
}

impl Map {
    pub fn px(&self, v: f64) -> f64 {
        self.offset + self.scale * v
    }
    pub fn value(&self, px: f64) -> f64 {
        (px - self.offset) / self.scale
    }
}

/// The top-down view: x to the right, z (forward) up, one scale for both
/// (metres look the same either way), ticks on both axes.
#[derive(Clone, Debug, PartialEq)]
pub struct TopDown {
    pub x: Map,
    pub z: Map,
    pub x_ticks: Vec<f64>,
    pub z_ticks: Vec<f64>,
    pub step: f64,
}

/// Fits the x/z extent of `points` (non-finite ones skipped; at least 2 m
/// across) into the box (left, top, width, height) at equal scale, centred,
/// with ticks of one nice step in metres on both axes.
pub fn top_down(points: &[[f64; 3]], bx: (f64, f64, f64, f64)) -> TopDown {
    let (mut x0, mut x1, mut z0, mut z1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for p in points.iter().filter(|p| p[0].is_finite() && p[2].is_finite()) {
        (x0, x1, z0, z1) = (x0.min(p[0]), x1.max(p[0]), z0.min(p[2]), z1.max(p[2]));
    }
    if x0 > x1 {
        (x0, x1, z0, z1) = (0.0, 0.0, 0.0, 0.0);
    }
    // At least 2 m across so a car standing still still gets a scale.
    let (cx, cz) = ((x0 + x1) / 2.0, (z0 + z1) / 2.0);
    let (hx, hz) = (((x1 - x0) / 2.0).max(1.0), ((z1 - z0) / 2.0).max(1.0));
    let (x0, x1, z0, z1) = (cx - hx, cx + hx, cz - hz, cz + hz);
    let (left, top, w, h) = bx;
    let step = tick_step(0.0, (x1 - x0).max(z1 - z0), 6);
    let (tx0, tx1) = ((x0 / step).floor() * step, (x1 / step).ceil() * step);
    let (tz0, tz1) = ((z0 / step).floor() * step, (z1 / step).ceil() * step);
    let scale = (w / (tx1 - tx0)).min(h / (tz1 - tz0));
    let (mx, mz) = ((tx0 + tx1) / 2.0, (tz0 + tz1) / 2.0);
    let x = Map { offset: left + w / 2.0 - scale * mx, scale };
    let z = Map { offset: top + h / 2.0 + scale * mz, scale: -scale };
    // Ticks over the whole box, which may be wider than the data on one axis.
    let (vx0, vx1) = (x.value(left), x.value(left + w));
    let (vz0, vz1) = (z.value(top + h), z.value(top));
    let inside = |lo: f64, hi: f64| ticks(lo, hi, step).into_iter().filter(move |v| *v >= lo - 1e-9 && *v <= hi + 1e-9);
    TopDown { x, z, x_ticks: inside(vx0, vx1).collect(), z_ticks: inside(vz0, vz1).collect(), step }
}

/// The index of the point nearest (x, z) in the top-down view, if any is finite.
pub fn nearest_xz(points: &[[f64; 3]], x: f64, z: f64) -> Option<usize> {
    points
        .iter()
        .enumerate()
        .filter(|(_, p)| p[0].is_finite() && p[2].is_finite())
        .min_by(|a, b| {
            let d = |p: &[f64; 3]| (p[0] - x).powi(2) + (p[2] - z).powi(2);
            d(a.1).total_cmp(&d(b.1))
        })
        .map(|(i, _)| i)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nice_numbers_and_ticks() {
        assert_eq!(nice_number(0.6, true), 0.5);
        assert_eq!(nice_number(0.73, true), 1.0);
        assert_eq!(nice_number(0.73, false), 1.0);
        assert_eq!(nice_number(84.0, false), 100.0);
        assert_eq!(nice_number(3.1, true), 5.0);
        assert_eq!(tick_step(0.0, 84.0, 6), 20.0);
        assert_eq!(tick_step(0.0, 0.0, 6), 0.2);
        assert_eq!(ticks(-5.3, 84.0, 20.0), vec![-20.0, 0.0, 20.0, 40.0, 60.0, 80.0, 100.0]);
        assert_eq!(ticks(0.0, 0.3, 0.1)[3], 0.30000000000000004);
        assert_eq!(tick_label(0.30000000000000004, 0.1), "0.3");
        assert_eq!(tick_label(-0.0, 0.5), "0.0");
        assert_eq!(tick_label(-1e-17, 20.0), "0");
        assert_eq!(tick_label(-40.0, 20.0), "-40");
        assert_eq!(tick_label(0.025, 0.005), "0.025");
    }

    #[test]
    fn top_down_is_equal_scale_and_covers_the_points() {
        let pts = [[0.0, 0.0, 0.0], [-5.3, 0.0, 84.0], [f64::NAN, 0.0, 1e9]];
        let t = top_down(&pts, (50.0, 10.0, 500.0, 500.0));
        assert_eq!(t.step, 20.0);
        assert_eq!(t.x.scale, -t.z.scale);
        // 0..100 m of z tick span fills the 500 px height: 5 px per metre.
        assert_eq!(t.x.scale, 5.0);
        for p in &pts[..2] {
            let (px, pz) = (t.x.px(p[0]), t.z.px(p[2]));
            assert!((50.0..=550.0).contains(&px) && (10.0..=510.0).contains(&pz), "{px} {pz}");
        }
        // z up: a larger z is higher on the page.
        assert!(t.z.px(80.0) < t.z.px(0.0));
        assert_eq!(t.z_ticks, vec![0.0, 20.0, 40.0, 60.0, 80.0, 100.0]);
        // x: 100 m of box around the data's tick range −20..0, centred on −10.
        assert_eq!(t.x_ticks, vec![-60.0, -40.0, -20.0, 0.0, 20.0, 40.0]);
        assert!((t.x.value(t.x.px(12.5)) - 12.5).abs() < 1e-12);
        // One point: 2 m across, ticks of 0.5 m.
        let one = top_down(&[[3.0, 0.0, 4.0]], (0.0, 0.0, 100.0, 100.0));
        assert_eq!(one.step, 0.5);
        assert_eq!(nearest_xz(&pts, -5.0, 80.0), Some(1));
        assert_eq!(nearest_xz(&[], 0.0, 0.0), None);
    }
}
