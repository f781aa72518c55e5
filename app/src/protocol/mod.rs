//! The messages between the page and its workers, one type per kind of
//! worker job: [`sift`] (the SIFT pool), [`odometry`] (a tracking worker),
//! [`inside`] (SIFT's anatomy and the whole-frame sweep). They cross
//! `postMessage` as plain JS objects whose bulky parts are typed arrays, all
//! read and written through one [`codec`]. One worker script serves every
//! kind, so a request travels in the [`Request`] envelope; a reply is decoded
//! as the kind its sender expects. Imports nothing else of the app.

pub mod codec;
pub mod inside;
pub mod mark;
pub mod odometry;
pub mod sift;

use codec::{kind, set};
use wasm_bindgen::JsValue;

/// Page → worker: any kind's request.
#[derive(Debug, Clone, PartialEq)]
pub enum Request {
    Sift(sift::SiftRequest),
    Odometry(odometry::VoRequest),
    Inside(inside::InsideRequest),
}

impl Request {
    pub fn to_js(&self) -> JsValue {
        match self {
            Request::Sift(r) => r.to_js(),
            Request::Odometry(r) => r.to_js(),
            Request::Inside(r) => r.to_js(),
        }
    }

    pub fn from_js(v: &JsValue) -> Result<Self, String> {
        if let Some(r) = sift::SiftRequest::from_js(v) {
            return r.map(Request::Sift);
        }
        if let Some(r) = odometry::VoRequest::from_js(v) {
            return r.map(Request::Odometry);
        }
        if let Some(r) = inside::InsideRequest::from_js(v) {
            return r.map(Request::Inside);
        }
        Err(format!("unknown message type {:?}", kind(v)?))
    }
}

/// What a worker posts once its wasm is initialised and it listens (the
/// page queues its requests until then).
pub fn ready_js() -> JsValue {
    let o = js_sys::Object::new();
    set(&o, "type", &"ready".into());
    o.into()
}

/// Whether `v` is the worker's [`ready_js`] message.
pub fn is_ready(v: &JsValue) -> bool {
    kind(v).is_ok_and(|k| k == "ready")
}
