//! What runs inside a Web Worker: SIFT with the lab's parameters ([`sift`]),
//! an odometry tracker's loop a frame at a time ([`odometry`]), and the
//! see-inside jobs ([`inside`]). One worker script serves all three kinds;
//! [`start`] decodes each request and hands it to its kind's handler.

pub mod inside;
pub mod mark;
pub mod odometry;
pub mod sift;

use crate::protocol::{ready_js, Request};
use wasm_bindgen::prelude::*;
use wasm_bindgen::JsCast;

/// Entry point of the worker script: listen for requests, then say we are ready
/// (the page queues its requests until then, so none is lost during start-up).
pub fn start() {
    std::panic::set_hook(Box::new(|info| {
        web_sys::console::error_1(&format!("siftlab worker panicked: {info}").into());
    }));
    let scope: web_sys::DedicatedWorkerGlobalScope = js_sys::global().unchecked_into();
    // The "Mark my code" worker loads this build only for its matcher
    // ([`mark`]'s exports): its own script handles the messages.
    if scope.name() == crate::protocol::mark::MARK_WORKER_NAME {
        return;
    }
    let post_scope = scope.clone();
    let onmessage = Closure::<dyn FnMut(web_sys::MessageEvent)>::new(move |ev: web_sys::MessageEvent| {
        let post = |m: JsValue| {
            let _ = post_scope.post_message(&m);
        };
        match Request::from_js(&ev.data()) {
            Ok(Request::Sift(r)) => sift::handle(r, &|m| post(m.to_js())),
            Ok(Request::Odometry(r)) => odometry::handle(r, &|m| post(m.to_js())),
            Ok(Request::Inside(r)) => inside::handle(r, &|m| post(m.to_js())),
            Err(e) => web_sys::console::error_1(&format!("siftlab worker: {e}").into()),
        }
    });
    scope.set_onmessage(Some(onmessage.as_ref().unchecked_ref()));
    // The handler lives as long as the worker.
    onmessage.forget();
    let _ = scope.post_message(&ready_js());
}
