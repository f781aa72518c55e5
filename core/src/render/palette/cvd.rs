//! Checks that the palette's meaningful pairs stay apart for the two common
//! colour-vision deficiencies. The rule: each pair's CIEDE2000 colour
//! difference is at least [`MIN_DE`] in normal vision, and after simulating
//! deuteranopia and protanopia at severity 1.0 (Machado, Oliveira & Fernandes,
//! "A Physiologically-based Model for Simulation of Color Vision Deficiency",
//! IEEE TVCG 2009: their 3×3 matrices applied to linear RGB, clipped to
//! [0, 1]). On top of that every pair differs in dash or marker (`mod.rs`).
//! `cargo test -p siftlab-core palette -- --nocapture` prints the table.

use super::*;

/// ΔE00 of 15 is a difference seen at a glance on a figure (2.3 is the bare
/// noticeable one); the old red/green pairs fell to 11.5 and 1.6 here.
pub const MIN_DE: f64 = 15.0;

/// Machado et al. 2009, severity 1.0, for linear RGB.
pub const PROTANOPIA: [[f64; 3]; 3] =
    [[0.152286, 1.052583, -0.204868], [0.114503, 0.786281, 0.099216], [-0.003882, -0.048116, 1.051998]];
pub const DEUTERANOPIA: [[f64; 3]; 3] =
    [[0.367322, 0.860646, -0.227968], [0.280085, 0.672501, 0.047413], [-0.011820, 0.042940, 0.968881]];

