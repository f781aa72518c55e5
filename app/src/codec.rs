//! The one codec of the worker messages: every field of `msg` and `msg_inside`
//! is read and written through these helpers, with its checks.

use js_sys::{Float32Array, Object, Reflect, Uint8Array};
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
// run natively: `fuzz/fuzz_targets/app_state.rs` and the host tests call them
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

pub(crate) fn kind(o: &JsValue) -> Result<String, String> {
    get_str(o, "type")
}
