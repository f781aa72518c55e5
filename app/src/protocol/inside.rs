//! The "see inside" messages between the page and a worker: SIFT's anatomy
//! of one frame, and the whole-frame sweep of a pair.

use super::codec::{
    get, get_camera, get_f32s, get_f64, get_features, get_str, get_typed, get_u32, kind, set, set_camera, set_failed,
    set_features, set_image_job, set_progress,
};
use js_sys::{Array, Float32Array, Float64Array, Object, Uint32Array, Uint8Array};
use siftlab_core::dataset::PoseRow;
use siftlab_core::matching::sweep::{Curve, Sweep};
use siftlab_core::matching::StrategyKind;
use siftlab_core::sift::Features;
use siftlab_core::vo::Camera;
use wasm_bindgen::{JsCast, JsValue};

/// Page → worker.
#[derive(Debug, Clone, PartialEq)]
pub enum InsideRequest {
    /// SIFT's anatomy of the image `bytes` (OpenCV SIMD width `lanes`).
    Anatomy { id: u32, bytes: Vec<u8>, lanes: u32 },
    /// The sweep of `prev` against `cur`, judged by the poses' epipolar
    /// geometry (with the sequence's `camera`) within `px` pixels when the
    /// poses are known.
    WholeFrame { id: u32, prev: Features, cur: Features, poses: Option<Box<[PoseRow; 2]>>, camera: Camera, px: f64 },
}

/// One pyramid level, subsampled for display (`step` octave pixels per
/// thumbnail pixel; the values are the level's own).
#[derive(Debug, Clone, PartialEq)]
pub struct LevelThumb {
    pub octave: u32,
    pub index: u32,
    pub dog: bool,
    pub step: u32,
    pub width: u32,
    pub height: u32,
    pub values: Vec<f32>,
}

/// What the anatomy view shows; keypoint-indexed fields follow the frame's
/// keypoints (the funnel's last stage is that list).
#[derive(Debug, Clone, PartialEq)]
pub struct AnatomyData {
    pub octaves: u32,
    pub levels_per_octave: u32,
    /// (stage, count) in pipeline order.
    pub stages: Vec<(String, u32)>,
    /// (reason, count) of the refinement's drops.
    pub drops: Vec<(String, u32)>,
    pub cutoff: Option<f32>,
    pub levels: Vec<LevelThumb>,
    /// Per stage, its points as x, y pairs in image pixels.
    pub points: Vec<Vec<f32>>,
    /// The dropped extrema (x, y pairs) and each one's reason (index into `drops`).
    pub rejected: Vec<f32>,
    pub rejected_why: Vec<u8>,
    /// Per kept keypoint: 36 raw then 36 smoothed bins (NaN if unknown).
    pub hist: Vec<f32>,
    /// Per kept keypoint: the 80 % line.
    pub hist_thr: Vec<f32>,
    /// Per kept keypoint: how many peaks were taken, then all their (bin, angle) pairs.
    pub peak_counts: Vec<u8>,
    pub peaks: Vec<f32>,
    pub ms: f64,
}

/// The sweep of a pair, and whether it was judged.
#[derive(Debug, Clone, PartialEq)]
pub struct SweepData {
    pub sweep: Sweep,
    pub judged: bool,
    pub px: f64,
    pub ms: f64,
}

/// Worker → page.
#[derive(Debug, Clone, PartialEq)]
pub enum InsideReply {
    /// The job reached a new stage (shown to the user as progress).
    Progress {
        id: u32,
        stage: String,
    },
    Anatomy {
        id: u32,
        data: Box<AnatomyData>,
    },
    WholeFrame {
        id: u32,
        data: Box<SweepData>,
    },
    /// A user-facing message.
    Failed {
        id: u32,
        message: String,
    },
}

fn named_counts(list: &[(String, u32)]) -> (JsValue, JsValue) {
    let names: Array = list.iter().map(|(n, _)| JsValue::from_str(n)).collect();
    let counts: Vec<u32> = list.iter().map(|(_, c)| *c).collect();
    (names.into(), Uint32Array::from(counts.as_slice()).into())
}

fn get_named_counts(o: &JsValue, names: &str, counts: &str) -> Result<Vec<(String, u32)>, String> {
    let n: Array = get_typed(o, names)?;
    let c = get_typed::<Uint32Array>(o, counts)?.to_vec();
    let names: Vec<String> = n.iter().filter_map(|v| v.as_string()).collect();
    if names.len() != c.len() {
        return Err(format!("{names:?} and {c:?} differ in length"));
    }
    Ok(names.into_iter().zip(c).collect())
}

