//! What the page and the workers take from the JavaScript platform: the clock,
//! the memory and the core count.

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

/// This wasm instance's linear memory in bytes (`memory.buffer.byteLength`).
/// Memory only grows, so in a worker it is the peak of every job so far.
pub fn wasm_memory_bytes() -> u32 {
    let mem = wasm_bindgen::memory();
    js_sys::Reflect::get(&mem, &"buffer".into())
        .ok()
        .and_then(|b| b.dyn_into::<js_sys::ArrayBuffer>().ok())
        .map_or(0, |b| b.byte_length())
}

/// The cores the browser reports (`navigator.hardwareConcurrency`, window or
/// worker), if it reports any.
pub fn hardware_concurrency() -> Option<usize> {
    let nav = js_sys::Reflect::get(&js_sys::global(), &"navigator".into()).ok()?;
    let n = js_sys::Reflect::get(&nav, &"hardwareConcurrency".into()).ok()?.as_f64()?;
    (n >= 1.0 && n.fract() == 0.0).then_some(n as usize)
}

/// An object URL for `bytes` (a download link's target), if the browser makes one.
pub fn blob_url(bytes: &[u8]) -> Option<String> {
    let parts = js_sys::Array::new();
    parts.push(&js_sys::Uint8Array::from(bytes));
    let blob = web_sys::Blob::new_with_u8_array_sequence(&parts).ok()?;
    web_sys::Url::create_object_url_with_blob(&blob).ok()
}

/// Frees an object URL made by [`blob_url`].
pub fn revoke(url: Option<String>) {
    if let Some(u) = url {
        let _ = web_sys::Url::revoke_object_url(&u);
    }
}
