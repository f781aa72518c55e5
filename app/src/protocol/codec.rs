//! The one codec of the worker messages: every field of every message is read
//! and written through these helpers, with its checks.

use js_sys::{Float32Array, Int32Array, Object, Reflect, Uint8Array};
use siftlab_core::sift::{Features, KeyPoint};
use wasm_bindgen::{JsCast, JsValue};

pub(crate) fn set(o: &Object, k: &str, v: &JsValue) {
    // Setting a property on a fresh plain object cannot fail.
    let _ = Reflect::set(o, &JsValue::from_str(k), v);
}

pub(crate) fn get(o: &JsValue, k: &str) -> Result<JsValue, String> {
    Reflect::get(o, &JsValue::from_str(k)).map_err(|_| format!("message has no field {k}"))
}

pub(crate) fn get_u32(o: &JsValue, k: &str) -> Result<u32, String> {
    u32_field(k, get(o, k)?.as_f64())
}

// The checks below take plain Rust values, not `JsValue`s, so they build and
// run natively: `tests/fuzz/fuzz_targets/app_state.rs` and the host tests call them
// (wasm-bindgen's imports panic off wasm32).

/// A JS number as a u32 message field: a whole number in 0..=u32::MAX. An
/// `as u32` cast would turn NaN, -1 or 1e20 silently into 0 or u32::MAX,
/// i.e. another id or frame than the one sent.
pub fn u32_field(k: &str, v: Option<f64>) -> Result<u32, String> {
    let v = v.ok_or_else(|| format!("message field {k} is not a number"))?;
    if v.fract() == 0.0 && (0.0..=u32::MAX as f64).contains(&v) {
        Ok(v as u32)
    } else {
        Err(format!("message field {k} is {v}, not a whole number in 0..={}", u32::MAX))
    }
}

/// Flat x, y coordinates as points.
pub fn points_field(k: &str, flat: &[f32]) -> Result<Vec<[f32; 2]>, String> {
    if !flat.len().is_multiple_of(2) {
        return Err(format!("message field {k} has an odd number of coordinates"));
    }
    Ok(flat.chunks_exact(2).map(|c| [c[0], c[1]]).collect())
}

/// Exactly three numbers as a 3-vector.
pub fn vec3_field(k: &str, a: &[f64]) -> Result<[f64; 3], String> {
    <[f64; 3]>::try_from(a).map_err(|_| format!("message field {k} needs 3 numbers"))
}

pub(crate) fn get_f64(o: &JsValue, k: &str) -> Result<f64, String> {
    get(o, k)?.as_f64().ok_or_else(|| format!("message field {k} is not a number"))
}

pub(crate) fn get_str(o: &JsValue, k: &str) -> Result<String, String> {
    get(o, k)?.as_string().ok_or_else(|| format!("message field {k} is not a string"))
}

pub(crate) fn get_bytes(o: &JsValue, k: &str) -> Result<Vec<u8>, String> {
    get(o, k)?
        .dyn_into::<Uint8Array>()
        .map(|a| a.to_vec())
        .map_err(|_| format!("message field {k} is not a Uint8Array"))
}

pub(crate) fn get_vec3(o: &JsValue, k: &str) -> Result<Option<[f64; 3]>, String> {
    let v = get(o, k)?;
    if v.is_null() || v.is_undefined() {
        return Ok(None);
    }
    let a =
        v.dyn_into::<js_sys::Float64Array>().map_err(|_| format!("message field {k} is not a Float64Array"))?.to_vec();
    vec3_field(k, &a).map(Some)
}

/// A camera's intrinsics as a message field: fx, fy, cx, cy, checked as
/// the odometry checks them.
pub fn camera_field(k: &str, a: &[f64]) -> Result<siftlab_core::vo::Camera, String> {
    let [fx, fy, cx, cy] = <[f64; 4]>::try_from(a).map_err(|_| format!("message field {k} needs 4 numbers"))?;
    let cam = siftlab_core::vo::Camera { fx, fy, cx, cy };
    cam.validate().map_err(|e| format!("message field {k}: {e}"))?;
    Ok(cam)
}

pub(crate) fn set_camera(o: &Object, k: &str, c: &siftlab_core::vo::Camera) {
    set(o, k, &js_sys::Float64Array::from([c.fx, c.fy, c.cx, c.cy].as_slice()).into());
}

pub(crate) fn get_camera(o: &JsValue, k: &str) -> Result<siftlab_core::vo::Camera, String> {
    let a = get(o, k)?
        .dyn_into::<js_sys::Float64Array>()
        .map_err(|_| format!("message field {k} is not a Float64Array"))?
        .to_vec();
    camera_field(k, &a)
}

pub(crate) fn vec3(v: &[f64; 3]) -> JsValue {
    js_sys::Float64Array::from(v.as_slice()).into()
}

pub(crate) fn points_js(points: &[[f32; 2]]) -> JsValue {
    let flat: Vec<f32> = points.iter().flatten().copied().collect();
    Float32Array::from(flat.as_slice()).into()
}

