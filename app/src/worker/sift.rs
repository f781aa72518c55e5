//! The SIFT worker's job: decode a frame and run SIFT with the lab's
//! parameters, reporting each stage so the page can show progress.

use crate::platform::now_ms;
use crate::protocol::sift::{SiftReply, SiftRequest, SiftResult};
use siftlab_core::sift::{detect_and_compute, SiftParams};
use siftlab_core::GrayImage;

/// Handles one request, posting progress and the outcome through `post`.
pub fn handle(req: SiftRequest, post: &dyn Fn(SiftReply)) {
    match req {
        SiftRequest::Sift { id, bytes, lanes } => sift(id, &bytes, lanes, true, post),
        SiftRequest::Features { id, bytes, lanes } => sift(id, &bytes, lanes, false, post),
    }
}

/// SIFT on one image with the lab's parameters, its stages posted as
/// progress; the reply carries the gray image only if `with_gray`.
fn sift(id: u32, bytes: &[u8], lanes: u32, with_gray: bool, post: &dyn Fn(SiftReply)) {
    {
        post(SiftReply::Progress { id, stage: "decoding the image".into() });
        let t0 = now_ms();
        let img = match GrayImage::decode(bytes) {
            Ok(img) => img,
            Err(e) => return post(SiftReply::Failed { id, message: e.to_string() }),
        };
        let t1 = now_ms();
        post(SiftReply::Progress {
            id,
            stage: format!("running SIFT on {}x{} (nfeatures=1500)", img.width(), img.height()),
        });
        // The lab's cv2.SIFT_create(nfeatures=1500), with the SIMD width of
        // the OpenCV build being reproduced (it moves angles and descriptors by ulps).
        let params = SiftParams { opencv_lanes: lanes as usize, ..SiftParams::default() };
        let features = detect_and_compute(&img, &params);
        let t2 = now_ms();
        post(SiftReply::Done {
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
