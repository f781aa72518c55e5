//! The loop's tests on a synthetic zooming "road" (the lab's rules, the
//! recorded points, the iterator, errors, the pipelined run).

use super::pipeline::run_with_workers;
use super::*;
use crate::camera::Camera;
use crate::dataset::PoseRow;
use crate::{Error, GrayImage, Result};

/// A textured "road" image seen by a camera displaced by `dz` forward:
/// a pure zoom about the principal point of a far plane approximates it.
fn frame(w: usize, h: usize, zoom: f64, cam: &Camera) -> GrayImage {
    let mut d = vec![0u8; w * h];
    for y in 0..h {
        for x in 0..w {
            let u = (x as f64 - cam.cx) / zoom;
            let v = (y as f64 - cam.cy) / zoom;
            let val = 128.0
                + 45.0 * (u * 0.11 + v * 0.05).sin()
                + 40.0 * (v * 0.13 - u * 0.07).sin()
                + 30.0 * (u * 0.031).cos() * (v * 0.027).sin();
            d[y * w + x] = val.round().clamp(0.0, 255.0) as u8;
        }
    }
    GrayImage::new(w, h, d).unwrap()
}

fn grid(img: &GrayImage) -> Vec<[f32; 2]> {
    let mut p = Vec::new();
    for y in (20..img.height() - 20).step_by(12) {
        for x in (20..img.width() - 20).step_by(12) {
            p.push([x as f32 + 0.5, y as f32 + 0.5]);
        }
    }
    p
}

fn gt(z: f64) -> PoseRow {
    [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, z]
}

#[test]
fn loop_follows_the_lab_rules() {
    let cam = Camera { fx: 300.0, fy: 300.0, cx: 160.0, cy: 120.0 };
    let mut odo = Odometry::with_detector(cam, Box::new(grid)).unwrap();
    odo.min_points = 10_000;
    let r0 = odo.step(&frame(320, 240, 1.0, &cam), Some(&gt(0.0))).unwrap();
    assert!(r0.redetected && r0.points_out > 300);
    assert_eq!(r0.position, [0.0; 3]);
    let r1 = odo.step(&frame(320, 240, 1.02, &cam), Some(&gt(1.0))).unwrap();
    // Frame 1: position drawn as 0, never re-detects.
    assert_eq!(r1.position, [0.0; 3]);
    assert!(!r1.redetected && r1.scale.is_none());
    assert!(r1.tracked > 250, "{}", r1.tracked);
    // Frame 2 with a GT step of 0.05 (≤ 0.1): no update, but re-detection.
    let before = odo.pose();
    let r2 = odo.step(&frame(320, 240, 1.04, &cam), Some(&gt(1.05))).unwrap();
    assert_eq!(r2.scale, Some(0.050000000000000044));
    assert!(!r2.updated && r2.redetected);
    assert_eq!(odo.pose(), before);
    assert_eq!(r2.position, before.1);
    // Frame 3 with a GT step of 2: t += 2·R·ti.
    let r3 = odo.step(&frame(320, 240, 1.06, &cam), Some(&gt(3.05))).unwrap();
    assert!(r3.updated);
    let moved: f64 = (0..3).map(|k| (r3.position[k] - r2.position[k]).powi(2)).sum::<f64>().sqrt();
    assert!((moved - 2.0).abs() < 1e-9, "moved {moved}");
}

/// The recorded points are the ones the counts count, and recording
/// changes nothing else.
#[test]
fn detail_matches_the_counts() {
    let cam = Camera { fx: 300.0, fy: 300.0, cx: 160.0, cy: 120.0 };
    let (mut plain, mut rec) =
        (Odometry::with_detector(cam, Box::new(grid)).unwrap(), Odometry::with_detector(cam, Box::new(grid)).unwrap());
    plain.min_points = 10_000;
    rec.min_points = 10_000;
    rec.record_detail = true;
    for k in 0..4 {
        let img = frame(320, 240, 1.0 + 0.02 * k as f64, &cam);
        let a = plain.step(&img, Some(&gt(k as f64))).unwrap();
        let mut b = rec.step(&img, Some(&gt(k as f64))).unwrap();
        let d = b.detail.take().expect("recorded");
        assert_eq!(a, b, "frame {k}");
        let count = |m: &[bool]| m.iter().filter(|&&x| x).count();
        assert_eq!((d.prev.len(), d.cur.len()), (a.tracked, a.tracked));
        assert_eq!(count(&d.essential_mask), a.essential_inliers);
        assert_eq!(count(&d.pose_mask), a.pose_inliers);
        assert_eq!(d.detected.len(), if a.redetected { a.points_out } else { 0 });
        assert!(
            d.pose_mask.iter().zip(&d.essential_mask).all(|(&p, &e)| !p || e),
            "recoverPose counts RANSAC inliers only"
        );
    }
}

#[test]
fn iterator_yields_one_result_per_frame() {
    let cam = Camera { fx: 300.0, fy: 300.0, cx: 160.0, cy: 120.0 };
    let mut odo = Odometry::with_detector(cam, Box::new(grid)).unwrap();
    let frames = (0..4).map(|k| Ok((frame(320, 240, 1.0 + 0.02 * k as f64, &cam), Some(gt(k as f64)))));
    let out: Vec<StepResult> = odo.steps(frames).collect::<Result<_>>().unwrap();
    assert_eq!(out.iter().map(|r| r.frame).collect::<Vec<_>>(), vec![0, 1, 2, 3]);
    assert_eq!(out[3].scale, Some(1.0));
    assert!(out[2].updated && out[3].updated);
    assert_eq!(odo.next_frame(), 4);
}