impl InsideRequest {
    pub fn to_js(&self) -> JsValue {
        let o = Object::new();
        match self {
            InsideRequest::Anatomy { id, bytes, lanes } => set_image_job(&o, "anatomy", *id, bytes, *lanes),
            InsideRequest::WholeFrame { id, prev, cur, poses, camera, px } => {
                set(&o, "type", &"wholeFrame".into());
                set_camera(&o, "camera", camera);
                set(&o, "id", &(*id).into());
                set(&o, "px", &(*px).into());
                set_features(&o, "prev", prev);
                set_features(&o, "cur", cur);
                let p = poses.as_ref().map(|ab| Float64Array::from(ab.concat().as_slice()).into());
                set(&o, "poses", &p.unwrap_or(JsValue::NULL));
            }
        }
        o.into()
    }

    /// `None` when `v` is not a "see inside" request.
    pub fn from_js(v: &JsValue) -> Option<Result<Self, String>> {
        let id = || get_u32(v, "id");
        match get(v, "type").ok()?.as_string()?.as_str() {
            "anatomy" => Some((|| {
                Ok(InsideRequest::Anatomy {
                    id: id()?,
                    bytes: get_typed::<Uint8Array>(v, "bytes")?.to_vec(),
                    lanes: get_u32(v, "lanes")?,
                })
            })()),
            "wholeFrame" => Some((|| {
                let p = get(v, "poses")?;
                let poses = if p.is_null() || p.is_undefined() {
                    None
                } else {
                    let a = p.dyn_into::<Float64Array>().map_err(|_| "poses is not a Float64Array")?.to_vec();
                    let row = |i: usize| -> Result<PoseRow, String> {
                        a.get(12 * i..12 * i + 12)
                            .and_then(|s| s.try_into().ok())
                            .ok_or_else(|| "poses needs 24 numbers".to_string())
                    };
                    Some(Box::new([row(0)?, row(1)?]))
                };
                Ok(InsideRequest::WholeFrame {
                    id: id()?,
                    prev: get_features(v, "prev")?,
                    cur: get_features(v, "cur")?,
                    poses,
                    camera: get_camera(v, "camera")?,
                    px: get_f64(v, "px")?,
                })
            })()),
            _ => None,
        }
    }
}

fn level_js(l: &LevelThumb) -> JsValue {
    let o = Object::new();
    for (k, v) in [("octave", l.octave), ("index", l.index), ("step", l.step), ("width", l.width), ("height", l.height)]
    {
        set(&o, k, &v.into());
    }
    set(&o, "dog", &l.dog.into());
    set(&o, "values", &Float32Array::from(l.values.as_slice()).into());
    o.into()
}

fn get_level(v: &JsValue) -> Result<LevelThumb, String> {
    let n = |k: &str| get_u32(v, k);
    let l = LevelThumb {
        octave: n("octave")?,
        index: n("index")?,
        dog: get(v, "dog")?.as_bool().unwrap_or(false),
        step: n("step")?,
        width: n("width")?,
        height: n("height")?,
        values: get_f32s(v, "values")?,
    };
    if l.values.len() != (l.width * l.height) as usize {
        return Err("a pyramid level's size does not match its values".into());
    }
    Ok(l)
}

const KINDS: [(&str, StrategyKind); 3] =
    [("dt", StrategyKind::Dt), ("nn", StrategyKind::Nn), ("nndr", StrategyKind::Nndr)];

impl InsideReply {
    pub fn to_js(&self) -> JsValue {
        let o = Object::new();
        match self {
            InsideReply::Progress { id, stage } => {
                set_progress(&o, *id, stage);
            }
            InsideReply::Failed { id, message } => {
                set_failed(&o, *id, message);
            }
            InsideReply::Anatomy { id, data: d } => {
                set(&o, "type", &"anatomyDone".into());
                set(&o, "id", &(*id).into());
                set(&o, "octaves", &d.octaves.into());
                set(&o, "levelsPerOctave", &d.levels_per_octave.into());
                let (n, c) = named_counts(&d.stages);
                set(&o, "stageNames", &n);
                set(&o, "stageCounts", &c);
                let (n, c) = named_counts(&d.drops);
                set(&o, "dropNames", &n);
                set(&o, "dropCounts", &c);
                set(&o, "cutoff", &d.cutoff.map(|c| JsValue::from_f64(c as f64)).unwrap_or(JsValue::NULL));
                let levels: Array = d.levels.iter().map(level_js).collect();
                set(&o, "levels", &levels.into());
                let points: Array = d.points.iter().map(|p| JsValue::from(Float32Array::from(p.as_slice()))).collect();
                set(&o, "points", &points.into());
                set(&o, "rejected", &Float32Array::from(d.rejected.as_slice()).into());
                set(&o, "rejectedWhy", &Uint8Array::from(d.rejected_why.as_slice()).into());
                set(&o, "hist", &Float32Array::from(d.hist.as_slice()).into());
                set(&o, "histThr", &Float32Array::from(d.hist_thr.as_slice()).into());
                set(&o, "peakCounts", &Uint8Array::from(d.peak_counts.as_slice()).into());
                set(&o, "peaks", &Float32Array::from(d.peaks.as_slice()).into());
                set(&o, "ms", &d.ms.into());
            }
            InsideReply::WholeFrame { id, data } => {
                set(&o, "type", &"wholeFrameDone".into());
                set(&o, "id", &(*id).into());
                set(&o, "judged", &data.judged.into());
                set(&o, "px", &data.px.into());
                set(&o, "ms", &data.ms.into());
                for (name, kind) in KINDS {
                    let (keys, pairs, ok, max) = data.sweep.curve(kind).parts();
                    let flat: Vec<u32> = pairs.iter().flatten().copied().collect();
                    set(&o, &format!("{name}Keys"), &Float64Array::from(keys).into());
                    set(&o, &format!("{name}Pairs"), &Uint32Array::from(flat.as_slice()).into());
                    let ok: Option<Vec<u8>> = ok.map(|o| o.iter().map(|&b| b as u8).collect());
                    let ok = ok.map(|o| Uint8Array::from(o.as_slice()).into()).unwrap_or(JsValue::NULL);
                    set(&o, &format!("{name}Ok"), &ok);
                    set(&o, &format!("{name}Max"), &max.into());
                }
            }
        }
        o.into()
    }

