//! The SIFT workers' messages: a frame's bytes in, its keypoints and
//! descriptors (and, for the pair view, the gray image) out.

use super::codec::*;
use js_sys::{Object, Uint8Array};
use siftlab_core::sift::Features;
use wasm_bindgen::JsValue;

/// Page → SIFT worker.
#[derive(Debug, Clone, PartialEq)]
pub enum SiftRequest {
    /// Decode `bytes` (PNG/JPEG) as the core does and run SIFT with the lab's
    /// parameters; `lanes` is OpenCV's SIMD width to reproduce (8 = AVX2, 16 = AVX-512).
    Sift { id: u32, bytes: Vec<u8>, lanes: u32 },
    /// [`SiftRequest::Sift`] without the gray image in the reply (its `Done`
    /// has an empty `gray`): what an odometry run asks for each frame, so the
    /// page's cache holds 0.23 MB per KITTI frame instead of 0.7 MB.
    Features { id: u32, bytes: Vec<u8>, lanes: u32 },
}

/// What SIFT produced for one frame, plus the gray image it ran on.
#[derive(Debug, Clone, PartialEq)]
pub struct SiftResult {
    pub width: usize,
    pub height: usize,
    /// Empty in the reply to [`SiftRequest::Features`].
    pub gray: Vec<u8>,
    pub features: Features,
    pub decode_ms: f64,
    pub sift_ms: f64,
    /// How the worker's build computes SIFT's multiply-adds (`fma_engine`).
    pub engine: String,
    /// The worker's wasm memory (`memory.buffer.byteLength`) after the job:
    /// linear memory never shrinks, so this is the worker's peak so far.
    pub memory: u32,
}

/// SIFT worker → page.
#[derive(Debug, Clone, PartialEq)]
pub enum SiftReply {
    /// A job reached a new stage (shown to the user as progress).
    Progress {
        id: u32,
        stage: String,
    },
    Done {
        id: u32,
        result: SiftResult,
    },
    /// A user-facing message (the core's `Error` Display).
    Failed {
        id: u32,
        message: String,
    },
}

impl SiftRequest {
    pub fn to_js(&self) -> JsValue {
        let o = Object::new();
        match self {
            SiftRequest::Sift { id, bytes, lanes } => set_image_job(&o, "sift", *id, bytes, *lanes),
            SiftRequest::Features { id, bytes, lanes } => set_image_job(&o, "features", *id, bytes, *lanes),
        }
        o.into()
    }

    /// `None` when `v` is not a SIFT request.
    pub fn from_js(v: &JsValue) -> Option<Result<Self, String>> {
        let job = || Ok::<_, String>((get_u32(v, "id")?, get_bytes(v, "bytes")?, get_u32(v, "lanes")?));
        Some(match kind(v).ok()?.as_str() {
            "sift" => job().map(|(id, bytes, lanes)| SiftRequest::Sift { id, bytes, lanes }),
            "features" => job().map(|(id, bytes, lanes)| SiftRequest::Features { id, bytes, lanes }),
            _ => return None,
        })
    }
}

impl SiftReply {
    pub fn to_js(&self) -> JsValue {
        let o = Object::new();
        match self {
            SiftReply::Progress { id, stage } => {
                set_progress(&o, *id, stage);
            }
            SiftReply::Failed { id, message } => {
                set_failed(&o, *id, message);
            }
            SiftReply::Done { id, result } => {
                set(&o, "type", &"done".into());
                set(&o, "id", &(*id).into());
                set(&o, "width", &(result.width as u32).into());
                set(&o, "height", &(result.height as u32).into());
                set(&o, "gray", &Uint8Array::from(result.gray.as_slice()).into());
                set_features(&o, "", &result.features);
                set(&o, "decodeMs", &result.decode_ms.into());
                set(&o, "siftMs", &result.sift_ms.into());
                set(&o, "engine", &result.engine.as_str().into());
                set(&o, "memory", &result.memory.into());
            }
        }
        o.into()
    }

    pub fn from_js(v: &JsValue) -> Result<Self, String> {
        match kind(v)?.as_str() {
            "progress" => Ok(SiftReply::Progress { id: get_u32(v, "id")?, stage: get_str(v, "stage")? }),
            "failed" => Ok(SiftReply::Failed { id: get_u32(v, "id")?, message: get_str(v, "message")? }),
            "done" => {
                let parts = SiftParts {
                    width: get_u32(v, "width")?,
                    height: get_u32(v, "height")?,
                    gray: get_bytes(v, "gray")?,
                    features: get_features(v, "")?,
                };
                Ok(SiftReply::Done {
                    id: get_u32(v, "id")?,
                    result: SiftResult {
                        decode_ms: get_f64(v, "decodeMs")?,
                        sift_ms: get_f64(v, "siftMs")?,
                        engine: get_str(v, "engine")?,
                        memory: get_u32(v, "memory")?,
                        ..parts.check()?
                    },
                })
            }
            other => Err(format!("not a SIFT worker's reply: {other:?}")),
        }
    }
}

/// The image part of a `done` message as it arrives.
#[derive(Debug, Clone, Default)]
pub struct SiftParts {
    pub width: u32,
    pub height: u32,
    pub gray: Vec<u8>,
    pub features: Features,
}

impl SiftParts {
    /// Checks the image's size and builds the result (timings and engine
    /// empty). An empty `gray` is a reply without the image
    /// ([`SiftRequest::Features`]), whatever the size. The size is compared
    /// in u64: in usize, 65536 × 65536 wraps to 0 on wasm32 and an empty
    /// buffer would pass as a 4-gigapixel image.
    pub fn check(self) -> Result<SiftResult, String> {
        let SiftParts { width, height, gray, features } = self;
        if !gray.is_empty() && gray.len() as u64 != width as u64 * height as u64 {
            return Err(format!("gray buffer has {} bytes for {width}x{height}", gray.len()));
        }
        Ok(SiftResult {
            width: width as usize,
            height: height as usize,
            gray,
            features,
            decode_ms: 0.0,
            sift_ms: 0.0,
            engine: String::new(),
            memory: 0,
        })
    }
}
