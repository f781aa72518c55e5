//! An odometry tracker's messages: the run's start, then one frame at a time
//! (the image, its keypoints, or a matcher-driven run's features); one step
//! back per frame, then the metrics and the end of the run.

use super::codec::*;
use js_sys::{Object, Uint8Array};
use siftlab_core::matching::Strategy;
use siftlab_core::sift::Features;
use siftlab_core::vo::{Camera, StepDetail};
use wasm_bindgen::{JsCast, JsValue};

/// What drives an odometry run: the lab's Lucas–Kanade loop, or the loop
/// driven by the student's matcher (`vo::matched`) with a validated strategy.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Tracker {
    Lk,
    Matched(Strategy),
}

impl Tracker {
    /// The strategy of a matched run (`None`: LK), as the core's figures take it.
    pub fn strategy(&self) -> Option<&Strategy> {
        match self {
            Tracker::Lk => None,
            Tracker::Matched(s) => Some(s),
        }
    }

    /// The menu's and the message's name: `lk`, `dt`, `nn` or `nndr`.
    pub fn name(&self) -> &'static str {
        self.strategy().map_or("lk", Strategy::name)
    }
}

/// The tracker in a message: its name and the strategy's threshold (a number
/// or null). Decoding builds the variant directly: the page sends only
/// strategies the core has already validated.
fn set_tracker(o: &Object, t: &Tracker) {
    set(o, "tracker", &t.name().into());
    set(o, "threshold", &t.strategy().and_then(Strategy::threshold).map_or(JsValue::NULL, JsValue::from));
}

fn get_tracker(v: &JsValue) -> Result<Tracker, String> {
    let t = get(v, "threshold")?.as_f64();
    let name = get_str(v, "tracker")?;
    Ok(match (name.as_str(), t) {
        ("lk", _) => Tracker::Lk,
        ("dt", Some(t)) => Tracker::Matched(Strategy::Dt(t)),
        ("nn", t) => Tracker::Matched(Strategy::Nn(t)),
        ("nndr", Some(t)) => Tracker::Matched(Strategy::Nndr(t)),
        _ => return Err(format!("voStart: tracker {name:?} with threshold {t:?} is not a tracker")),
    })
}

/// Page → tracking worker.
#[derive(Debug, Clone, PartialEq)]
pub enum VoRequest {
    /// Starts a run over `total` frames: LK fed one [`VoRequest::Frame`] at a
    /// time, or the matched loop fed [`VoRequest::Features`] (or `Frame`s, on
    /// which the worker runs SIFT itself).
    Start { id: u32, total: u32, poses: String, camera: Camera, tracker: Tracker },
    /// The run's next frame, with its keypoints if the page's SIFT workers
    /// computed them (`None`: the tracker detects itself where the loop
    /// re-detects; frame 1 never does).
    Frame { id: u32, frame: u32, bytes: Vec<u8>, points: Option<Vec<[f32; 2]>> },
    /// A matcher-driven run's next frame as its SIFT features, computed once
    /// by the page's SIFT workers and shared by every tracker of the page.
    Features { id: u32, frame: u32, features: Features },
    /// Recompute what the run did with frame `frame` (its points and masks,
    /// not kept for old frames of a long run) from frame `from`: for LK the
    /// last frame the loop detected on, with `frames` the files `from` …
    /// `frame`, `refs` the points detected on `from` and `detected` those on
    /// `frame` if the loop re-detected there; for a matched run
    /// `from = frame − 1` and `features` the two frames' features. The run's
    /// own state is untouched; `token` names the answer.
    Replay {
        token: u32,
        from: u32,
        frame: u32,
        frames: Vec<Vec<u8>>,
        refs: Vec<[f32; 2]>,
        detected: Option<Vec<[f32; 2]>>,
        features: Vec<Features>,
    },
}

/// Tracking worker → page.
#[derive(Debug, Clone, PartialEq)]
pub enum VoReply {
    /// One frame done: the estimated and true camera positions, the loop's
    /// counts, and the points it used (for the odometry's own view).
    Step {
        id: u32,
        frame: u32,
        total: u32,
        position: [f64; 3],
        truth: Option<[f64; 3]>,
        counts: StepCounts,
        detail: Option<Box<StepDetail>>,
    },
    /// Sent just before `Done`: the run's metrics (`TrajectoryMetrics::to_array`,
    /// KITTI figures NaN when undefined).
    Metrics { id: u32, metrics: [f64; 7] },
    /// The run is over: trajectory error (RMSE, GT scale, no alignment), the
    /// lab's trajectory window as PNG (the core's renderer, as the CLI writes
    /// it), and the estimated poses in KITTI's format (as `--save-poses` writes them).
    Done { id: u32, ate: f64, png: Vec<u8>, ms: f64, kitti: String },
    /// A user-facing message; the run is over.
    Failed { id: u32, message: String },
    /// The answer to [`VoRequest::Replay`] `token`: the frame's points (`None`
    /// where the run recorded none, e.g. fewer than 5 matches), or why not.
    Replayed { token: u32, frame: u32, detail: Result<Option<Box<StepDetail>>, String> },
}

