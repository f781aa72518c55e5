//! `siftlab [-d DATASET] view_trajectory [-a ALGO [-t T]] [FRAME_ID] [--save-poses FILE]
//! [--save-poses-tum FILE] [--metrics FILE] [--plot FILE] [--trace FILE]`: the lab's visual
//! odometry over frames 0..=FRAME_ID of a MyKITTI folder (Lucas–Kanade, or with `-a` the
//! student's matcher: `vo::matched`), the lab's window `trajectory.png` (truth
//! green, estimate red), the final position with the trajectory error, and on
//! request the poses, the metrics as JSON, a plot with axes (PNG or SVG) and
//! the per-frame counts as JSON Lines.

use siftlab_core::dataset::Dataset;
use siftlab_core::error::{Error, Result};
use siftlab_core::matching::Strategy;
use siftlab_core::render::plot::figures::{report_figure, run_style, Run};
use siftlab_core::render::plot::{raster::rasterize, svg::to_svg};
use siftlab_core::sift::SiftParams;
use siftlab_core::vo::export::{kitti_text, tum_text};
use siftlab_core::vo::matched::MatchedOdometry;
use siftlab_core::vo::metrics::TrajectoryMetrics;
use siftlab_core::vo::odometry::{run, sift_detector};
use siftlab_core::vo::{Odometry, Record, StepResult};
use std::fmt::Write as _;
use std::io::Write as _;
use std::path::Path;

/// What `view_trajectory` runs and writes.
#[derive(Clone, Debug, Default)]
pub struct Options<'a> {
    /// Frames 0..frames (the CLI passes FRAME_ID + 1; default: every frame
    /// of the dataset with a pose).
    pub frames: Option<usize>,
    /// `None`: the lab's Lucas–Kanade tracking; else matching with this strategy.
    pub strategy: Option<Strategy>,
    /// KITTI format, one line per frame from 0: accumulated R and the drawn position.
    pub save_poses: Option<&'a Path>,
    /// TUM format (`evo`): `i/10 x y z qx qy qz qw`.
    pub save_poses_tum: Option<&'a Path>,
    /// The metrics as one JSON object.
    pub metrics: Option<&'a Path>,
    /// The trajectory and error plot, PNG or SVG by extension.
    pub plot: Option<&'a Path>,
    /// The per-frame counts as JSON Lines ([`trace_jsonl`]).
    pub trace: Option<&'a Path>,
    /// SIFT's parameters (`--opencv-lanes`); `None`: the lab's, at the
    /// width OpenCV would use on this CPU (`SiftParams::for_host`).
    pub sift: Option<SiftParams>,
}

/// The fields of [`StepResult`] a trace holds, in its order: what
/// `tests/references/vo_reference.py --trace` and `vo_matched_reference.py
/// --trace` write for OpenCV's loops, so the files compare line by line.
pub const TRACE_FIELDS: [&str; 6] =
    ["frame", "points_in", "tracked", "essential_inliers", "pose_inliers", "redetected"];

/// One JSON object per frame (JSON Lines), keys [`TRACE_FIELDS`], spaced as
/// Python's `json.dumps`: `{"frame": 1, "points_in": 1500, ...}`.
pub fn trace_jsonl(steps: &[StepResult]) -> String {
    let mut out = String::new();
    for s in steps {
        let _ = writeln!(
            out,
            "{{\"frame\": {}, \"points_in\": {}, \"tracked\": {}, \"essential_inliers\": {}, \
             \"pose_inliers\": {}, \"redetected\": {}}}",
            s.frame, s.points_in, s.tracked, s.essential_inliers, s.pose_inliers, s.redetected
        );
    }
    out
}

fn write(path: &Path, bytes: &[u8], what: &str) -> Result<()> {
    std::fs::write(path, bytes).map_err(|e| Error::Dataset(format!("cannot write {what} to {}: {e}", path.display())))
}

/// Checks the plot's file name before the run, so a typo does not cost the run.
fn plot_format(path: &Path) -> Result<bool> {
    match path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).as_deref() {
        Some("png") => Ok(false),
        Some("svg") => Ok(true),
        _ => Err(Error::InvalidArgument(format!(
            "--plot {}: the file name must end in .png or .svg (the format is taken from it)",
            path.display()
        ))),
    }
}

/// Opens the trace file before the run, so a path that cannot be written
/// fails at once rather than after every frame.
fn open_trace(path: &Path) -> Result<std::fs::File> {
    std::fs::File::create(path)
        .map_err(|e| Error::Dataset(format!("cannot write the trace to {}: {e}", path.display())))
}

