//! What the page and the workers take from the JavaScript platform: the clock.

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
