//! The worker side: decode a frame and run SIFT with the lab's parameters,
//! reporting each stage so the page can show progress while it waits.

use crate::msg::{FromWorker, SiftResult, ToWorker};
use siftlab_core::sift::{detect_and_compute, SiftParams};
use siftlab_core::GrayImage;
use wasm_bindgen::prelude::*;
use wasm_bindgen::JsCast;

/// `performance.now()` of whatever global we run in (window or worker).
pub fn now_ms() -> f64 {
    let perf = js_sys::Reflect::get(&js_sys::global(), &"performance".into()).ok();
    perf.and_then(|p| {
        let now = js_sys::Reflect::get(&p, &"now".into()).ok()?;
        now.dyn_ref::<js_sys::Function>()?.call0(&p).ok()?.as_f64()
    })
    .unwrap_or_else(js_sys::Date::now)
}

/// Handles one request, posting progress and the outcome through `post`.
pub fn handle(msg: ToWorker, post: &dyn Fn(FromWorker)) {
    match msg {
        ToWorker::Sift { id, bytes, lanes } => {
            post(FromWorker::Progress { id, stage: "decoding the image".into() });
            let t0 = now_ms();
            let img = match GrayImage::decode(&bytes) {
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
                    gray: img.data().to_vec(),
                    features,
                    decode_ms: t1 - t0,
                    sift_ms: t2 - t1,
                },
            });
        }
        ToWorker::Vo { id, frames, poses } => {
            if let Err(message) = odometry(id, &frames, &poses, post) {
                post(FromWorker::Failed { id, message });
            }
        }
    }
}

/// The lab's `view_trajectory` loop, one message per frame so the page can
/// draw the trajectory as it grows.
fn odometry(id: u32, frames: &[Vec<u8>], poses: &str, post: &dyn Fn(FromWorker)) -> Result<(), String> {
    use siftlab_core::dataset::{parse_poses, position};
    use siftlab_core::render::{encode_png, trajectory};
    use siftlab_core::vo::{metrics::ate_rmse, odometry::Odometry, Camera};
    let t0 = now_ms();
    let poses = parse_poses(poses).map_err(|e| format!("poses/00.txt: {e}"))?;
    if poses.len() < frames.len() {
        return Err(format!(
            "poses/00.txt has {} poses but {} frames were asked for: the lab takes the scale from the ground truth of every frame",
            poses.len(),
            frames.len()
        ));
    }
    let mut odo = Odometry::new(Camera::default()).map_err(|e| e.to_string())?;
    let (mut est, mut truth) = (Vec::new(), Vec::new());
    let total = frames.len() as u32;
    for (i, bytes) in frames.iter().enumerate() {
        let img = GrayImage::decode(bytes).map_err(|e| format!("frame {i}: {e}"))?;
        let step = odo.step(&img, poses.get(i)).map_err(|e| e.to_string())?;
        let gt = step.gt_position.or_else(|| poses.get(i).map(position));
        est.push(step.position);
        if let Some(g) = gt {
            truth.push(g);
        }
        post(FromWorker::VoStep {
            id,
            frame: i as u32,
            total,
            position: step.position,
            truth: gt,
            tracked: step.tracked as u32,
            redetected: step.redetected,
        });
    }
    let ate = ate_rmse(&est, &truth).map_err(|e| e.to_string())?;
    let png = encode_png(&trajectory::draw(&truth, &est, &trajectory::Style::default())).map_err(|e| e.to_string())?;
    post(FromWorker::VoDone { id, ate, png, ms: now_ms() - t0 });
    Ok(())
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
