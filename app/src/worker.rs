//! The worker side: decode a frame and run SIFT with the lab's parameters,
//! reporting each stage so the page can show progress while it waits.

use crate::msg::{FromWorker, SiftResult, ToWorker};
use crate::platform::now_ms;
use siftlab_core::sift::{detect_and_compute, SiftParams};
use siftlab_core::GrayImage;
use wasm_bindgen::prelude::*;
use wasm_bindgen::JsCast;

/// Handles one request, posting progress and the outcome through `post`.
pub fn handle(msg: ToWorker, post: &dyn Fn(FromWorker)) {
    match msg {
        ToWorker::Sift { id, bytes, lanes } => sift(id, &bytes, lanes, true, post),
        ToWorker::Features { id, bytes, lanes } => sift(id, &bytes, lanes, false, post),
        ToWorker::Inside(r) => crate::inside::handle(r, post),
        ToWorker::VoStart { id, total, poses } => {
            let started = VoSession::start(id, total as usize, &poses);
            let failed = started.as_ref().err().cloned();
            SESSION.with(|s| *s.borrow_mut() = started.ok());
            if let Some(message) = failed {
                post(FromWorker::Failed { id, message });
            }
        }
        ToWorker::VoMatchedStart { id, total, poses, algo, threshold } => {
            let started = siftlab_core::matching::Strategy::parse(&algo, threshold)
                .map_err(|e| e.to_string())
                .and_then(|s| VoSession::start(id, total as usize, &poses).map(|v| v.with_matcher(s)))
                .and_then(|r| r);
            let failed = started.as_ref().err().cloned();
            SESSION.with(|s| *s.borrow_mut() = started.ok());
            if let Some(message) = failed {
                post(FromWorker::Failed { id, message });
            }
        }
        ToWorker::VoFrame { id, frame, bytes, points } => {
            on_session(id, post, |session| session.frame(frame as usize, Input::Image(&bytes, points), post))
        }
        ToWorker::VoFeatures { id, frame, features } => {
            on_session(id, post, |session| session.frame(frame as usize, Input::Features(features), post))
        }
    }
}

/// Runs `f` on the worker's odometry session `id`; an error ends the session.
fn on_session(id: u32, post: &dyn Fn(FromWorker), f: impl FnOnce(&mut VoSession) -> Result<(), String>) {
    let r = SESSION.with(|s| match s.borrow_mut().as_mut() {
        Some(session) if session.id == id => f(session),
        _ => Err("no odometry run is going on (it was stopped or failed)".into()),
    });
    if let Err(message) = r {
        SESSION.with(|s| *s.borrow_mut() = None);
        post(FromWorker::Failed { id, message });
    }
}

/// SIFT on one image with the lab's parameters, its stages posted as
/// progress; the reply carries the gray image only if `with_gray`.
fn sift(id: u32, bytes: &[u8], lanes: u32, with_gray: bool, post: &dyn Fn(FromWorker)) {
    {
        post(FromWorker::Progress { id, stage: "decoding the image".into() });
        let t0 = now_ms();
        let img = match GrayImage::decode(bytes) {
            Ok(img) => img,
            Err(e) => return post(FromWorker::Failed { id, message: e.to_string() }),
        };
        let t1 = now_ms();
        post(FromWorker::Progress {
            id,
            stage: format!("running SIFT on {}x{} (nfeatures=1500)", img.width(), img.height()),
        });
        // The lab's cv2.SIFT_create(nfeatures=1500), with the SIMD width of
        // the OpenCV build being reproduced (it moves angles and descriptors by ulps).
        let params = SiftParams { opencv_lanes: lanes as usize, ..SiftParams::default() };
        let features = detect_and_compute(&img, &params);
        let t2 = now_ms();
        post(FromWorker::Done {
            id,
            result: SiftResult {
                width: img.width(),
                height: img.height(),
                gray: if with_gray { img.data().to_vec() } else { Vec::new() },
                features,
                decode_ms: t1 - t0,
                sift_ms: t2 - t1,
                engine: siftlab_core::sift::fma_engine().to_string(),
                memory: crate::platform::wasm_memory_bytes(),
            },
        });
    }
}

/// What a tracking worker gets for its next frame: the image (and the
/// keypoints a SIFT worker found in it, if any), or a matcher-driven run's
/// SIFT features.
enum Input<'a> {
    Image(&'a [u8], Option<Vec<[f32; 2]>>),
    Features(siftlab_core::sift::Features),
}

thread_local! {
    /// The odometry run this worker tracks for, between `VoFrame` messages.
    static SESSION: std::cell::RefCell<Option<VoSession>> = const { std::cell::RefCell::new(None) };
}

/// The lab's `view_trajectory` loop, a frame at a time: the odometry state,
/// the ground truth and the positions so far.
struct VoSession {
    id: u32,
    total: usize,
    poses: Vec<siftlab_core::dataset::PoseRow>,
    odo: siftlab_core::vo::Odometry,
    /// Set for a run driven by the student's matcher (`odo` then unused).
    matched: Option<siftlab_core::vo::MatchedOdometry>,
    /// Estimated poses as KITTI rows, for the metrics.
    rows: Vec<siftlab_core::dataset::PoseRow>,
    est: Vec<[f64; 3]>,
    truth: Vec<[f64; 3]>,
    t0: f64,
}