fn linear(c: u8) -> f64 {
    let c = c as f64 / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// The linear RGB a viewer with `m`'s deficiency sees for `c` (`None`: normal vision).
pub fn simulate(c: Color, m: Option<&[[f64; 3]; 3]>) -> [f64; 3] {
    let l = c.map(linear);
    match m {
        None => l,
        Some(m) => std::array::from_fn(|i| (m[i][0] * l[0] + m[i][1] * l[1] + m[i][2] * l[2]).clamp(0.0, 1.0)),
    }
}

/// CIE L*a*b* (D65) of a linear sRGB colour.
pub fn lab(l: [f64; 3]) -> [f64; 3] {
    let [r, g, b] = l;
    let x = (0.4124564 * r + 0.3575761 * g + 0.1804375 * b) / 0.95047;
    let y = 0.2126729 * r + 0.7151522 * g + 0.0721750 * b;
    let z = (0.0193339 * r + 0.1191920 * g + 0.9503041 * b) / 1.08883;
    let f =
        |t: f64| if t > (6.0f64 / 29.0).powi(3) { t.cbrt() } else { t / (3.0 * (6.0f64 / 29.0).powi(2)) + 4.0 / 29.0 };
    let (fx, fy, fz) = (f(x), f(y), f(z));
    [116.0 * fy - 16.0, 500.0 * (fx - fy), 200.0 * (fy - fz)]
}

/// CIEDE2000 (Sharma, Wu & Dalal 2005), kL = kC = kH = 1.
pub fn ciede2000(p: [f64; 3], q: [f64; 3]) -> f64 {
    let (l1, a1, b1, l2, a2, b2) = (p[0], p[1], p[2], q[0], q[1], q[2]);
    let cb = (a1.hypot(b1) + a2.hypot(b2)) / 2.0;
    let g = 0.5 * (1.0 - (cb.powi(7) / (cb.powi(7) + 25f64.powi(7))).sqrt());
    let (a1p, a2p) = ((1.0 + g) * a1, (1.0 + g) * a2);
    let (c1p, c2p) = (a1p.hypot(b1), a2p.hypot(b2));
    let hue = |b: f64, a: f64| if a == 0.0 && b == 0.0 { 0.0 } else { b.atan2(a).to_degrees().rem_euclid(360.0) };
    let (h1p, h2p) = (hue(b1, a1p), hue(b2, a2p));
    let (dlp, dcp) = (l2 - l1, c2p - c1p);
    let dhp = if c1p * c2p == 0.0 {
        0.0
    } else if (h2p - h1p).abs() <= 180.0 {
        h2p - h1p
    } else if h2p - h1p > 180.0 {
        h2p - h1p - 360.0
    } else {
        h2p - h1p + 360.0
    };
    let dhp_big = 2.0 * (c1p * c2p).sqrt() * (dhp / 2.0).to_radians().sin();
    let (lbp, cbp) = ((l1 + l2) / 2.0, (c1p + c2p) / 2.0);
    let hbp = if c1p * c2p == 0.0 {
        h1p + h2p
    } else if (h1p - h2p).abs() <= 180.0 {
        (h1p + h2p) / 2.0
    } else if h1p + h2p < 360.0 {
        (h1p + h2p + 360.0) / 2.0
    } else {
        (h1p + h2p - 360.0) / 2.0
    };
    let cos = |d: f64| d.to_radians().cos();
    let t = 1.0 - 0.17 * cos(hbp - 30.0) + 0.24 * cos(2.0 * hbp) + 0.32 * cos(3.0 * hbp + 6.0)
        - 0.20 * cos(4.0 * hbp - 63.0);
    let dtheta = 30.0 * (-((hbp - 275.0) / 25.0).powi(2)).exp();
    let rc = 2.0 * (cbp.powi(7) / (cbp.powi(7) + 25f64.powi(7))).sqrt();
    let sl = 1.0 + 0.015 * (lbp - 50.0).powi(2) / (20.0 + (lbp - 50.0).powi(2)).sqrt();
    let (sc, sh) = (1.0 + 0.045 * cbp, 1.0 + 0.015 * cbp * t);
    let rt = -(2.0 * dtheta).to_radians().sin() * rc;
    ((dlp / sl).powi(2) + (dcp / sc).powi(2) + (dhp_big / sh).powi(2) + rt * (dcp / sc) * (dhp_big / sh)).sqrt()
}

/// ΔE00 between `a` and `b` as normal vision, deuteranopia and protanopia see them.
pub fn differences(a: Color, b: Color) -> [f64; 3] {
    [None, Some(&DEUTERANOPIA), Some(&PROTANOPIA)].map(|m| ciede2000(lab(simulate(a, m)), lab(simulate(b, m))))
}

/// The pairs whose colours carry a distinction, by name.
fn meaningful_pairs() -> Vec<(String, Color, String, Color)> {
    let mut pairs = vec![
        ("correct".to_string(), CORRECT.color, "wrong".to_string(), WRONG.color),
        ("kept".into(), BLUE, "rest".into(), REST),
        ("ok text".into(), BLUE, "bad text".into(), VERMILLION_TEXT),
        ("selected".into(), SELECTED.color, "info".into(), INFO.color),
    ];
    let named = |set: &[(&str, Style)]| -> Vec<(String, Color, String, Color)> {
        let mut out = Vec::new();
        for (i, (a, sa)) in set.iter().enumerate() {
            for (b, sb) in &set[i + 1..] {
                out.push((a.to_string(), sa.color, b.to_string(), sb.color));
            }
        }
        out
    };
    let trackers =
        [("truth", TRUTH), ("LK", TRACKERS[0]), ("dt", TRACKERS[1]), ("nn", TRACKERS[2]), ("nndr", TRACKERS[3])];
    pairs.extend(named(&trackers));
    // The trade-off chart's curves: the same styles, listed for what they are.
    let strategies = [
        ("dt curve", strategy(StrategyKind::Dt)),
        ("nn curve", strategy(StrategyKind::Nn)),
        ("nndr curve", strategy(StrategyKind::Nndr)),
    ];
    pairs.extend(named(&strategies));
    let anatomy = [
        ("stage", STAGE_POINTS),
        ("no conv.", DROPS[0]),
        ("border", DROPS[1]),
        ("contrast", DROPS[2]),
        ("edge", DROPS[3]),
    ];
    pairs.extend(named(&anatomy));
    // The odometry's own view: inliers, outliers and re-detections on a frame.
    pairs.extend(named(&[("inlier", INLIER), ("outlier", OUTLIER), ("re-detected", REDETECTED)]));
    // The whole-frame view's picked match and its epipolar line against the rest.
    pairs.extend(named(&[("picked", PICKED), ("correct ", CORRECT), ("wrong ", WRONG)]));
    pairs
}

#[test]
fn ciede2000_matches_sharmas_test_data() {
    // Pairs 1, 7, 17 and 25 of Sharma, Wu & Dalal's table.
    for (p, q, want) in [
        ([50.0, 2.6772, -79.7751], [50.0, 0.0, -82.7485], 2.0425),
        ([50.0, 0.0, 0.0], [50.0, -1.0, 2.0], 2.3669),
        ([50.0, 2.5, 0.0], [73.0, 25.0, -18.0], 27.1492),
        ([60.2574, -34.0099, 36.2677], [60.4626, -34.1751, 39.4387], 1.2644),
    ] {
        assert!((ciede2000(p, q) - want).abs() < 5e-5, "{p:?} {q:?}: {} vs {want}", ciede2000(p, q));
    }
    // The simulation keeps greys grey: each matrix row sums to 1.
    for m in [PROTANOPIA, DEUTERANOPIA] {
        let w = simulate([255, 255, 255], Some(&m));
        assert!(w.iter().all(|v| (v - 1.0).abs() < 1e-5), "{w:?}");
    }
}

#[test]
fn meaningful_pairs_stay_apart_for_deuteranopes_and_protanopes() {
    println!("{:>10} / {:<10} {:>7} {:>7} {:>7}", "pair", "", "normal", "deuter.", "protan.");
    let mut failed = Vec::new();
    for (a, ca, b, cb) in meaningful_pairs() {
        let d = differences(ca, cb);
        println!("{a:>10} / {b:<10} {:>7.1} {:>7.1} {:>7.1}", d[0], d[1], d[2]);
        if d.iter().any(|&v| v < MIN_DE) {
            failed.push(format!("{a}/{b} {d:.1?}"));
        }
    }
    assert!(failed.is_empty(), "closer than ΔE00 {MIN_DE}: {failed:?}");
}

/// The rule can fail: the red/green pairs the figures used before this
/// palette are exactly what a deuteranope cannot tell apart.
#[test]
fn the_old_red_green_pairs_fail_the_rule() {
    let old_correct_wrong = differences([40, 200, 60], [230, 40, 40]);
    let old_truth_lk = differences([0, 150, 0], [215, 25, 28]);
    assert!(old_correct_wrong[0] > 70.0, "apart in normal vision: {old_correct_wrong:?}");
    assert!(old_correct_wrong[1] < MIN_DE, "{old_correct_wrong:?}");
    assert!(old_truth_lk[1] < 3.0, "{old_truth_lk:?}");
}
