//! The odometry worker: the lab's loop in one worker, and the app's streamed
//! run with helper workers' keypoints, replays and refusals.

use siftlab_app::protocol::odometry::{StepCounts, Tracker, VoReply, VoRequest};
use siftlab_app::protocol::sift::{SiftReply, SiftRequest};
use siftlab_app::protocol::Request;
use siftlab_core::matching::Strategy;
use siftlab_core::sift::Features;
use siftlab_core::vo::{Camera, StepDetail};
use wasm_bindgen_test::*;

/// The lab's odometry loop in one worker: `VoStart`, then every frame with no
/// keypoints given (the worker detects where the loop re-detects), until the
/// first failure.
pub(crate) fn one_worker_odometry(id: u32, frames: Vec<Vec<u8>>, poses: &str) -> Vec<VoReply> {
    let got = std::cell::RefCell::new(Vec::new());
    let post = |m: VoReply| got.borrow_mut().push(m);
    let failed = |got: &std::cell::RefCell<Vec<VoReply>>| matches!(got.borrow().last(), Some(VoReply::Failed { .. }));
    let total = frames.len() as u32;
    siftlab_app::worker::odometry::handle(
        VoRequest::Start { id, total, poses: poses.into(), camera: Camera::default(), tracker: Tracker::Lk },
        &post,
    );
    for (i, bytes) in frames.into_iter().enumerate() {
        if failed(&got) {
            break;
        }
        siftlab_app::worker::odometry::handle(VoRequest::Frame { id, frame: i as u32, bytes, points: None }, &post);
    }
    got.into_inner()
}