/// What one frame of the loop counted (`vo::StepResult`'s fields, as
/// `view_trajectory --trace` writes them).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StepCounts {
    pub points_in: u32,
    pub tracked: u32,
    pub essential_inliers: u32,
    pub pose_inliers: u32,
    pub redetected: bool,
    /// The points carried to the next frame (SIFT's count where it re-detected).
    pub points_out: u32,
}

impl StepCounts {
    pub fn of(s: &siftlab_core::vo::StepResult) -> StepCounts {
        StepCounts {
            points_in: s.points_in as u32,
            tracked: s.tracked as u32,
            essential_inliers: s.essential_inliers as u32,
            pose_inliers: s.pose_inliers as u32,
            redetected: s.redetected,
            points_out: s.points_out as u32,
        }
    }
}

/// The detail's masks in one byte per point: bit 0 RANSAC's, bit 1 recoverPose's.
fn set_detail(o: &Object, d: &StepDetail) {
    set(o, "dPrev", &points_js(&d.prev));
    set(o, "dCur", &points_js(&d.cur));
    let masks: Vec<u8> =
        d.essential_mask.iter().zip(&d.pose_mask).map(|(&e, &p)| u8::from(e) | (u8::from(p) << 1)).collect();
    set(o, "dMask", &Uint8Array::from(masks.as_slice()).into());
    set(o, "dDetected", &points_js(&d.detected));
}

fn get_detail(v: &JsValue) -> Result<Option<Box<StepDetail>>, String> {
    let Some(prev) = get_points(v, "dPrev")? else { return Ok(None) };
    let cur = get_points(v, "dCur")?.unwrap_or_default();
    let masks = get_bytes(v, "dMask")?;
    if cur.len() != prev.len() || masks.len() != prev.len() {
        return Err(format!("voStep detail: {} / {} / {} points", prev.len(), cur.len(), masks.len()));
    }
    Ok(Some(Box::new(StepDetail {
        prev,
        cur,
        essential_mask: masks.iter().map(|m| m & 1 != 0).collect(),
        pose_mask: masks.iter().map(|m| m & 2 != 0).collect(),
        detected: get_points(v, "dDetected")?.unwrap_or_default(),
    })))
}

impl VoRequest {
    pub fn to_js(&self) -> JsValue {
        let o = Object::new();
        match self {
            VoRequest::Start { id, total, poses, camera, tracker } => {
                set(&o, "type", &"voStart".into());
                set(&o, "id", &(*id).into());
                set(&o, "total", &(*total).into());
                set(&o, "poses", &poses.as_str().into());
                set_camera(&o, "camera", camera);
                set_tracker(&o, tracker);
            }
            VoRequest::Frame { id, frame, bytes, points } => {
                set(&o, "type", &"voFrame".into());
                set(&o, "id", &(*id).into());
                set(&o, "frame", &(*frame).into());
                set(&o, "bytes", &Uint8Array::from(bytes.as_slice()).into());
                set(&o, "points", &points.as_deref().map(points_js).unwrap_or(JsValue::NULL));
            }
            VoRequest::Features { id, frame, features } => {
                set(&o, "type", &"voFeatures".into());
                set(&o, "id", &(*id).into());
                set(&o, "frame", &(*frame).into());
                set_features(&o, "", features);
            }
            VoRequest::Replay { token, from, frame, frames, refs, detected, features } => {
                set(&o, "type", &"voReplay".into());
                set(&o, "id", &(*token).into());
                set(&o, "from", &(*from).into());
                set(&o, "frame", &(*frame).into());
                let files = js_sys::Array::new();
                for f in frames {
                    files.push(&Uint8Array::from(f.as_slice()));
                }
                set(&o, "frames", &files.into());
                set(&o, "refs", &points_js(refs));
                set(&o, "detected", &detected.as_deref().map(points_js).unwrap_or(JsValue::NULL));
                set(&o, "nFeatures", &(features.len() as u32).into());
                for (k, f) in features.iter().enumerate() {
                    set_features(&o, &format!("f{k}"), f);
                }
            }
        }
        o.into()
    }

    /// `None` when `v` is not an odometry request.
    pub fn from_js(v: &JsValue) -> Option<Result<Self, String>> {
        let parse = |k: &str| -> Result<Self, String> {
            let id = get_u32(v, "id")?;
            Ok(match k {
                "voStart" => VoRequest::Start {
                    id,
                    total: get_u32(v, "total")?,
                    poses: get_str(v, "poses")?,
                    camera: get_camera(v, "camera")?,
                    tracker: get_tracker(v)?,
                },
                "voFrame" => VoRequest::Frame {
                    id,
                    frame: get_u32(v, "frame")?,
                    bytes: get_bytes(v, "bytes")?,
                    points: get_points(v, "points")?,
                },
                "voReplay" => {
                    let files = get(v, "frames")?
                        .dyn_into::<js_sys::Array>()
                        .map_err(|_| "voReplay: frames is not an array".to_string())?;
                    let frames = files
                        .iter()
                        .map(|f| f.dyn_into::<Uint8Array>().map(|a| a.to_vec()))
                        .collect::<Result<Vec<_>, _>>()
                        .map_err(|_| "voReplay: a frame is not bytes".to_string())?;
                    let features = (0..get_u32(v, "nFeatures")?.min(2))
                        .map(|k| get_features(v, &format!("f{k}")))
                        .collect::<Result<Vec<_>, _>>()?;
                    VoRequest::Replay {
                        token: id,
                        from: get_u32(v, "from")?,
                        frame: get_u32(v, "frame")?,
                        frames,
                        refs: get_points(v, "refs")?.unwrap_or_default(),
                        detected: get_points(v, "detected")?,
                        features,
                    }
                }
                _ => VoRequest::Features { id, frame: get_u32(v, "frame")?, features: get_features(v, "")? },
            })
        };
        let k = kind(v).ok()?;
        matches!(k.as_str(), "voStart" | "voFrame" | "voFeatures" | "voReplay").then(|| parse(&k))
    }
}