    pub fn from_js(v: &JsValue) -> Result<Self, String> {
        let id = || get_u32(v, "id");
        match kind(v)?.as_str() {
            "progress" => Ok(InsideReply::Progress { id: id()?, stage: get_str(v, "stage")? }),
            "failed" => Ok(InsideReply::Failed { id: id()?, message: get_str(v, "message")? }),
            "anatomyDone" => (|| {
                let levels: Array = get_typed(v, "levels")?;
                let points: Array = get_typed(v, "points")?;
                let cutoff = get(v, "cutoff")?.as_f64().map(|c| c as f32);
                let data = AnatomyData {
                    octaves: get_u32(v, "octaves")?,
                    levels_per_octave: get_u32(v, "levelsPerOctave")?,
                    stages: get_named_counts(v, "stageNames", "stageCounts")?,
                    drops: get_named_counts(v, "dropNames", "dropCounts")?,
                    cutoff,
                    levels: levels.iter().map(|l| get_level(&l)).collect::<Result<_, _>>()?,
                    points: points
                        .iter()
                        .map(|p| p.dyn_into::<Float32Array>().map(|a| a.to_vec()))
                        .collect::<Result<_, _>>()
                        .map_err(|_| "points are not Float32Arrays")?,
                    rejected: get_f32s(v, "rejected")?,
                    rejected_why: get_typed::<Uint8Array>(v, "rejectedWhy")?.to_vec(),
                    hist: get_f32s(v, "hist")?,
                    hist_thr: get_f32s(v, "histThr")?,
                    peak_counts: get_typed::<Uint8Array>(v, "peakCounts")?.to_vec(),
                    peaks: get_f32s(v, "peaks")?,
                    ms: get_f64(v, "ms")?,
                };
                Ok(InsideReply::Anatomy { id: id()?, data: Box::new(data) })
            })(),
            "wholeFrameDone" => (|| {
                let curve = |name: &str, kind| -> Result<Curve, String> {
                    let keys = get_typed::<Float64Array>(v, &format!("{name}Keys"))?.to_vec();
                    let flat = get_typed::<Uint32Array>(v, &format!("{name}Pairs"))?.to_vec();
                    let pairs = flat.chunks_exact(2).map(|c| [c[0], c[1]]).collect();
                    let ok = get(v, &format!("{name}Ok"))?;
                    let ok = ok.dyn_into::<Uint8Array>().ok().map(|a| a.to_vec().into_iter().map(|b| b != 0).collect());
                    Curve::from_parts(kind, keys, pairs, ok, get_f64(v, &format!("{name}Max"))?)
                        .map_err(|e| e.to_string())
                };
                let sweep = Sweep {
                    dt: curve("dt", StrategyKind::Dt)?,
                    nn: curve("nn", StrategyKind::Nn)?,
                    nndr: curve("nndr", StrategyKind::Nndr)?,
                };
                let data = SweepData {
                    sweep,
                    judged: get(v, "judged")?.as_bool().unwrap_or(false),
                    px: get_f64(v, "px")?,
                    ms: get_f64(v, "ms")?,
                };
                Ok(InsideReply::WholeFrame { id: id()?, data: Box::new(data) })
            })(),
            other => Err(format!("not a see-inside reply: {other:?}")),
        }
    }
}