/// The app's odometry as `run_vo` drives it (a tracking worker fed one frame at a
/// time with keypoints detected ahead by helper workers) gives exactly what the
/// one-worker loop gives: every step's positions and counts, the trajectory error
/// and the PNG. Both are run here through the worker's message handler, on four of
/// the bundled KITTI frames; the e2e test compares the page with the CLI.
#[wasm_bindgen_test]
fn streamed_odometry_equals_the_one_worker_loop() {
    let frames: Vec<Vec<u8>> = (0..4)
        .map(|i| match i {
            0 => include_bytes!("../../../www/demo/MyKITTI/gray/00/image_0/000000.png").to_vec(),
            1 => include_bytes!("../../../www/demo/MyKITTI/gray/00/image_0/000001.png").to_vec(),
            2 => include_bytes!("../../../www/demo/MyKITTI/gray/00/image_0/000002.png").to_vec(),
            _ => include_bytes!("../../../www/demo/MyKITTI/gray/00/image_0/000003.png").to_vec(),
        })
        .collect();
    let poses = include_str!("../../../www/demo/MyKITTI/poses/00.txt");
    let handle = |m: VoRequest| {
        let got = std::cell::RefCell::new(Vec::new());
        siftlab_app::worker::odometry::handle(m, &|m| got.borrow_mut().push(m));
        got.into_inner()
    };
    let handle_sift = |m: SiftRequest| {
        let got = std::cell::RefCell::new(Vec::new());
        siftlab_app::worker::sift::handle(m, &|m| got.borrow_mut().push(m));
        got.into_inner()
    };
    let without_time = |m: VoReply| match m {
        VoReply::Done { id, ate, png, kitti, .. } => VoReply::Done { id, ate, png, ms: 0.0, kitti },
        // The KITTI figures are NaN (4 frames: no 100 m segment), and NaN != NaN.
        VoReply::Metrics { id, metrics } => {
            VoReply::Metrics { id, metrics: metrics.map(|v| if v.is_nan() { -1.0 } else { v }) }
        }
        m => m,
    };
    let one_worker: Vec<VoReply> =
        one_worker_odometry(7, frames.clone(), poses).into_iter().map(without_time).collect();
    assert_eq!(one_worker.len(), 6, "{one_worker:?}");
    assert!(matches!(one_worker[4], VoReply::Metrics { metrics, .. } if metrics[0] == 4.0));
    assert!(matches!(one_worker[5], VoReply::Done { .. }));

    assert!(handle(VoRequest::Start {
        id: 7,
        total: 4,
        poses: poses.into(),
        camera: Camera::default(),
        tracker: Tracker::Lk
    })
    .is_empty());
    // Each frame's SIFT as the page's SIFT workers compute it (no gray image),
    // through the postMessage encoding.
    let features: Vec<Features> = frames
        .iter()
        .enumerate()
        .map(|(i, bytes)| {
            let msg = SiftRequest::Features { id: i as u32, bytes: bytes.clone(), lanes: 8 };
            assert_eq!(Request::from_js(&msg.to_js()).unwrap(), Request::Sift(msg.clone()));
            let got = handle_sift(msg);
            let Some(SiftReply::Done { result, .. }) = got.last() else { panic!("{got:?}") };
            assert!(result.gray.is_empty() && result.width == 1241, "{}x{}", result.width, result.height);
            assert!(result.memory > 0);
            let back = SiftReply::from_js(&got.last().unwrap().to_js()).unwrap();
            assert_eq!(&back, got.last().unwrap());
            assert!(
                result.features.keypoints.len() >= 1400,
                "frame {i}: {} keypoints",
                result.features.keypoints.len()
            );
            result.features.clone()
        })
        .collect();
    let mut streamed = Vec::new();
    for (i, bytes) in frames.iter().enumerate() {
        // As `vo_run` sends them: the keypoint positions, except on frame 1.
        let points = (i != 1).then(|| features[i].keypoints.iter().map(|k| [k.x, k.y]).collect::<Vec<_>>());
        let msg = VoRequest::Frame { id: 7, frame: i as u32, bytes: bytes.clone(), points };
        assert_eq!(Request::from_js(&msg.to_js()).unwrap(), Request::Odometry(msg.clone()));
        streamed.extend(handle(msg).into_iter().map(without_time));
    }
    assert_eq!(streamed, one_worker);
    // Each frame's points recomputed from the last frame the loop detected on
    // (what the page asks when an old frame of a long run is shown) are the
    // run's, through the message encoding both ways.
    let steps: Vec<(StepCounts, Option<Box<StepDetail>>)> = streamed
        .iter()
        .filter_map(|m| match m {
            VoReply::Step { counts, detail, .. } => Some((*counts, detail.clone())),
            _ => None,
        })
        .collect();
    assert_eq!(steps.len(), 4);
    let points = |f: &Features| f.keypoints.iter().map(|k| [k.x, k.y]).collect::<Vec<_>>();
    for i in 0..4 {
        let from = (0..i).rev().find(|&j| j == 0 || steps[j].0.redetected).unwrap_or(0);
        let msg = VoRequest::Replay {
            token: 40 + i as u32,
            from: from as u32,
            frame: i as u32,
            frames: frames[from..=i].to_vec(),
            refs: points(&features[from]),
            detected: (i > from && steps[i].0.redetected).then(|| points(&features[i])),
            features: Vec::new(),
        };
        assert_eq!(Request::from_js(&msg.to_js()).unwrap(), Request::Odometry(msg.clone()));
        let got = handle(msg);
        let [reply] = got.as_slice() else { panic!("{got:?}") };
        assert_eq!(VoReply::from_js(&reply.to_js()).unwrap(), *reply);
        let VoReply::Replayed { token, frame, detail: Ok(detail) } = reply else { panic!("{reply:?}") };
        assert_eq!((*token, *frame), (40 + i as u32, i as u32));
        assert!(detail.is_some(), "frame {i}");
        assert_eq!(detail, &steps[i].1, "frame {i} replayed from {from}");
    }
    // A frame the run has not reached is refused with the reason.
    let got = handle(VoRequest::Replay {
        token: 50,
        from: 0,
        frame: 9,
        frames: Vec::new(),
        refs: Vec::new(),
        detected: None,
        features: Vec::new(),
    });
    let [VoReply::Replayed { detail: Err(e), .. }] = got.as_slice() else { panic!("{got:?}") };
    assert!(e.contains("frame 9 is not among the run's frames"), "{e}");

    // A frame out of turn ends the run with a message, and later frames are refused.
    assert!(handle(VoRequest::Start {
        id: 8,
        total: 4,
        poses: poses.into(),
        camera: Camera::default(),
        tracker: Tracker::Lk
    })
    .is_empty());
    let got = handle(VoRequest::Frame { id: 8, frame: 2, bytes: frames[2].clone(), points: None });
    let [VoReply::Failed { message, .. }] = got.as_slice() else { panic!("{got:?}") };
    assert!(message.contains("out of order"), "{message}");
    let got = handle(VoRequest::Frame { id: 8, frame: 0, bytes: frames[0].clone(), points: None });
    let [VoReply::Failed { message, .. }] = got.as_slice() else { panic!("{got:?}") };
    assert!(message.contains("no odometry run"), "{message}");
    // An LK run refuses features without the image.
    assert!(handle(VoRequest::Start {
        id: 9,
        total: 4,
        poses: poses.into(),
        camera: Camera::default(),
        tracker: Tracker::Lk
    })
    .is_empty());
    let got = handle(VoRequest::Features { id: 9, frame: 0, features: features[0].clone() });
    let [VoReply::Failed { message, .. }] = got.as_slice() else { panic!("{got:?}") };
    assert!(message.contains("needs the image"), "{message}");

    // A matcher-driven run fed the shared features (`VoFeatures`) gives what
    // the same run computing SIFT itself from the images gives.
    let start = |id| VoRequest::Start {
        id,
        total: 4,
        poses: poses.into(),
        camera: Camera::default(),
        tracker: Tracker::Matched(Strategy::Nndr(0.8)),
    };
    let mut own = Vec::new();
    assert!(handle(start(10)).is_empty());
    for (i, bytes) in frames.iter().enumerate() {
        own.extend(
            handle(VoRequest::Frame { id: 10, frame: i as u32, bytes: bytes.clone(), points: None })
                .into_iter()
                .map(without_time),
        );
    }
    let mut shared = Vec::new();
    assert!(handle(start(10)).is_empty());
    for (i, f) in features.into_iter().enumerate() {
        shared
            .extend(handle(VoRequest::Features { id: 10, frame: i as u32, features: f }).into_iter().map(without_time));
    }
    assert_eq!(own.len(), 6, "{own:?}");
    assert_eq!(shared, own);
    // A SIFT worker given a broken frame says why.
    let got = handle_sift(SiftRequest::Features { id: 3, bytes: b"nope".to_vec(), lanes: 8 });
    let Some(SiftReply::Failed { message, .. }) = got.last() else { panic!("{got:?}") };
    assert!(message.starts_with("not an image"), "{message}");
}
