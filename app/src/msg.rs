//! The messages between the page and the SIFT worker, typed on both sides.
//!
//! They cross `postMessage` as plain JS objects whose bulky parts are typed
//! arrays (the gray pixels, the keypoint floats, the descriptor bytes), so the
//! structured clone copies a few flat buffers instead of thousands of objects.
//! Keypoint fields travel as f32 and the octave as i32: exactly the types the
//! core computes, so nothing is rounded on the way.

use crate::codec::*;
pub use crate::codec::{points_field, u32_field, vec3_field};
use js_sys::{Float32Array, Int32Array, Object, Uint8Array};
use siftlab_core::sift::{Features, KeyPoint};
use wasm_bindgen::{JsCast, JsValue};

/// Page → worker.
#[derive(Debug, Clone, PartialEq)]
pub enum ToWorker {
    /// Decode `bytes` (PNG/JPEG) as the core does and run SIFT with the lab's
    /// parameters; `lanes` is OpenCV's SIMD width to reproduce (8 = AVX2, 16 = AVX-512).
    Sift { id: u32, bytes: Vec<u8>, lanes: u32 },
    /// [`ToWorker::Sift`] without the gray image in the reply (its `Done` has
    /// an empty `gray`): what an odometry run asks for each frame, so the
    /// page's cache holds 0.23 MB per KITTI frame instead of 0.7 MB.
    Features { id: u32, bytes: Vec<u8>, lanes: u32 },
    /// Starts an odometry run of `total` frames fed one [`ToWorker::VoFrame`] at a time.
    VoStart { id: u32, total: u32, poses: String },
    /// The run's next frame, with its keypoints if the page's SIFT workers
    /// computed them (`None`: the tracker detects itself where the loop
    /// re-detects; frame 1 never does).
    VoFrame { id: u32, frame: u32, bytes: Vec<u8>, points: Option<Vec<[f32; 2]>> },
    /// Starts a run of the loop driven by the student's matcher
    /// (`vo::matched`) instead of LK; its frames come as `VoFeatures` (or as
    /// `VoFrame`s, on which the worker runs SIFT itself).
    VoMatchedStart { id: u32, total: u32, poses: String, algo: String, threshold: Option<f64> },
    /// A matcher-driven run's next frame as its SIFT features, computed once
    /// by the page's SIFT workers and shared by every tracker of the page.
    VoFeatures { id: u32, frame: u32, features: Features },
    /// SIFT's anatomy or the whole-frame sweep (`msg_inside`).
    Inside(crate::msg_inside::InsideRequest),
}

