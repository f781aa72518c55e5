//! One module worker running the worker script, seen from the page: requests
//! go out as [`Request`]s (queued until the worker says it is ready, so none
//! sent during its start-up is lost), replies come back decoded as the one
//! kind this worker's owner expects. Dropping the handle terminates the worker.

use crate::protocol::{is_ready, Request};
use std::cell::RefCell;
use std::rc::Rc;
use wasm_bindgen::prelude::*;
use wasm_bindgen::JsCast;

struct Inner {
    worker: web_sys::Worker,
    ready: bool,
    queue: Vec<JsValue>,
}

pub(crate) struct WorkerHandle {
    inner: Rc<RefCell<Inner>>,
    // Keeps the JS callbacks alive as long as the worker.
    _handlers: [Closure<dyn FnMut(JsValue)>; 2],
}

impl WorkerHandle {
    /// Starts a module worker running `script`: its replies, decoded by
    /// `decode`, go to `on_message` (an undecodable one is logged); a failed
    /// start or a panic (wasm aborts, the instance is unusable) calls `on_crash`.
    pub(crate) fn start<R: 'static>(
        script: &str,
        decode: fn(&JsValue) -> Result<R, String>,
        on_message: impl Fn(R) + 'static,
        on_crash: impl Fn() + 'static,
    ) -> Result<WorkerHandle, String> {
        let deliver = move |data: &JsValue| match decode(data) {
            Ok(m) => on_message(m),
            Err(e) => web_sys::console::error_1(&format!("siftlab: bad worker message: {e}").into()),
        };
        Self::start_with(script, Box::new(deliver), Box::new(on_crash))
    }

    /// [`WorkerHandle::start`] after the decoding: one copy of the
    /// transport for every kind of reply.
    fn start_with(
        script: &str,
        deliver: Box<dyn Fn(&JsValue)>,
        on_crash: Box<dyn Fn()>,
    ) -> Result<WorkerHandle, String> {
        let opts = web_sys::WorkerOptions::new();
        opts.set_type(web_sys::WorkerType::Module);
        let worker =
            web_sys::Worker::new_with_options(script, &opts).map_err(|e| format!("cannot start a worker: {e:?}"))?;
        let inner = Rc::new(RefCell::new(Inner { worker: worker.clone(), ready: false, queue: Vec::new() }));
        let on_ready = inner.clone();
        let on_message = Closure::<dyn FnMut(JsValue)>::new(move |ev: JsValue| {
            let data = ev.unchecked_into::<web_sys::MessageEvent>().data();
            if is_ready(&data) {
                // What was queued goes out, in order.
                let mut inner = on_ready.borrow_mut();
                inner.ready = true;
                for m in std::mem::take(&mut inner.queue) {
                    let _ = inner.worker.post_message(&m);
                }
                return;
            }
            deliver(&data);
        });
        let on_error = Closure::<dyn FnMut(JsValue)>::new(move |ev: JsValue| {
            if let Some(e) = ev.dyn_ref::<web_sys::ErrorEvent>() {
                e.prevent_default();
            }
            on_crash();
        });
        worker.set_onmessage(Some(on_message.as_ref().unchecked_ref()));
        worker.set_onerror(Some(on_error.as_ref().unchecked_ref()));
        Ok(WorkerHandle { inner, _handlers: [on_message, on_error] })
    }

    /// Posts `m`, or queues it until the worker is ready.
    pub(crate) fn send(&self, m: &Request) {
        let m = m.to_js();
        let mut inner = self.inner.borrow_mut();
        if inner.ready {
            let _ = inner.worker.post_message(&m);
        } else {
            inner.queue.push(m);
        }
    }
}

impl Drop for WorkerHandle {
    fn drop(&mut self) {
        self.inner.borrow().worker.terminate();
    }
}