impl VoSession {
    /// Checks the poses before any frame is read, as the CLI does.
    fn start(id: u32, total: usize, poses: &str) -> Result<Self, String> {
        use siftlab_core::dataset::parse_poses;
        use siftlab_core::vo::{Camera, Odometry};
        let t0 = now_ms();
        let poses = parse_poses(poses).map_err(|e| format!("poses/00.txt: {e}"))?;
        if poses.len() < total {
            return Err(format!(
                "poses/00.txt has {} poses but {} frames were asked for: the lab takes the scale from the ground truth of every frame",
                poses.len(),
                total
            ));
        }
        let odo = Odometry::new(Camera::default()).map_err(|e| e.to_string())?;
        Ok(VoSession { id, total, poses, odo, matched: None, rows: Vec::new(), est: Vec::new(), truth: Vec::new(), t0 })
    }

    /// The same session tracking with `strategy`'s matches instead of LK.
    fn with_matcher(mut self, strategy: siftlab_core::matching::Strategy) -> Result<Self, String> {
        use siftlab_core::vo::{Camera, MatchedOdometry};
        self.matched = Some(MatchedOdometry::new(Camera::default(), strategy).map_err(|e| e.to_string())?);
        Ok(self)
    }

    /// Frame `i` (the next one): one step, posted; after the last, the
    /// trajectory error and the lab's window as PNG. `points`: the frame's
    /// keypoints if detected elsewhere (else detected here when the loop
    /// re-detects).
    fn frame(&mut self, i: usize, input: Input, post: &dyn Fn(FromWorker)) -> Result<(), String> {
        use siftlab_core::dataset::position;
        use siftlab_core::render::{encode_png, trajectory_window, TrajectoryStyle};
        use siftlab_core::vo::ate_rmse;
        if i != self.est.len() || i >= self.total {
            return Err(format!("frame {i} arrived out of order (expected frame {})", self.est.len()));
        }
        let decode = |bytes: &[u8]| GrayImage::decode(bytes).map_err(|e| format!("frame {i}: {e}"));
        let gt = self.poses.get(i);
        let step = match (self.matched.as_mut(), input) {
            (Some(m), Input::Features(f)) => m.step_features(f, gt),
            (Some(m), Input::Image(bytes, _)) => m.step(&decode(bytes)?, gt),
            (None, Input::Image(bytes, points)) => self.odo.step_detected(&decode(bytes)?, gt, points),
            (None, Input::Features(_)) => {
                return Err(format!("frame {i}: the Lucas–Kanade loop needs the image, not only its features"))
            }
        }
        .map_err(|e| e.to_string())?;
        self.rows.push(siftlab_core::vo::pose_row(&step.rotation, &step.position));
        let gt = step.gt_position.or_else(|| self.poses.get(i).map(position));
        self.est.push(step.position);
        if let Some(g) = gt {
            self.truth.push(g);
        }
        post(FromWorker::VoStep {
            id: self.id,
            frame: i as u32,
            total: self.total as u32,
            position: step.position,
            truth: gt,
            tracked: step.tracked as u32,
            redetected: step.redetected,
        });
        if i + 1 == self.total {
            let ate = ate_rmse(&self.est, &self.truth).map_err(|e| e.to_string())?;
            let style = TrajectoryStyle::default();
            let png = encode_png(&trajectory_window(&self.truth, &self.est, &style)).map_err(|e| e.to_string())?;
            let gt = &self.poses[..self.rows.len()];
            let metrics = siftlab_core::vo::evaluate(&self.rows, gt).map_err(|e| e.to_string())?;
            post(FromWorker::VoMetrics { id: self.id, metrics: metrics.to_array() });
            let kitti = siftlab_core::vo::kitti_rows_text(&self.rows);
            post(FromWorker::VoDone { id: self.id, ate, png, ms: now_ms() - self.t0, kitti });
        }
        Ok(())
    }
}

/// Entry point of the worker script: listen for requests, then say we are ready
/// (the page queues its requests until then, so none is lost during start-up).
pub fn start() {
    std::panic::set_hook(Box::new(|info| {
        web_sys::console::error_1(&format!("siftlab worker panicked: {info}").into());
    }));
    let scope: web_sys::DedicatedWorkerGlobalScope = js_sys::global().unchecked_into();
    let post_scope = scope.clone();
    let onmessage = Closure::<dyn FnMut(web_sys::MessageEvent)>::new(move |ev: web_sys::MessageEvent| {
        let post = |m: FromWorker| {
            let _ = post_scope.post_message(&m.to_js());
        };
        match ToWorker::from_js(&ev.data()) {
            Ok(msg) => handle(msg, &post),
            Err(e) => web_sys::console::error_1(&format!("siftlab worker: {e}").into()),
        }
    });
    scope.set_onmessage(Some(onmessage.as_ref().unchecked_ref()));
    // The handler lives as long as the worker.
    onmessage.forget();
    let _ = scope.post_message(&FromWorker::Ready.to_js());
}
