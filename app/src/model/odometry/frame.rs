//! The odometry's own view as plain functions: what the loop did with one
//! camera frame (each point's flow from the previous frame, RANSAC's inliers
//! and outliers, the re-detected points) as SVG path data in image pixels,
//! the frame's counts as a sentence, and the per-frame chart's lines.

use crate::protocol::odometry::StepCounts;
use siftlab_core::render::palette::{INLIER, OUTLIER, REDETECTED};
use siftlab_core::vo::StepDetail;
use std::fmt::Write;

/// A PNG's size from its IHDR chunk (the frames are PNG files).
pub fn png_size(bytes: &[u8]) -> Option<(u32, u32)> {
    if bytes.len() < 24 || &bytes[..8] != b"\x89PNG\r\n\x1a\n" || &bytes[12..16] != b"IHDR" {
        return None;
    }
    let be = |i: usize| u32::from_be_bytes([bytes[i], bytes[i + 1], bytes[i + 2], bytes[i + 3]]);
    Some((be(16), be(20)))
}

/// One frame's drawing: segments (previous → current position) and end
/// markers per class, and the re-detected points' markers.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FlowPaths {
    pub inlier_lines: String,
    pub inlier_ends: String,
    pub outlier_lines: String,
    pub outlier_ends: String,
    pub detected: String,
}

/// Marker radius in image pixels (KITTI frames are 1241 px wide, shown at
/// about half that).
const R: f64 = 3.0;

/// The frame's points as paths: a segment per point from where it was in
/// the previous frame to where it is now, in the inlier or outlier style by
/// findEssentialMat's mask, and a diamond at each re-detected point.
pub fn flow_paths(d: &StepDetail) -> FlowPaths {
    let mut out = FlowPaths::default();
    let (mut inl, mut outl) = (Vec::new(), Vec::new());
    for ((p, c), &ok) in d.prev.iter().zip(&d.cur).zip(&d.essential_mask) {
        let (lines, ends) = if ok { (&mut out.inlier_lines, &mut inl) } else { (&mut out.outlier_lines, &mut outl) };
        let _ = write!(lines, "M{:.1} {:.1}L{:.1} {:.1}", p[0], p[1], c[0], c[1]);
        ends.extend_from_slice(c);
    }
    out.inlier_ends = INLIER.marker.svg_path(&inl, R);
    out.outlier_ends = OUTLIER.marker.svg_path(&outl, R);
    let det: Vec<f32> = d.detected.iter().flatten().copied().collect();
    out.detected = REDETECTED.marker.svg_path(&det, R);
    out
}

/// The frame an old frame's points are recomputed from: for LK the last
/// frame before it the loop detected on (frame 0 always did), for a matched
/// run the frame before.
pub fn replay_from(counts: &[StepCounts], frame: usize, lk: bool) -> usize {
    if !lk || frame == 0 {
        return frame.saturating_sub(1);
    }
    (0..frame).rev().find(|&j| j == 0 || counts[j].redetected).unwrap_or(0)
}

/// "a of b (p %)", or "a" when b is 0.
fn share(a: u32, b: u32) -> String {
    if b == 0 {
        a.to_string()
    } else {
        format!("{a} of {b} ({:.0} %)", 100.0 * a as f64 / b as f64)
    }
}

/// What the loop did on frame `frame`, in a sentence. `lk`: tracking (else
/// the matcher's matches); `detected`: the points SIFT gave on this frame
/// (frame 0's count).
pub fn counts_text(frame: u32, c: &StepCounts, lk: bool, detected: usize) -> String {
    if frame == 0 {
        return if lk {
            format!("frame 0: SIFT detected {detected} points to track")
        } else {
            "frame 0: its keypoints are matched from frame 1 on".into()
        };
    }
    let (what, from) = if lk { ("tracked", "points") } else { ("matched", "keypoints of the previous frame") };
    let mut s = format!(
        "frame {frame}: {} {from} {what} · RANSAC inliers {} · recoverPose {}",
        share(c.tracked, c.points_in),
        share(c.essential_inliers, c.tracked),
        c.pose_inliers
    );
    if c.redetected && lk {
        s.push_str(" · fewer than 1500 left: SIFT re-detected the points to track");
    }
    s
}

/// The per-frame chart: one polyline's points for `values` (one per frame
/// from 0; frame 0 tracks nothing and is left out), x across `w` for frames
/// 0 … `frames` − 1, y from `ymax` at the top to 0 at `h`.
pub fn series_points(values: &[u32], frames: usize, ymax: u32, w: f64, h: f64) -> String {
    let fy = |v: u32| h - h * v as f64 / ymax.max(1) as f64;
    values
        .iter()
        .enumerate()
        .skip(1)
        .map(|(i, &v)| format!("{:.1},{:.1}", chart_x(i, frames, w), fy(v)))
        .collect::<Vec<_>>()
        .join(" ")
}

