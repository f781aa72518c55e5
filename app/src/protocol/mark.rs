//! "Mark my code": a frame pair as the page sends it to the marking worker.
//! The protocol line (docs/marking.md) carries the pair for Python; the same
//! message carries the features in the codec's arrays for the worker's
//! matcher, which answers the student's knnMatch by reference to them.

use super::codec::{get_features, get_u32, set, set_features};
use js_sys::Object;
use siftlab_mark::Pair;
use wasm_bindgen::JsValue;

/// The name the page gives the "Mark my code" worker (`www/mark-worker.js`).
pub const MARK_WORKER_NAME: &str = "siftlab-mark";

/// The pair's fields, added to the message object `o`.
pub fn set_pair(o: &Object, pair: &Pair) {
    set(o, "pairId", &pair.id.into());
    set_features(o, "p", &pair.prev);
    set_features(o, "c", &pair.cur);
}

/// The pair of a message built by [`set_pair`].
pub fn get_pair(v: &JsValue) -> Result<Pair, String> {
    Ok(Pair { id: get_u32(v, "pairId")?, prev: get_features(v, "p")?, cur: get_features(v, "c")? })
}
