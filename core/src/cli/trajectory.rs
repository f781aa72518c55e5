//! `siftlab [-d DATASET] view_trajectory [FRAME_ID] [--save-poses FILE]`: the
//! lab's visual odometry over frames 0..=FRAME_ID of a MyKITTI folder, the plot
//! `trajectory.png` (truth green, estimate red) and the final position with
//! the trajectory error.

use crate::dataset::Dataset;
use crate::error::{Error, Result};
use crate::vo::metrics::ate_rmse;
use crate::vo::odometry::{pose_row, run};
use crate::vo::{Camera, Odometry};
use std::fmt::Write as _;
use std::path::Path;

/// Runs the VO on the first `frames` frames, 0..frames (the CLI passes
/// FRAME_ID + 1; default: every frame of the dataset), writes `out_png` and, if asked, the estimated poses (KITTI
/// format, one line per frame from 0: accumulated R and the drawn position).
/// Returns the text to print.
pub fn view_trajectory(
    dataset: &Path,
    frames: Option<usize>,
    save_poses: Option<&Path>,
    out_png: &Path,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<String> {
    let ds = Dataset::open(dataset)?;
    let n = frames.unwrap_or(ds.frame_count().min(ds.poses().len()));
    if n == 0 {
        return Err(Error::InvalidArgument("the trajectory needs at least one frame (frame 0)".into()));
    }
    ds.check_frames(n)?;
    let mut odo = Odometry::new(Camera::default())?;
    let steps = run(&mut odo, n, ds.poses(), |i| ds.load_frame(i), progress)?;

    let est: Vec<[f64; 3]> = steps.iter().map(|s| s.position).collect();
    let gt: Vec<[f64; 3]> = ds.poses()[..n].iter().map(crate::dataset::position).collect();
    let ate = ate_rmse(&est, &gt)?;

    if let Some(path) = save_poses {
        let mut text = String::new();
        for s in &steps {
            let row = pose_row(&s.rotation, &s.position);
            let line: Vec<String> = row.iter().map(|v| crate::pyfmt::py_float(*v)).collect();
            let _ = writeln!(text, "{}", line.join(" "));
        }
        std::fs::write(path, text)
            .map_err(|e| Error::Dataset(format!("cannot write the poses to {}: {e}", path.display())))?;
    }

    write_png(out_png, &est, &gt)?;

    let p = est[n - 1];
    let g = gt[n - 1];
    let mut out = String::new();
    let _ = writeln!(
        out,
        "final position: x={:.4} y={:.4} z={:.4} (ground truth {:.4} {:.4} {:.4})",
        p[0], p[1], p[2], g[0], g[1], g[2]
    );
    let _ = write!(out, "trajectory error (ATE RMSE, {n} frames): {ate:.4} m");
    Ok(out)
}

/// The lab's window after the last frame (truth green, estimate red, the
/// current coordinates as text), as `trajectory.png`.
fn write_png(out: &Path, est: &[[f64; 3]], gt: &[[f64; 3]]) -> Result<()> {
    let img = crate::render::trajectory::draw(gt, est, &crate::render::trajectory::Style::default());
    let png = crate::render::encode_png(&img)?;
    std::fs::write(out, png).map_err(|e| Error::Dataset(format!("cannot write {}: {e}", out.display())))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    /// The bundled real KITTI frames.
    fn fixture() -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../www/demo/MyKITTI")
    }

    fn tmp(name: &str) -> PathBuf {
        std::env::temp_dir().join(format!("siftlab-traj-{}-{name}", std::process::id()))
    }

    #[test]
    fn runs_the_lab_loop_and_writes_poses_and_png() {
        let (poses, png) = (tmp("poses.txt"), tmp("trajectory.png"));
        let mut calls = Vec::new();
        let text = view_trajectory(&fixture(), Some(3), Some(&poses), &png, &mut |d, t| calls.push((d, t))).unwrap();
        assert_eq!(calls, vec![(1, 3), (2, 3), (3, 3)]);
        // tests/scripts/vo_reference.py --dataset www/demo/MyKITTI --frames 3
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
        let e = view_trajectory(&fixture(), Some(0), None, &png, &mut nop).unwrap_err().to_string();
        assert!(e.contains("at least one frame"), "{e}");
        let e = view_trajectory(&fixture(), Some(101), None, &png, &mut nop).unwrap_err().to_string();
        assert!(e.contains("frames 0 to 100 are needed but") && e.contains("has frames 0 to 99 only"), "{e}");
        let e = view_trajectory(Path::new("/nonexistent/MyKITTI"), None, None, &png, &mut nop).unwrap_err().to_string();
        assert!(e.contains("dataset folder /nonexistent/MyKITTI does not exist"), "{e}");
        assert!(!png.exists());
    }
}
