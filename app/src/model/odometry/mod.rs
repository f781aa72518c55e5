//! The odometry views' logic as plain functions: which tracker the controls
//! ask for, the four runs of the comparison, the metrics table's cells and the
//! hover text. The figures themselves are the core's (`render::plot`), the
//! same the CLI's `--plot` writes.

pub mod frame;

use crate::model::parse::{parse_strategy, threshold_box_text};
pub use crate::protocol::odometry::Tracker;
use siftlab_core::matching::{args, Strategy, StrategyKind};
use siftlab_core::render::plot::axes::nearest_xz;
use siftlab_core::render::plot::figures::{run_style, Run};
use siftlab_core::vo::TrajectoryMetrics;

/// The tracker menu's choices: the lab's LK (`None`), or one of the strategies.
pub const TRACKERS: [Option<StrategyKind>; 4] =
    [None, Some(StrategyKind::Dt), Some(StrategyKind::Nn), Some(StrategyKind::Nndr)];

/// A menu choice's value (`lk`, `dt`, `nn`, `nndr`) and back.
pub fn tracker_value(kind: Option<StrategyKind>) -> &'static str {
    kind.map_or("lk", StrategyKind::name)
}

pub fn tracker_kind(value: &str) -> Option<StrategyKind> {
    StrategyKind::parse(value)
}

/// The menu's label of a choice.
pub fn tracker_label(kind: Option<StrategyKind>) -> String {
    kind.map_or("Lucas–Kanade (the lab's)".into(), |k| format!("SIFT matching: {}", k.name()))
}

/// The threshold a strategy starts with in the menu (the README's figures).
pub fn default_threshold(kind: StrategyKind) -> String {
    threshold_box_text(args::odometry_default(kind))
}

/// The tracker the controls describe, parsed once: LK, or the strategy with
/// the core's checks and messages (an empty threshold is no threshold).
pub fn tracker_from(kind: Option<StrategyKind>, threshold: &str) -> Result<Tracker, String> {
    match kind {
        None => Ok(Tracker::Lk),
        Some(k) => parse_strategy(k, threshold).map(Tracker::Matched),
    }
}

/// The comparison's runs, in the table's order: LK, then each strategy at
/// its odometry default (dt 200, nn, nndr 0.8).
pub fn compare_runs() -> [Tracker; 4] {
    let with = |kind: StrategyKind| {
        Strategy::parse(kind.name(), args::odometry_default(kind)).map_or(Tracker::Lk, Tracker::Matched)
    };
    [Tracker::Lk, with(StrategyKind::Dt), with(StrategyKind::Nn), with(StrategyKind::Nndr)]
}

/// A finished run as the page keeps it.
#[derive(Clone, Debug, PartialEq)]
pub struct RunResult {
    pub tracker: Tracker,
    pub positions: Vec<[f64; 3]>,
    pub metrics: Option<TrajectoryMetrics>,
    pub ms: f64,
}

impl RunResult {
    /// The run as the core's figures draw it (name and style by tracker).
    pub fn plot_run(&self) -> Run {
        let (name, style) = run_style(self.tracker.strategy());
        Run { name, style, positions: self.positions.clone() }
    }
}

/// The line the CLI prints under its metrics (`vo::kitti_line`: the
/// segments the KITTI figures rest on and the true path's length), from the
/// poses file's text, for frames 0 … n − 1.
pub fn kitti_note_text(poses: &str, n: usize) -> Option<String> {
    let rows = siftlab_core::dataset::parse_poses(poses).ok()?;
    (rows.len() >= n).then(|| siftlab_core::vo::kitti_line(&rows[..n]))
}

/// One row of the metrics table: run, ATE, aligned ATE, RPE (m, °), KITTI
/// (%, °/100 m; "n/a" under 100 m of path), frames/s.
pub fn metric_cells(name: &str, m: &TrajectoryMetrics, ms: f64) -> [String; 8] {
    let opt = |v: Option<f64>, d: usize| v.map_or("n/a".to_string(), |v| format!("{v:.d$}"));
    let fps = if ms > 0.0 { format!("{:.1}", m.frames as f64 * 1000.0 / ms) } else { "–".into() };
    [
        name.to_string(),
        format!("{:.4}", m.ate_rmse),
        format!("{:.4}", m.ate_rmse_aligned),
        format!("{:.4}", m.rpe_trans_rmse),
        format!("{:.4}", m.rpe_rot_rmse_deg),
        opt(m.kitti_t_err_pct, 2),
        opt(m.kitti_r_err_deg_per_100m, 3),
        fps,
    ]
}

