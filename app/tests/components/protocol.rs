//! The worker messages through their postMessage encoding, bit for bit, and
//! the odometry's refusals named.

use crate::fixtures::golden;
use crate::worker_odometry::one_worker_odometry;
use siftlab_app::protocol::odometry::{StepCounts, Tracker, VoReply, VoRequest};
use siftlab_app::protocol::sift::{SiftReply, SiftRequest, SiftResult};
use siftlab_app::protocol::{is_ready, ready_js, Request};
use siftlab_core::matching::Strategy;
use siftlab_core::vo::{Camera, StepDetail};
use wasm_bindgen_test::*;

#[wasm_bindgen_test]
fn worker_messages_round_trip_bit_for_bit() {
    let (w, h, features) = golden(2);
    let result = SiftResult {
        width: w,
        height: h,
        gray: vec![7; w * h],
        features,
        decode_ms: 1.5,
        sift_ms: 250.0,
        engine: "SIMD128: exact multiply-add emulation".into(),
        memory: 96 << 20,
    };
    let m = SiftReply::Done { id: 3, result };
    assert_eq!(SiftReply::from_js(&m.to_js()).unwrap(), m);
    for s in [
        SiftRequest::Sift { id: 4, bytes: vec![1, 2, 3], lanes: 16 },
        SiftRequest::Features { id: 5, bytes: vec![1, 2, 3], lanes: 8 },
    ] {
        assert_eq!(Request::from_js(&s.to_js()).unwrap(), Request::Sift(s));
    }
    let (_, _, features) = golden(3);
    let s = VoRequest::Features { id: 1, frame: 3, features };
    assert_eq!(Request::from_js(&s.to_js()).unwrap(), Request::Odometry(s));
    assert!(is_ready(&ready_js()));
    assert!(Request::from_js(&ready_js()).unwrap_err().contains("unknown message type"));
    for m in [SiftReply::Progress { id: 1, stage: "x".into() }, SiftReply::Failed { id: 2, message: "m".into() }] {
        assert_eq!(SiftReply::from_js(&m.to_js()).unwrap(), m);
    }
    assert!(SiftReply::from_js(&wasm_bindgen::JsValue::from_str("junk")).is_err());
}

#[wasm_bindgen_test]
fn odometry_messages_round_trip_and_bad_poses_are_named() {
    // Sequence 03's camera travels with the run.
    let camera = Camera { fx: 721.5377, fy: 721.5377, cx: 609.5593, cy: 172.854 };
    let v = VoRequest::Start { id: 5, total: 2, poses: "1 0 0 0 0 1 0 0 0 0 1 0".into(), camera, tracker: Tracker::Lk };
    assert_eq!(Request::from_js(&v.to_js()).unwrap(), Request::Odometry(v.clone()));
    // Each strategy travels typed, an absent threshold as null.
    for s in [Strategy::Nndr(0.8), Strategy::Nn(None), Strategy::Nn(Some(250.0)), Strategy::Dt(200.0)] {
        let m = VoRequest::Start { id: 5, total: 2, poses: "p".into(), camera, tracker: Tracker::Matched(s) };
        assert_eq!(Request::from_js(&m.to_js()).unwrap(), Request::Odometry(m));
    }
    // A tracker that is not one (an nndr without its ratio) is refused by name.
    let m = VoRequest::Start { id: 5, total: 2, poses: "p".into(), camera, tracker: Tracker::Lk }.to_js();
    js_sys::Reflect::set(&m, &"tracker".into(), &"nndr".into()).unwrap();
    assert_eq!(Request::from_js(&m).unwrap_err(), "voStart: tracker \"nndr\" with threshold None is not a tracker");
    // A camera that cannot be one is refused when the message is read.
    let js = v.to_js();
    let bad = js_sys::Float64Array::from([0.0, 721.5377, 609.5593, 172.854].as_slice());
    js_sys::Reflect::set(&js, &"camera".into(), &bad).unwrap();
    let e = Request::from_js(&js).unwrap_err();
    assert!(e.starts_with("message field camera: invalid camera intrinsics fx=0"), "{e}");
    for m in [
        VoReply::Step {
            id: 5,
            frame: 2,
            total: 6,
            position: [0.5, -0.25, 1.75],
            truth: Some([0.0, 0.0, 2.0]),
            counts: StepCounts {
                points_in: 1500,
                tracked: 2,
                essential_inliers: 1,
                pose_inliers: 1,
                redetected: true,
                points_out: 1499,
            },
            detail: Some(Box::new(StepDetail {
                prev: vec![[1.5, 2.25], [3.0, 4.0]],
                cur: vec![[1.0, 2.0], [3.5, 4.5]],
                essential_mask: vec![true, false],
                pose_mask: vec![true, false],
                detected: vec![[7.0, 8.0]],
            })),
        },
        VoReply::Step {
            id: 5,
            frame: 0,
            total: 6,
            position: [0.0; 3],
            truth: None,
            counts: StepCounts::default(),
            detail: None,
        },
        VoReply::Done { id: 5, ate: 0.2815, png: vec![137, 80, 78, 71], ms: 1234.5, kitti: "1 0 0 0\n".into() },
        VoReply::Metrics { id: 5, metrics: [100.0, 1.1, 0.14, 0.13, 0.12, f64::NAN, f64::NAN] },
    ] {
        let back = VoReply::from_js(&m.to_js()).unwrap();
        if let (VoReply::Metrics { metrics: a, .. }, VoReply::Metrics { metrics: b, .. }) = (&back, &m) {
            // NaN (no KITTI segment) is not equal to itself: compare the bits.
            assert_eq!(a.map(f64::to_bits), b.map(f64::to_bits));
            continue;
        }
        assert_eq!(VoReply::from_js(&m.to_js()).unwrap(), m);
    }
    let run = |frames: Vec<Vec<u8>>, poses: &str| one_worker_odometry(1, frames, poses);
    // Malformed poses and too few poses fail before any SIFT runs, with the file named.
    let got = run(vec![vec![0; 4]; 2], "1 0 0 0\n");
    let [VoReply::Failed { message, .. }] = got.as_slice() else { panic!("{got:?}") };
    assert!(message.starts_with("the poses file line 1"), "{message}");
    let got = run(vec![vec![0; 4]; 3], "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 0 0 1 0 0 0 0 1 1\n");
    let [VoReply::Failed { message, .. }] = got.as_slice() else { panic!("{got:?}") };
    assert!(message.contains("has 2 poses but the odometry needs 3"), "{message}");
    // A frame that is not an image: named by its index.
    let got = run(vec![b"nope".to_vec(); 2], "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 0 0 1 0 0 0 0 1 1\n");
    let [VoReply::Failed { message, .. }] = got.as_slice() else { panic!("{got:?}") };
    assert!(message.starts_with("frame 0: not an image"), "{message}");
}