/// What SIFT produced for one frame, plus the gray image it ran on.
#[derive(Debug, Clone, PartialEq)]
pub struct SiftResult {
    pub width: usize,
    pub height: usize,
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

/// Worker → page.
#[derive(Debug, Clone, PartialEq)]
pub enum FromWorker {
    /// The worker's wasm is initialised and it listens.
    Ready,
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
    /// One odometry step done: the estimated and true camera positions.
    VoStep {
        id: u32,
        frame: u32,
        total: u32,
        position: [f64; 3],
        truth: Option<[f64; 3]>,
        tracked: u32,
        redetected: bool,
    },
    /// The run is over: trajectory error (RMSE, GT scale, no alignment) and
    /// the lab's trajectory window as PNG (the core's renderer, as the CLI writes it).
    VoDone {
        id: u32,
        ate: f64,
        png: Vec<u8>,
        ms: f64,
        /// The estimated poses in KITTI's format, as `--save-poses` writes them.
        kitti: String,
    },
    /// Sent just before `VoDone`: the run's metrics
    /// (`TrajectoryMetrics::to_array`, KITTI figures NaN when undefined).
    VoMetrics {
        id: u32,
        metrics: [f64; 7],
    },
    /// The outcome of a [`ToWorker::Inside`] request.
    Inside(crate::msg_inside::InsideReply),
}

impl ToWorker {
    pub fn to_js(&self) -> JsValue {
        let o = Object::new();
        match self {
            ToWorker::Sift { id, bytes, lanes } => set_image_job(&o, "sift", *id, bytes, *lanes),
            ToWorker::Features { id, bytes, lanes } => set_image_job(&o, "features", *id, bytes, *lanes),
            ToWorker::VoFeatures { id, frame, features } => {
                set(&o, "type", &"voFeatures".into());
                set(&o, "id", &(*id).into());
                set(&o, "frame", &(*frame).into());
                set_features(&o, features);
            }
            ToWorker::VoStart { id, total, poses } => {
                set(&o, "type", &"voStart".into());
                set(&o, "id", &(*id).into());
                set(&o, "total", &(*total).into());
                set(&o, "poses", &poses.as_str().into());
            }
            ToWorker::VoFrame { id, frame, bytes, points } => {
                set(&o, "type", &"voFrame".into());
                set(&o, "id", &(*id).into());
                set(&o, "frame", &(*frame).into());
                set(&o, "bytes", &Uint8Array::from(bytes.as_slice()).into());
                set(&o, "points", &points.as_deref().map(points_js).unwrap_or(JsValue::NULL));
            }
            ToWorker::VoMatchedStart { id, total, poses, algo, threshold } => {
                set(&o, "type", &"voMatchedStart".into());
                set(&o, "id", &(*id).into());
                set(&o, "total", &(*total).into());
                set(&o, "poses", &poses.as_str().into());
                set(&o, "algo", &algo.as_str().into());
                set(&o, "threshold", &threshold.map_or(JsValue::NULL, JsValue::from));
            }
            ToWorker::Inside(r) => return r.to_js(),
        }
        o.into()
    }

    pub fn from_js(v: &JsValue) -> Result<Self, String> {
        if let Some(r) = crate::msg_inside::InsideRequest::from_js(v) {
            return r.map(ToWorker::Inside);
        }
        match kind(v)?.as_str() {
            "sift" => {
                Ok(ToWorker::Sift { id: get_u32(v, "id")?, bytes: get_bytes(v, "bytes")?, lanes: get_u32(v, "lanes")? })
            }
            "features" => Ok(ToWorker::Features {
                id: get_u32(v, "id")?,
                bytes: get_bytes(v, "bytes")?,
                lanes: get_u32(v, "lanes")?,
            }),
            "voFeatures" => Ok(ToWorker::VoFeatures {
                id: get_u32(v, "id")?,
                frame: get_u32(v, "frame")?,
                features: get_features(v)?,
            }),
            "voStart" => Ok(ToWorker::VoStart {
                id: get_u32(v, "id")?,
                total: get_u32(v, "total")?,
                poses: get_str(v, "poses")?,
            }),
            "voFrame" => Ok(ToWorker::VoFrame {
                id: get_u32(v, "id")?,
                frame: get_u32(v, "frame")?,
                bytes: get_bytes(v, "bytes")?,
                points: get_points(v, "points")?,
            }),
            "voMatchedStart" => Ok(ToWorker::VoMatchedStart {
                id: get_u32(v, "id")?,
                total: get_u32(v, "total")?,
                poses: get_str(v, "poses")?,
                algo: get_str(v, "algo")?,
                threshold: get(v, "threshold")?.as_f64(),
            }),
            other => Err(format!("unknown message type {other:?}")),
        }
    }
}

/// Keypoint floats per keypoint in the `kp` array: x, y, size, angle, response.
pub const KP_FLOATS: usize = 5;

impl FromWorker {
    pub fn to_js(&self) -> JsValue {
        let o = Object::new();
        match self {
            FromWorker::Ready => set(&o, "type", &"ready".into()),
            FromWorker::Inside(r) => return r.to_js(),
            FromWorker::Progress { id, stage } => {
                set(&o, "type", &"progress".into());
                set(&o, "id", &(*id).into());
                set(&o, "stage", &stage.as_str().into());
            }
            FromWorker::Failed { id, message } => {
                set(&o, "type", &"failed".into());
                set(&o, "id", &(*id).into());
                set(&o, "message", &message.as_str().into());
            }
            FromWorker::VoStep { id, frame, total, position, truth, tracked, redetected } => {
                set(&o, "type", &"voStep".into());
                set(&o, "id", &(*id).into());
                set(&o, "frame", &(*frame).into());
                set(&o, "total", &(*total).into());
                set(&o, "position", &vec3(position));
                set(&o, "truth", &truth.as_ref().map(vec3).unwrap_or(JsValue::NULL));
                set(&o, "tracked", &(*tracked).into());
                set(&o, "redetected", &(*redetected).into());
            }
            FromWorker::VoDone { id, ate, png, ms, kitti } => {
                set(&o, "type", &"voDone".into());
                set(&o, "kitti", &kitti.as_str().into());
                set(&o, "id", &(*id).into());
                set(&o, "ate", &(*ate).into());
                set(&o, "png", &Uint8Array::from(png.as_slice()).into());
                set(&o, "ms", &(*ms).into());
            }
            FromWorker::VoMetrics { id, metrics } => {
                set(&o, "type", &"voMetrics".into());
                set(&o, "id", &(*id).into());
                set(&o, "metrics", &js_sys::Float64Array::from(metrics.as_slice()).into());
            }
            FromWorker::Done { id, result } => {
                set(&o, "type", &"done".into());
                set(&o, "id", &(*id).into());
                set(&o, "width", &(result.width as u32).into());
                set(&o, "height", &(result.height as u32).into());
                set(&o, "gray", &Uint8Array::from(result.gray.as_slice()).into());
                set_features(&o, &result.features);
                set(&o, "decodeMs", &result.decode_ms.into());
                set(&o, "siftMs", &result.sift_ms.into());
                set(&o, "engine", &result.engine.as_str().into());
                set(&o, "memory", &result.memory.into());
            }
        }
        o.into()
    }