pub(crate) fn get_points(o: &JsValue, k: &str) -> Result<Option<Vec<[f32; 2]>>, String> {
    let v = get(o, k)?;
    if v.is_null() || v.is_undefined() {
        return Ok(None);
    }
    let flat = v.dyn_into::<Float32Array>().map_err(|_| format!("message field {k} is not a Float32Array"))?.to_vec();
    points_field(k, &flat).map(Some)
}

/// The fields of a job on one image at OpenCV SIMD width `lanes`: SIFT's
/// (`ToWorker::Sift`) and its anatomy's (`InsideRequest::Anatomy`).
pub(crate) fn set_image_job(o: &Object, kind: &str, id: u32, bytes: &[u8], lanes: u32) {
    set(o, "type", &kind.into());
    set(o, "id", &id.into());
    set(o, "lanes", &lanes.into());
    set(o, "bytes", &Uint8Array::from(bytes).into());
}

/// A job's progress reply, the same for every kind of worker.
pub(crate) fn set_progress(o: &Object, id: u32, stage: &str) {
    set(o, "type", &"progress".into());
    set(o, "id", &id.into());
    set(o, "stage", &stage.into());
}

/// A job's failure reply (a user-facing message), the same for every kind of worker.
pub(crate) fn set_failed(o: &Object, id: u32, message: &str) {
    set(o, "type", &"failed".into());
    set(o, "id", &id.into());
    set(o, "message", &message.into());
}

pub(crate) fn kind(o: &JsValue) -> Result<String, String> {
    get_str(o, "type")
}

/// A field as a typed array (or any JS class) `T`.
pub(crate) fn get_typed<T: JsCast>(o: &JsValue, k: &str) -> Result<T, String> {
    get(o, k)?.dyn_into::<T>().map_err(|_| format!("message field {k} has the wrong array type"))
}

pub(crate) fn get_f32s(o: &JsValue, k: &str) -> Result<Vec<f32>, String> {
    Ok(get_typed::<Float32Array>(o, k)?.to_vec())
}

/// Keypoint floats per keypoint in a `kp` array: x, y, size, angle, response.
pub const KP_FLOATS: usize = 5;

/// Features from their flat arrays: [`KP_FLOATS`] floats and one octave per
/// keypoint, 128 descriptor bytes per keypoint. Sizes are compared in u64: in
/// usize, a product can wrap on wasm32 and let a short buffer pass.
pub fn features_from_parts(kp: &[f32], octave: &[i32], desc: &[u8]) -> Result<Features, String> {
    let n = octave.len() as u64;
    if kp.len() as u64 != n * KP_FLOATS as u64 || desc.len() as u64 != n * 128 {
        return Err(format!(
            "inconsistent features in a message: {n} octaves, {} floats, {} descriptor bytes",
            kp.len(),
            desc.len()
        ));
    }
    let keypoints = kp
        .chunks_exact(KP_FLOATS)
        .zip(octave)
        .map(|(f, &octave)| KeyPoint { x: f[0], y: f[1], size: f[2], angle: f[3], response: f[4], octave })
        .collect();
    let descriptors = desc.chunks_exact(128).map(|c| std::array::from_fn(|i| c[i])).collect();
    Ok(Features { keypoints, descriptors })
}

/// The field names of a feature set: `kp`, `octave`, `desc`, or with a
/// prefix `prevKp`, `prevOctave`, `prevDesc`.
fn feature_keys(prefix: &str) -> [String; 3] {
    if prefix.is_empty() {
        ["kp".into(), "octave".into(), "desc".into()]
    } else {
        [format!("{prefix}Kp"), format!("{prefix}Octave"), format!("{prefix}Desc")]
    }
}

/// Writes `f` as three flat typed arrays (keypoint floats as f32 and octaves
/// as i32: exactly the core's types, so nothing is rounded on the way).
pub(crate) fn set_features(o: &Object, prefix: &str, f: &Features) {
    let [kp_key, oct_key, desc_key] = feature_keys(prefix);
    let kp: Vec<f32> = f.keypoints.iter().flat_map(|k| [k.x, k.y, k.size, k.angle, k.response]).collect();
    let oct: Vec<i32> = f.keypoints.iter().map(|k| k.octave).collect();
    let desc: Vec<u8> = f.descriptors.iter().flatten().copied().collect();
    set(o, &kp_key, &Float32Array::from(kp.as_slice()).into());
    set(o, &oct_key, &Int32Array::from(oct.as_slice()).into());
    set(o, &desc_key, &Uint8Array::from(desc.as_slice()).into());
}

/// Reads what [`set_features`] wrote, with [`features_from_parts`]'s checks.
pub(crate) fn get_features(o: &JsValue, prefix: &str) -> Result<Features, String> {
    let [kp_key, oct_key, desc_key] = feature_keys(prefix);
    let kp = get_f32s(o, &kp_key)?;
    let oct = get_typed::<Int32Array>(o, &oct_key)?.to_vec();
    features_from_parts(&kp, &oct, &get_bytes(o, &desc_key)?)
}
