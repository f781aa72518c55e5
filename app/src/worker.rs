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