/// Runs the VO on the first frames, writes `out_png` (the lab's window) and
/// whatever `opts` asks for. Returns the text to print (on stderr) and the metrics.
pub fn view_trajectory(
    ds: &Dataset,
    opts: &Options,
    out_png: &Path,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<(String, TrajectoryMetrics)> {
    let svg = opts.plot.map(plot_format).transpose()?;
    ds.require_poses("view_trajectory")?;
    let n = opts.frames.unwrap_or(ds.frame_count().min(ds.poses().len()));
    if n == 0 {
        return Err(Error::InvalidArgument("the trajectory needs at least one frame (frame 0)".into()));
    }
    ds.check_frames(n)?;
    let mut trace = opts.trace.map(open_trace).transpose()?;
    let params = opts.sift.clone().unwrap_or_else(SiftParams::for_host);
    let steps: Vec<StepResult> = match &opts.strategy {
        None => {
            let mut odo = Odometry::with_detector(*ds.camera(), sift_detector(params))?;
            run(&mut odo, n, ds.poses(), |i| ds.load_frame(i), progress)?
        }
        Some(s) => {
            let mut odo = MatchedOdometry::new(*ds.camera(), *s)?;
            siftlab_core::vo::run_matched(&mut odo, n, ds.poses(), |i| ds.load_frame(i), &params, progress)?
        }
    };

    let mut record = Record::default();
    steps.iter().for_each(|s| record.push(s));
    let end = record.finish(ds.poses())?;
    let (est, gt) = (record.positions(), &end.truth);

    if let Some(path) = opts.save_poses {
        write(path, kitti_text(record.poses()).as_bytes(), "the poses")?;
    }
    if let Some(path) = opts.save_poses_tum {
        write(path, tum_text(record.poses()).as_bytes(), "the TUM poses")?;
    }
    if let Some(path) = opts.metrics {
        write(path, (end.metrics.to_json_with_segments(end.segments.len()) + "\n").as_bytes(), "the metrics")?;
    }
    if let (Some(file), Some(path)) = (&mut trace, opts.trace) {
        file.write_all(trace_jsonl(&steps).as_bytes())
            .map_err(|e| Error::Dataset(format!("cannot write the trace to {}: {e}", path.display())))?;
    }
    if let (Some(path), Some(svg)) = (opts.plot, svg) {
        let (name, style) = run_style(opts.strategy.as_ref());
        let scene = report_figure(gt, &[Run { name, style, positions: est.clone() }], 720);
        let bytes =
            if svg { to_svg(&scene, None).into_bytes() } else { siftlab_core::render::encode_png(&rasterize(&scene))? };
        write(path, &bytes, "the plot")?;
    }

    write_png(out_png, &est, gt)?;

    let p = est[n - 1];
    let g = gt[n - 1];
    let mut out = String::new();
    let _ = writeln!(
        out,
        "final position: x={:.4} y={:.4} z={:.4} (ground truth {:.4} {:.4} {:.4})",
        p[0], p[1], p[2], g[0], g[1], g[2]
    );
    let _ = writeln!(out, "trajectory error (ATE RMSE, {n} frames): {:.4} m", end.ate);
    // The summary is the app's line too (`TrajectoryMetrics::summary`); the
    // segments the KITTI figures rest on follow on a line of their own.
    let _ = writeln!(out, "{} ({n} frames): {}", run_style(opts.strategy.as_ref()).0, end.metrics.summary());
    out.push_str(&end.kitti_line());
    Ok((out, end.metrics))
}

/// The lab's window after the last frame (truth green, estimate red, the
/// current coordinates as text), as `trajectory.png`.
fn write_png(out: &Path, est: &[[f64; 3]], gt: &[[f64; 3]]) -> Result<()> {
    let img = siftlab_core::render::trajectory::draw(gt, est, &siftlab_core::render::trajectory::Style::default());
    let png = siftlab_core::render::encode_png(&img)?;
    std::fs::write(out, png).map_err(|e| Error::Dataset(format!("cannot write {}: {e}", out.display())))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    /// The bundled real KITTI frames.
    fn fixture() -> Dataset {
        Dataset::open(&Path::new(env!("CARGO_MANIFEST_DIR")).join("../../www/demo/MyKITTI")).unwrap()
    }

    fn tmp(name: &str) -> PathBuf {
        std::env::temp_dir().join(format!("siftlab-traj-{}-{name}", std::process::id()))
    }

    #[test]
    fn runs_the_lab_loop_and_writes_poses_and_png() {
        let (poses, png) = (tmp("poses.txt"), tmp("trajectory.png"));
        let mut calls = Vec::new();
        let opts = Options { frames: Some(3), save_poses: Some(&poses), ..Options::default() };
        let (text, m) = view_trajectory(&fixture(), &opts, &png, &mut |d, t| calls.push((d, t))).unwrap();
        assert_eq!((m.frames, m.kitti_t_err_pct), (3, None));
        assert_eq!(calls, vec![(1, 3), (2, 3), (3, 3)]);
        // tests/references/vo_reference.py --dataset www/demo/MyKITTI --frames 3
        // (OpenCV 4.8.0.76): position after frame 2.
        let want = [-0.03253505574129042, -0.0229585009250804, 1.858783796014574];
        let lines: Vec<Vec<f64>> = std::fs::read_to_string(&poses)
            .unwrap()
            .lines()
            .map(|l| l.split(' ').map(|v| v.parse().unwrap()).collect())
            .collect();
        assert_eq!(lines.len(), 3);
        assert!(lines.iter().all(|l| l.len() == 12));
        assert_eq!([lines[0][3], lines[0][7], lines[0][11]], [0.0; 3]);
        assert_eq!([lines[1][3], lines[1][7], lines[1][11]], [0.0; 3]);
        let got = [lines[2][3], lines[2][7], lines[2][11]];
        for k in 0..3 {
            assert!((got[k] - want[k]).abs() < 1e-6, "frame 2 position {got:?} vs OpenCV {want:?}");
        }
        assert!(
            text.starts_with("final position: x=-0.0325 y=-0.0230 z=1.8588 (ground truth -0.0937 -0.0568 1.7163)"),
            "{text}"
        );
        assert!(text.contains("trajectory error (ATE RMSE, 3 frames): "), "{text}");

        let img = image::open(&png).unwrap().to_rgb8();
        assert_eq!(img.dimensions(), (600, 600));
        let count = |c: [u8; 3]| img.pixels().filter(|p| p.0 == c).count();
        assert!(count([0, 255, 0]) >= 4, "truth pixels");
        // Frames 0-2 all map to the lab window's (290, 90)/(290, 91) (positions
        // truncate to whole metres) and each frame's truth is drawn after its
        // estimate, so the radius-1 circles there are green.
        assert_eq!(img.get_pixel(290, 89).0, [0, 255, 0]);
        assert_eq!(img.get_pixel(290, 92).0, [0, 255, 0]);
        assert_eq!(img.get_pixel(290, 95).0, [0, 0, 0]);
        let _ = std::fs::remove_file(&poses);
        let _ = std::fs::remove_file(&png);
    }

    #[test]
    fn bad_arguments_and_datasets_are_explained() {
        let png = tmp("never.png");
        let mut nop = |_: usize, _: usize| {};
        let frames = |n| Options { frames: Some(n), ..Options::default() };
        let e = view_trajectory(&fixture(), &frames(0), &png, &mut nop).unwrap_err().to_string();
        assert!(e.contains("at least one frame"), "{e}");
        let e = view_trajectory(&fixture(), &frames(152), &png, &mut nop).unwrap_err().to_string();
        assert!(e.contains("frames 0 to 151 are needed but") && e.contains("has frames 0 to 150 only"), "{e}");
        let no_poses = Dataset::from_parts("picked".into(), 3, None);
        let e = view_trajectory(&no_poses, &frames(2), &png, &mut nop).unwrap_err().to_string();
        assert!(e.starts_with("view_trajectory needs the ground-truth poses poses/00.txt"), "{e}");
        let plot = Path::new("plot.jpg");
        let bad = Options { plot: Some(plot), ..Options::default() };
        let e = view_trajectory(&fixture(), &bad, &png, &mut nop).unwrap_err().to_string();
        assert!(e.contains("--plot plot.jpg: the file name must end in .png or .svg"), "{e}");
        // A trace that cannot be written fails before the run (no frame read).
        let trace = Path::new("/nonexistent/dir/trace.jsonl");
        let bad = Options { trace: Some(trace), ..Options::default() };
        let e = view_trajectory(&fixture(), &bad, &png, &mut |_, _| panic!("ran")).unwrap_err().to_string();
        assert!(e.starts_with("cannot write the trace to /nonexistent/dir/trace.jsonl: "), "{e}");
        assert!(!png.exists());
    }

    /// The trace's lines are Python's `json.dumps` of the same keys, so a
    /// line equals the OpenCV scripts' line for the same counts.
    #[test]
    fn trace_lines_read_as_python_writes_them() {
        let mut a = StepResult::start(0, None, siftlab_core::vo::IDENTITY);
        a.redetected = true;
        let mut b = StepResult::start(7, None, siftlab_core::vo::IDENTITY);
        (b.points_in, b.tracked, b.essential_inliers, b.pose_inliers) = (1502, 1467, 1423, 1022);
        assert_eq!(
            trace_jsonl(&[a, b.clone()]),
            "{\"frame\": 0, \"points_in\": 0, \"tracked\": 0, \"essential_inliers\": 0, \"pose_inliers\": 0, \
             \"redetected\": true}\n{\"frame\": 7, \"points_in\": 1502, \"tracked\": 1467, \"essential_inliers\": \
             1423, \"pose_inliers\": 1022, \"redetected\": false}\n"
        );
        let one = trace_jsonl(&[b]);
        let keys: Vec<&str> = one.split('"').skip(1).step_by(2).collect();
        assert_eq!(keys, TRACE_FIELDS);
    }
}