    pub fn from_js(v: &JsValue) -> Result<Self, String> {
        if let Some(r) = crate::msg_inside::InsideReply::from_js(v) {
            return r.map(FromWorker::Inside);
        }
        match kind(v)?.as_str() {
            "ready" => Ok(FromWorker::Ready),
            "progress" => Ok(FromWorker::Progress { id: get_u32(v, "id")?, stage: get_str(v, "stage")? }),
            "failed" => Ok(FromWorker::Failed { id: get_u32(v, "id")?, message: get_str(v, "message")? }),
            "voStep" => Ok(FromWorker::VoStep {
                id: get_u32(v, "id")?,
                frame: get_u32(v, "frame")?,
                total: get_u32(v, "total")?,
                position: get_vec3(v, "position")?.ok_or("voStep without a position")?,
                truth: get_vec3(v, "truth")?,
                tracked: get_u32(v, "tracked")?,
                redetected: get(v, "redetected")?.as_bool().unwrap_or(false),
            }),
            "voDone" => Ok(FromWorker::VoDone {
                id: get_u32(v, "id")?,
                ate: get_f64(v, "ate")?,
                png: get_bytes(v, "png")?,
                ms: get_f64(v, "ms")?,
                kitti: get_str(v, "kitti")?,
            }),
            "voMetrics" => {
                let a = get(v, "metrics")?
                    .dyn_into::<js_sys::Float64Array>()
                    .map_err(|_| "message field metrics is not a Float64Array".to_string())?
                    .to_vec();
                let metrics: [f64; 7] =
                    a.try_into().map_err(|a: Vec<f64>| format!("voMetrics has {} numbers, not 7", a.len()))?;
                Ok(FromWorker::VoMetrics { id: get_u32(v, "id")?, metrics })
            }
            "done" => {
                let parts = SiftParts {
                    width: get_u32(v, "width")?,
                    height: get_u32(v, "height")?,
                    gray: get_bytes(v, "gray")?,
                    ..get_feature_parts(v)?
                };
                Ok(FromWorker::Done {
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
            other => Err(format!("unknown message type {other:?}")),
        }
    }
}

/// Writes `f` as the flat `kp`, `octave` and `desc` arrays of a message.
fn set_features(o: &Object, f: &Features) {
    let mut flat = Vec::with_capacity(f.keypoints.len() * KP_FLOATS);
    let mut oct = Vec::with_capacity(f.keypoints.len());
    for k in &f.keypoints {
        flat.extend_from_slice(&[k.x, k.y, k.size, k.angle, k.response]);
        oct.push(k.octave);
    }
    set(o, "kp", &Float32Array::from(flat.as_slice()).into());
    set(o, "octave", &Int32Array::from(oct.as_slice()).into());
    let desc: Vec<u8> = f.descriptors.iter().flatten().copied().collect();
    set(o, "desc", &Uint8Array::from(desc.as_slice()).into());
}

/// The flat `kp`, `octave` and `desc` arrays of a message (no image).
fn get_feature_parts(v: &JsValue) -> Result<SiftParts, String> {
    let kp = get(v, "kp")?
        .dyn_into::<Float32Array>()
        .map_err(|_| "message field kp is not a Float32Array".to_string())?
        .to_vec();
    let octave = get(v, "octave")?
        .dyn_into::<Int32Array>()
        .map_err(|_| "message field octave is not an Int32Array".to_string())?
        .to_vec();
    Ok(SiftParts { kp, octave, desc: get_bytes(v, "desc")?, ..SiftParts::default() })
}

/// A message's features, with [`SiftParts::check`]'s size checks.
fn get_features(v: &JsValue) -> Result<Features, String> {
    Ok(get_feature_parts(v)?.check()?.features)
}

/// The bulk of a `done` message as it arrives: the gray image and the
/// keypoints and descriptors as flat arrays.
#[derive(Debug, Clone, Default)]
pub struct SiftParts {
    pub width: u32,
    pub height: u32,
    pub gray: Vec<u8>,
    /// [`KP_FLOATS`] floats per keypoint.
    pub kp: Vec<f32>,
    pub octave: Vec<i32>,
    /// 128 bytes per keypoint.
    pub desc: Vec<u8>,
}

impl SiftParts {
    /// Checks the sizes agree and builds the result (timings and engine
    /// empty). An empty `gray` is a reply without the image
    /// ([`ToWorker::Features`]), whatever the size. Sizes are compared in u64: in usize, 65536 × 65536 wraps to 0
    /// on wasm32 and an empty buffer would pass as a 4-gigapixel image.
    pub fn check(self) -> Result<SiftResult, String> {
        let SiftParts { width, height, gray, kp, octave, desc } = self;
        if !gray.is_empty() && gray.len() as u64 != width as u64 * height as u64 {
            return Err(format!("gray buffer has {} bytes for {width}x{height}", gray.len()));
        }
        let n = octave.len() as u64;
        if kp.len() as u64 != n * KP_FLOATS as u64 || desc.len() as u64 != n * 128 {
            return Err(format!(
                "inconsistent SIFT message: {n} octaves, {} floats, {} descriptor bytes",
                kp.len(),
                desc.len()
            ));
        }
        let keypoints = kp
            .chunks_exact(KP_FLOATS)
            .zip(&octave)
            .map(|(f, &octave)| KeyPoint { x: f[0], y: f[1], size: f[2], angle: f[3], response: f[4], octave })
            .collect();
        let descriptors = desc
            .chunks_exact(128)
            .map(|c| {
                let mut d = [0u8; 128];
                d.copy_from_slice(c);
                d
            })
            .collect();
        Ok(SiftResult {
            width: width as usize,
            height: height as usize,
            gray,
            features: Features { keypoints, descriptors },
            decode_ms: 0.0,
            sift_ms: 0.0,
            engine: String::new(),
            memory: 0,
        })
    }
}