#[test]
fn errors_leave_the_state_unchanged() {
    let cam = Camera { fx: 300.0, fy: 300.0, cx: 160.0, cy: 120.0 };
    let mut odo = Odometry::with_detector(cam, Box::new(grid)).unwrap();
    odo.step(&frame(320, 240, 1.0, &cam), Some(&gt(0.0))).unwrap();
    let e = odo.step(&frame(300, 240, 1.0, &cam), Some(&gt(1.0))).unwrap_err();
    assert!(e.to_string().contains("frame 1 is 300x240 but the previous frames are 320x240"), "{e}");
    assert_eq!(odo.next_frame(), 1);
    odo.step(&frame(320, 240, 1.02, &cam), Some(&gt(1.0))).unwrap();
    let e = odo.step(&frame(320, 240, 1.04, &cam), None).unwrap_err();
    assert!(e.to_string().contains("frame 2 needs the ground-truth poses"), "{e}");
    assert_eq!(odo.next_frame(), 2);
    // KITTI intrinsics on a small frame.
    let mut kitti = Odometry::with_detector(Camera::default(), Box::new(grid)).unwrap();
    let e = kitti.step(&frame(320, 240, 1.0, &cam), None).unwrap_err();
    assert!(e.to_string().contains("too small for the camera"), "{e}");
}

/// `run`'s pipeline (detection ahead on another thread) gives exactly
/// what stepping frame by frame gives, keeps the detector, and stops at
/// a frame that cannot be read with the earlier results kept in `odo`.
#[test]
fn pipelined_run_equals_stepping() {
    let cam = Camera { fx: 300.0, fy: 300.0, cx: 160.0, cy: 120.0 };
    let poses: Vec<PoseRow> = (0..6).map(|k| gt(0.7 * k as f64)).collect();
    let img = |k: usize| frame(320, 240, 1.0 + 0.015 * k as f64, &cam);
    let mut stepped = Odometry::with_detector(cam, Box::new(grid)).unwrap();
    stepped.min_points = 10_000;
    let want: Vec<StepResult> = (0..6).map(|k| stepped.step(&img(k), Some(&poses[k])).unwrap()).collect();
    // One detection thread, two (this machine's usual) and three: each
    // takes every n-th frame, and the results come back in frame order.
    for workers in 1..=3 {
        let mut odo = Odometry::with_detector(cam, Box::new(grid)).unwrap();
        odo.min_points = 10_000;
        let mut seen = Vec::new();
        let got =
            run_with_workers(&mut odo, 6, &poses, |k| Ok(img(k)), &mut |d, n| seen.push((d, n)), workers).unwrap();
        assert_eq!(got, want, "{workers} workers");
        assert!(got[2..].iter().all(|r| r.redetected));
        assert_eq!(seen, (1..=6).map(|d| (d, 6)).collect::<Vec<_>>());
        assert_eq!(odo.pose(), stepped.pose());
        // The detector is back in place: a further step detects with it.
        let r = odo.step(&img(6), Some(&gt(4.9))).unwrap();
        assert!(r.redetected && r.points_out > 300);

        // A frame that cannot be read stops the run with its error, on
        // whichever worker it lands, after the frames before it.
        for broken in [1, 3, 4] {
            let mut failing = Odometry::with_detector(cam, Box::new(grid)).unwrap();
            let load = |k: usize| {
                if k == broken {
                    Err(Error::Odometry(format!("frame {k} is broken")))
                } else {
                    Ok(img(k))
                }
            };
            let e = run_with_workers(&mut failing, 6, &poses, load, &mut |_, _| {}, workers).unwrap_err();
            assert!(e.to_string().contains(&format!("frame {broken} is broken")), "{e}");
            assert_eq!(failing.next_frame(), broken, "{workers} workers");
        }
    }
}

/// A frame's counts and points, recomputed from the last frame the loop
/// detected on (its image and points) by [`Odometry::resume`], equal the
/// original run's: the page shows a long run's old frames that way.
#[test]
fn resumed_loop_replays_each_frame() {
    let cam = Camera { fx: 300.0, fy: 300.0, cx: 160.0, cy: 120.0 };
    let img = |k: usize| frame(320, 240, 1.0 + 0.035 * k as f64, &cam);
    let poses: Vec<PoseRow> = (0..12).map(|k| gt(0.5 * k as f64)).collect();
    let mut odo = Odometry::with_detector(cam, Box::new(grid)).unwrap();
    // Re-detect only when a tenth of the grid is lost: chains of several frames.
    odo.min_points = 390;
    odo.record_detail = true;
    let run: Vec<StepResult> = (0..12).map(|k| odo.step(&img(k), Some(&poses[k])).unwrap()).collect();
    let redetected: Vec<usize> = (0..12).filter(|&k| run[k].redetected).collect();
    assert!(redetected.len() >= 3 && redetected.windows(2).any(|w| w[1] - w[0] >= 3), "{redetected:?}");
    for i in 1..12 {
        let j = *redetected.iter().rev().find(|&&j| j < i).unwrap();
        let refs = run[j].detail.as_ref().unwrap().detected.clone();
        let mut replay = Odometry::resume(cam, Box::new(grid), j, &img(j), refs, Some(&poses[j])).unwrap();
        replay.min_points = odo.min_points;
        for (k, pose) in poses.iter().enumerate().take(i).skip(j + 1) {
            replay.step(&img(k), Some(pose)).unwrap();
        }
        replay.record_detail = true;
        let got = replay.step(&img(i), Some(&poses[i])).unwrap();
        let want = &run[i];
        assert_eq!(got.detail, want.detail, "frame {i} from {j}");
        let counts =
            |r: &StepResult| (r.points_in, r.tracked, r.essential_inliers, r.pose_inliers, r.redetected, r.points_out);
        assert_eq!(counts(&got), counts(want), "frame {i} from {j}");
    }
}