/// The chart's x for frame `i` of `frames`.
pub fn chart_x(i: usize, frames: usize, w: f64) -> f64 {
    if frames <= 1 {
        0.0
    } else {
        w * i as f64 / (frames - 1) as f64
    }
}

/// How often the loop re-detected, after frame 0: "SIFT re-detected on 109
/// of 110 frames (whenever fewer than 1500 points survive tracking)".
pub fn redetections_text(c: &[StepCounts]) -> String {
    let after = c.len().saturating_sub(1);
    let n = c.iter().skip(1).filter(|c| c.redetected).count();
    format!("SIFT re-detected on {n} of {after} frames (whenever fewer than 1500 points survive tracking)")
}

/// The chart's top: the largest count, rounded up to a multiple of 500.
pub fn chart_top(values: &[u32]) -> u32 {
    values.iter().copied().max().unwrap_or(0).div_ceil(500).max(1) * 500
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn replays_start_at_the_last_detection() {
        let c = |redetected| StepCounts { redetected, ..StepCounts::default() };
        // Frame 0 detects; frames 1, 2 track; 3 re-detects; 4, 5 track.
        let counts = [c(true), c(false), c(false), c(true), c(false), c(false)];
        let lk: Vec<usize> = (0..6).map(|i| replay_from(&counts, i, true)).collect();
        assert_eq!(lk, [0, 0, 0, 0, 3, 3]);
        let matched: Vec<usize> = (0..6).map(|i| replay_from(&counts, i, false)).collect();
        assert_eq!(matched, [0, 0, 1, 2, 3, 4]);
    }

    #[test]
    fn png_size_reads_ihdr() {
        let mut b = b"\x89PNG\r\n\x1a\n\0\0\0\rIHDR".to_vec();
        b.extend_from_slice(&1241u32.to_be_bytes());
        b.extend_from_slice(&376u32.to_be_bytes());
        assert_eq!(png_size(&b), Some((1241, 376)));
        assert_eq!(png_size(&b[..20]), None);
        assert_eq!(png_size(b"GIF89a....................."), None);
    }

    #[test]
    fn flow_paths_split_by_the_ransac_mask() {
        let d = StepDetail {
            prev: vec![[10.0, 20.0], [30.0, 40.0]],
            cur: vec![[11.0, 21.5], [35.0, 41.0]],
            essential_mask: vec![true, false],
            pose_mask: vec![true, false],
            detected: vec![[5.0, 6.0]],
        };
        let p = flow_paths(&d);
        assert_eq!(p.inlier_lines, "M10.0 20.0L11.0 21.5");
        assert_eq!(p.outlier_lines, "M30.0 40.0L35.0 41.0");
        assert!(p.inlier_ends.starts_with("M8.0 21.5a3 3"), "{}", p.inlier_ends);
        assert!(p.outlier_ends.starts_with('M') && p.outlier_ends.contains('L'));
        assert_eq!(p.detected, "M5.0 3.0L8.0 6.0L5.0 9.0L2.0 6.0Z");
        assert_eq!(flow_paths(&StepDetail::default()), FlowPaths::default());
    }

    #[test]
    fn counts_read_as_a_sentence() {
        let c = StepCounts {
            points_in: 1500,
            tracked: 1480,
            essential_inliers: 1200,
            pose_inliers: 1190,
            redetected: true,
            points_out: 1500,
        };
        assert_eq!(
            counts_text(110, &c, true, 1500),
            "frame 110: 1480 of 1500 (99 %) points tracked · RANSAC inliers 1200 of 1480 (81 %) · recoverPose 1190 \
             · fewer than 1500 left: SIFT re-detected the points to track"
        );
        assert!(counts_text(110, &c, false, 0)
            .starts_with("frame 110: 1480 of 1500 (99 %) keypoints of the previous frame matched"));
        let first = StepCounts { redetected: true, points_out: 1500, ..StepCounts::default() };
        assert_eq!(counts_text(0, &first, true, 1500), "frame 0: SIFT detected 1500 points to track");
    }

    #[test]
    fn chart_geometry() {
        assert_eq!(series_points(&[0, 500, 1000], 3, 1000, 100.0, 50.0), "50.0,25.0 100.0,0.0");
        let c = |r| StepCounts { redetected: r, ..StepCounts::default() };
        assert_eq!(
            redetections_text(&[c(true), c(true), c(false), c(true)]),
            "SIFT re-detected on 2 of 3 frames (whenever fewer than 1500 points survive tracking)"
        );
        assert_eq!(chart_top(&[1499, 1200]), 1500);
        assert_eq!(chart_top(&[1501]), 2000);
        assert_eq!(chart_top(&[]), 500);
    }
}