impl VoReply {
    pub fn to_js(&self) -> JsValue {
        let o = Object::new();
        match self {
            VoReply::Step { id, frame, total, position, truth, counts, detail } => {
                set(&o, "type", &"voStep".into());
                set(&o, "id", &(*id).into());
                set(&o, "frame", &(*frame).into());
                set(&o, "total", &(*total).into());
                set(&o, "position", &vec3(position));
                set(&o, "truth", &truth.as_ref().map(vec3).unwrap_or(JsValue::NULL));
                set(&o, "pointsIn", &counts.points_in.into());
                set(&o, "tracked", &counts.tracked.into());
                set(&o, "essentialInliers", &counts.essential_inliers.into());
                set(&o, "poseInliers", &counts.pose_inliers.into());
                set(&o, "redetected", &counts.redetected.into());
                set(&o, "pointsOut", &counts.points_out.into());
                if let Some(d) = detail {
                    set_detail(&o, d);
                }
            }
            VoReply::Metrics { id, metrics } => {
                set(&o, "type", &"voMetrics".into());
                set(&o, "id", &(*id).into());
                set(&o, "metrics", &js_sys::Float64Array::from(metrics.as_slice()).into());
            }
            VoReply::Done { id, ate, png, ms, kitti } => {
                set(&o, "type", &"voDone".into());
                set(&o, "id", &(*id).into());
                set(&o, "ate", &(*ate).into());
                set(&o, "png", &Uint8Array::from(png.as_slice()).into());
                set(&o, "ms", &(*ms).into());
                set(&o, "kitti", &kitti.as_str().into());
            }
            VoReply::Failed { id, message } => {
                set_failed(&o, *id, message);
            }
            VoReply::Replayed { token, frame, detail } => {
                set(&o, "type", &"voReplayed".into());
                set(&o, "id", &(*token).into());
                set(&o, "frame", &(*frame).into());
                match detail {
                    Ok(Some(d)) => set_detail(&o, d),
                    Ok(None) => {}
                    Err(e) => set(&o, "error", &e.as_str().into()),
                }
            }
        }
        o.into()
    }

    pub fn from_js(v: &JsValue) -> Result<Self, String> {
        match kind(v)?.as_str() {
            "voStep" => Ok(VoReply::Step {
                id: get_u32(v, "id")?,
                frame: get_u32(v, "frame")?,
                total: get_u32(v, "total")?,
                position: get_vec3(v, "position")?.ok_or("voStep without a position")?,
                truth: get_vec3(v, "truth")?,
                counts: StepCounts {
                    points_in: get_u32(v, "pointsIn")?,
                    tracked: get_u32(v, "tracked")?,
                    essential_inliers: get_u32(v, "essentialInliers")?,
                    pose_inliers: get_u32(v, "poseInliers")?,
                    redetected: get(v, "redetected")?.as_bool().unwrap_or(false),
                    points_out: get_u32(v, "pointsOut")?,
                },
                detail: get_detail(v)?,
            }),
            "voMetrics" => {
                let a = get(v, "metrics")?
                    .dyn_into::<js_sys::Float64Array>()
                    .map_err(|_| "message field metrics is not a Float64Array".to_string())?
                    .to_vec();
                let metrics: [f64; 7] =
                    a.try_into().map_err(|a: Vec<f64>| format!("voMetrics has {} numbers, not 7", a.len()))?;
                Ok(VoReply::Metrics { id: get_u32(v, "id")?, metrics })
            }
            "voDone" => Ok(VoReply::Done {
                id: get_u32(v, "id")?,
                ate: get_f64(v, "ate")?,
                png: get_bytes(v, "png")?,
                ms: get_f64(v, "ms")?,
                kitti: get_str(v, "kitti")?,
            }),
            "failed" => Ok(VoReply::Failed { id: get_u32(v, "id")?, message: get_str(v, "message")? }),
            "voReplayed" => Ok(VoReply::Replayed {
                token: get_u32(v, "id")?,
                frame: get_u32(v, "frame")?,
                detail: match get(v, "error")?.as_string() {
                    Some(e) => Err(e),
                    None => Ok(get_detail(v)?),
                },
            }),
            other => Err(format!("not a tracking worker's reply: {other:?}")),
        }
    }
}