/// What the pointer is over in the top view (world x, z): the nearest
/// frame of the estimate, its position and its error against the truth.
pub fn hover_text(est: &[[f64; 3]], truth: &[[f64; 3]], x: f64, z: f64) -> Option<String> {
    let i = nearest_xz(est, x, z)?;
    let p = est[i];
    let err = truth.get(i).map(|g| ((p[0] - g[0]).powi(2) + (p[1] - g[1]).powi(2) + (p[2] - g[2]).powi(2)).sqrt());
    let err = err.map_or(String::new(), |e| format!(" · error {e:.3} m"));
    Some(format!("frame {i} · x={:.3} y={:.3} z={:.3} m{err}", p[0], p[1], p[2]))
}

/// The error plot's hover: frame `i` of each run, `name error` pairs.
pub fn error_hover_text(frame: f64, runs: &[(String, Vec<f64>)]) -> Option<String> {
    let i = frame.round();
    if i < 0.0 {
        return None;
    }
    let i = i as usize;
    let parts: Vec<String> = runs.iter().filter_map(|(n, e)| e.get(i).map(|v| format!("{n} {v:.3} m"))).collect();
    (!parts.is_empty()).then(|| format!("frame {i} · error {}", parts.join(", ")))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A straight drive, 1 m a frame: segments of 100 m start every 10th
    /// frame while more than 100 m of path remain (the devkit ends a segment
    /// at the first frame past its length: frame 50 has exactly 100 m left).
    #[test]
    fn the_kitti_note_counts_segments_and_path() {
        let text: String = (0..200).map(|i| format!("1 0 0 0 0 1 0 0 0 0 1 {i}\n")).collect();
        assert_eq!(kitti_note_text(&text, 151).unwrap(), "KITTI metric: 5 segments of 100 m (true path 150.0 m)");
        assert_eq!(
            kitti_note_text(&text, 100).unwrap(),
            "KITTI metric: no segment of 100 m or more (true path 99.0 m)"
        );
        assert_eq!(kitti_note_text(&text, 201), None, "more frames than poses");
    }

    #[test]
    fn trackers_and_thresholds() {
        let (dt, nn, nndr) = (Some(StrategyKind::Dt), Some(StrategyKind::Nn), Some(StrategyKind::Nndr));
        assert_eq!(tracker_from(None, "junk"), Ok(Tracker::Lk));
        assert_eq!(tracker_from(dt, " 200 "), Ok(Tracker::Matched(Strategy::Dt(200.0))));
        assert_eq!(tracker_from(nn, ""), Ok(Tracker::Matched(Strategy::Nn(None))));
        assert!(tracker_from(nndr, "").unwrap_err().contains("nndr needs a threshold"));
        assert!(tracker_from(nndr, "1.5").unwrap_err().contains("outside [0, 1]"));
        assert_eq!(tracker_from(dt, "x").unwrap_err(), "threshold must be a number, got 'x'");
        assert_eq!(StrategyKind::ALL.map(default_threshold), ["200", "", "0.8"]);
        let values: Vec<&str> = TRACKERS.iter().map(|&k| tracker_value(k)).collect();
        assert_eq!(values, ["lk", "dt", "nn", "nndr"]);
        assert!(values.iter().all(|v| tracker_kind(v) == TRACKERS[values.iter().position(|x| x == v).unwrap()]));
        assert_eq!(tracker_label(None), "Lucas–Kanade (the lab's)");
        assert_eq!(tracker_label(nndr), "SIFT matching: nndr");
        let names: Vec<String> = compare_runs().iter().map(|t| run_style(t.strategy()).0).collect();
        assert_eq!(names, ["LK", "dt 200", "nn", "nndr 0.8"]);
    }

    #[test]
    fn table_cells_and_hover() {
        let m = TrajectoryMetrics {
            frames: 100,
            ate_rmse: 1.13523,
            ate_rmse_aligned: 0.14531,
            rpe_trans_rmse: 0.13966,
            rpe_rot_rmse_deg: 0.14851,
            kitti_t_err_pct: None,
            kitti_r_err_deg_per_100m: Some(1.23456),
        };
        assert_eq!(
            metric_cells("LK", &m, 4000.0),
            ["LK", "1.1352", "0.1453", "0.1397", "0.1485", "n/a", "1.235", "25.0"].map(String::from)
        );
        assert_eq!(metric_cells("LK", &m, 0.0)[7], "–");
        let est = [[0.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.5, 0.0, 2.0]];
        let truth = [[0.0, 0.0, 0.0], [0.0, 0.0, 1.2], [0.0, 0.0, 2.0]];
        assert_eq!(hover_text(&est, &truth, 0.4, 1.9).unwrap(), "frame 2 · x=0.500 y=0.000 z=2.000 m · error 0.500 m");
        assert_eq!(hover_text(&[], &truth, 0.0, 0.0), None);
        let runs = [("LK".to_string(), vec![0.0, 0.25]), ("nn".to_string(), vec![0.0])];
        assert_eq!(error_hover_text(0.6, &runs).unwrap(), "frame 1 · error LK 0.250 m");
        assert_eq!(error_hover_text(-3.0, &runs), None);
    }
}
