//! The page side of "Mark my code": the browser transport of
//! `core::mark::Session` (the loop, limits and restarts live there, shared
//! with `siftlab mark`). One Pyodide worker (`www/mark-worker.js`, started
//! from a `blob:` URL so the page's CSP binds it) runs the student's file,
//! one request at a time, each with a time limit (wall time: a page cannot
//! read a worker's CPU time). Python cannot be interrupted from outside, so
//! a request over its limit ends the worker; the session then asks for a
//! fresh one (Pyodide comes from the browser's cache the second time).

use crate::model::lab::Source;
use crate::protocol::mark::set_pair;
use crate::protocol::mark::MARK_WORKER_NAME;
use siftlab_mark::{check_source, Limits, Marks, Outcome, Pair, Pairs, Session, Step};
use std::cell::RefCell;
use std::collections::HashMap;
use std::rc::Rc;
use wasm_bindgen::prelude::*;
use wasm_bindgen::JsCast;

/// Why a request got no reply.
#[derive(Clone, Debug, PartialEq)]
pub enum Failure {
    /// Over its time limit: the worker was terminated.
    Timeout,
    /// The worker could not start or crashed (its message).
    Crashed(String),
}

type Resolver = (js_sys::Function, js_sys::Function);

thread_local! {
    /// The memory snapshot of a Python that had just started (www/mark-worker.js), made by
    /// this page's first mark worker before any student code ran in it: each later worker
    /// starts from it instead of running CPython's start-up again.
    /// With it, the reference time (ms) that start measured: a restored Python runs the
    /// workload untimed until it is about that fast (its engine's tiers warm up); and that
    /// worker's compiled Pyodide (a `WebAssembly.Module`), which later workers instantiate
    /// instead of compiling it again (shared code: an engine's optimised tiers too).
    static SNAPSHOT: RefCell<Option<(js_sys::Uint8Array, f64, JsValue)>> = const { RefCell::new(None) };
}

#[derive(Default)]
struct State {
    next: u32,
    /// Each pending request's resolver and the session's request id its
    /// reply line must carry.
    pending: HashMap<u32, (Resolver, u64)>,
    ready: Option<Resolver>,
    /// Messages that were no reply (forged by the student's code, or late).
    stray: usize,
}

/// A mark worker whose Python is up: its start's time, its reference workload's time (ms),
/// whether Python came from the page's snapshot and whether the worker instantiated the
/// page's compiled Pyodide.
pub struct Started {
    pub worker: MarkWorker,
    pub ms: f64,
    pub reference: f64,
    pub restored: bool,
    pub shared: bool,
}

/// One running mark worker.
pub struct MarkWorker {
    worker: web_sys::Worker,
    state: Rc<RefCell<State>>,
    _handlers: [Closure<dyn FnMut(JsValue)>; 2],
}

fn js_err(e: JsValue) -> String {
    e.as_string().or_else(|| js_sys::JSON::stringify(&e).ok().and_then(|s| s.as_string())).unwrap_or_default()
}

/// A promise and its resolve/reject functions.
fn promise() -> (js_sys::Promise, Resolver) {
    let slot: Rc<RefCell<Option<Resolver>>> = Rc::default();
    let s = slot.clone();
    let p = js_sys::Promise::new(&mut |res, rej| *s.borrow_mut() = Some((res, rej)));
    let r = slot.borrow_mut().take().expect("the Promise executor runs at once");
    (p, r)
}

/// Rejects with "timeout" after `ms` unless something settled first.
fn reject_after(rej: &js_sys::Function, ms: i32) {
    let rej = rej.clone();
    let cb = Closure::once_into_js(move || {
        let _ = rej.call1(&JsValue::NULL, &"timeout".into());
    });
    if let Some(w) = web_sys::window() {
        let _ = w.set_timeout_with_callback_and_timeout_and_arguments_0(cb.unchecked_ref(), ms);
    }
}

impl MarkWorker {
    /// Starts the worker and waits until Python is up (at most `ms`).
    pub async fn start(ms: i32) -> Result<Started, Failure> {
        let opts = web_sys::WorkerOptions::new();
        opts.set_type(web_sys::WorkerType::Module);
        opts.set_name(MARK_WORKER_NAME);
        let worker = web_sys::Worker::new_with_options(&blob_url()?, &opts)
            .map_err(|e| Failure::Crashed(format!("cannot start the marking worker: {}", js_err(e))))?;
        let state: Rc<RefCell<State>> = Rc::default();
        let (ready, resolver) = promise();
        state.borrow_mut().ready = Some(resolver.clone());
        let st = state.clone();
        let on_message = Closure::<dyn FnMut(JsValue)>::new(move |ev: JsValue| {
            let data = ev.unchecked_into::<web_sys::MessageEvent>().data();
            let get = |k: &str| js_sys::Reflect::get(&data, &k.into()).unwrap_or(JsValue::UNDEFINED);
            match get("type").as_string().as_deref() {
                Some("markReady") => {
                    if let Some((res, _)) = st.borrow_mut().ready.take() {
                        // Only the start's own answer may carry a snapshot: it comes before the
                        // student's file reaches this worker (a message posted later finds no
                        // pending start and is ignored).
                        // A worker sends one only from a fresh start: the page had none, or the
                        // one it had did not load (it is replaced).
                        if let Ok(snap) = get("snapshot").dyn_into::<js_sys::Uint8Array>() {
                            let warm = get("reference").as_f64().filter(|r| r.is_finite() && *r > 0.0).unwrap_or(0.0);
                            let module = get("module");
                            let module = if module.is_instance_of::<js_sys::WebAssembly::Module>() {
                                module
                            } else {
                                JsValue::UNDEFINED
                            };
                            SNAPSHOT.with(|s| *s.borrow_mut() = Some((snap, warm, module)));
                        }
                        let _ = res.call1(&JsValue::NULL, &data);
                    }
                }
                Some("markFailed") => {
                    if let Some((_, rej)) = st.borrow_mut().ready.take() {
                        let _ = rej.call1(&JsValue::NULL, &get("message"));
                    }
                }
                Some("markReply") => {
                    // The student's code shares the worker and can post
                    // messages of its own: only the reply line to the
                    // pending request (its session id inside) settles it.
                    let id = get("id").as_f64().unwrap_or(-1.0) as u32;
                    let line = get("line").as_string().unwrap_or_default();
                    let mut s = st.borrow_mut();
                    match s.pending.get(&id) {
                        Some((_, req)) if Session::is_reply(&line, *req) => {
                            if let Some(((res, _), _)) = s.pending.remove(&id) {
                                let _ = res.call1(&JsValue::NULL, &JsValue::from_str(&line));
                            }
                        }
                        _ => s.stray += 1,
                    }
                }
                Some("markCrashed") => {
                    // Python ended inside the call (os._exit): the call crashed.
                    // The student's code could post this too, but a crash only
                    // costs its own call.
                    let id = get("id").as_f64().unwrap_or(-1.0) as u32;
                    // Prefixed here, so no posted text can pass for "timeout".
                    let message = format!("Python ended: {}", get("message").as_string().unwrap_or_default());
                    if let Some(((_, rej), _)) = st.borrow_mut().pending.remove(&id) {
                        let _ = rej.call1(&JsValue::NULL, &JsValue::from_str(&message));
                    }
                }
                _ => {}
            }
        });
        let st = state.clone();
        let on_error = Closure::<dyn FnMut(JsValue)>::new(move |ev: JsValue| {
            let msg = ev.dyn_ref::<web_sys::ErrorEvent>().map(|e| {
                e.prevent_default();
                e.message()
            });
            let msg: JsValue = format!("the marking worker stopped: {}", msg.unwrap_or_default()).into();
            let mut s = st.borrow_mut();
            for (_, ((_, rej), _)) in s.pending.drain() {
                let _ = rej.call1(&JsValue::NULL, &msg);
            }
            if let Some((_, rej)) = s.ready.take() {
                let _ = rej.call1(&JsValue::NULL, &msg);
            }
        });
        worker.set_onmessage(Some(on_message.as_ref().unchecked_ref()));
        worker.set_onerror(Some(on_error.as_ref().unchecked_ref()));
        let w = MarkWorker { worker, state, _handlers: [on_message, on_error] };
        let start = js_sys::Object::new();
        let _ = js_sys::Reflect::set(&start, &"op".into(), &"start".into());
        if let Some((snap, warm, module)) = SNAPSHOT.with(|s| s.borrow().clone()) {
            // Copied to the worker (structured clone): the page keeps its own for the next.
            let _ = js_sys::Reflect::set(&start, &"snapshot".into(), &snap);
            let _ = js_sys::Reflect::set(&start, &"warm".into(), &warm.into());
            let _ = js_sys::Reflect::set(&start, &"module".into(), &module);
        }
        if let Err(e) = w.worker.post_message(&start) {
            return Err(Failure::Crashed(format!("cannot start the marking worker: {}", js_err(e))));
        }
        reject_after(&resolver.1, ms);
        match wasm_bindgen_futures::JsFuture::from(ready).await {
            Ok(v) => {
                let get = |k: &str| js_sys::Reflect::get(&v, &k.into()).ok().and_then(|v| v.as_f64());
                // No figure is the slowest: the limits get the cap.
                let restored = js_sys::Reflect::get(&v, &"from".into()).ok().and_then(|f| f.as_string());
                let compiled = js_sys::Reflect::get(&v, &"compiled".into()).ok().and_then(|f| f.as_string());
                Ok(Started {
                    worker: w,
                    ms: get("ms").unwrap_or(0.0),
                    reference: get("reference").unwrap_or(f64::INFINITY),
                    restored: restored.as_deref() == Some("snapshot"),
                    shared: compiled.as_deref() == Some("shared"),
                })
            }
            Err(e) => {
                w.worker.terminate();
                let e = js_err(e);
                Err(if e == "timeout" {
                    Failure::Crashed(format!("Python did not start within {} s", ms / 1000))
                } else {
                    Failure::Crashed(e)
                })
            }
        }
    }

    /// Sends request `req` of the session (`op`: the protocol's op; `msg`
    /// may carry a pair's features for the worker's matcher:
    /// `protocol::mark::set_pair`) and waits at most `ms` for its reply
    /// line. Over the limit the worker is terminated: start another.
    pub async fn request_with(
        &self,
        msg: js_sys::Object,
        op: &str,
        line: &str,
        req: u64,
        ms: i32,
    ) -> Result<String, Failure> {
        let (p, (res, rej)) = promise();
        let id = {
            let mut s = self.state.borrow_mut();
            s.next += 1;
            let id = s.next;
            s.pending.insert(id, ((res, rej.clone()), req));
            id
        };
        let set = |k: &str, v: JsValue| js_sys::Reflect::set(&msg, &k.into(), &v);
        let _ = set("id", id.into());
        let _ = set("op", op.into());
        let _ = set("line", line.into());
        // The worker stops its own Python at this limit too (mark-worker.js): an engine may
        // leave a terminated worker's loop running.
        let _ = set("limit", ms.into());
        self.worker.post_message(&msg).map_err(|e| Failure::Crashed(js_err(e)))?;
        reject_after(&rej, ms);
        match wasm_bindgen_futures::JsFuture::from(p).await {
            Ok(v) => Ok(v.as_string().unwrap_or_default()),
            Err(e) => {
                self.state.borrow_mut().pending.remove(&id);
                let e = js_err(e);
                if e == "timeout" {
                    self.worker.terminate();
                    Err(Failure::Timeout)
                } else {
                    Err(Failure::Crashed(e))
                }
            }
        }
    }
}

impl Drop for MarkWorker {
    fn drop(&mut self) {
        self.worker.terminate();
    }
}

/// The worker's script behind a `blob:` URL. A worker loaded from a URL
/// gets the policy of that response's headers (none from a static server),
/// a `blob:` worker inherits the page's CSP (`connect-src 'self'`, no
/// `unsafe-eval`): the student's Python then cannot reach another origin
/// through any JavaScript it finds. The blob imports the real script by
/// its absolute URL; that module runs in the blob worker's scope.
fn blob_url() -> Result<String, Failure> {
    let href = web_sys::window()
        .and_then(|w| w.location().href().ok())
        .ok_or_else(|| Failure::Crashed("no page location".into()))?;
    let url = web_sys::Url::new_with_base("mark-worker.js", &href)
        .map_err(|e| Failure::Crashed(format!("mark-worker.js: {}", js_err(e))))?;
    let parts = js_sys::Array::of1(&JsValue::from_str(&format!("import {:?};\n", url.href())));
    let bag = web_sys::BlobPropertyBag::new();
    bag.set_type("text/javascript");
    let blob = web_sys::Blob::new_with_str_sequence_and_options(&parts, &bag)
        .map_err(|e| Failure::Crashed(format!("cannot build the worker's blob: {}", js_err(e))))?;
    web_sys::Url::create_object_url_with_blob(&blob)
        .map_err(|e| Failure::Crashed(format!("cannot build the worker's URL: {}", js_err(e))))
}

/// What a marking reports besides the marks.
#[derive(Clone, Debug, PartialEq)]
pub struct Timing {
    /// SIFT of the frames the cases need.
    pub sift_ms: f64,
    /// Python's (first) start.
    pub start_ms: f64,
    /// Loading the file and every call, restarts included.
    pub calls_ms: f64,
    /// The speed factor measured at each start of Python (its time for the
    /// reference workload over `REFERENCE_NOMINAL_MS`).
    pub speeds: Vec<f64>,
    /// A call's limit after the first start, in seconds.
    pub call_limit_s: f64,
    /// How many of the starts came from the page's Python snapshot.
    pub restored: usize,
    /// How many of the starts instantiated the page's compiled Pyodide instead of
    /// compiling it (www/mark-worker.js).
    pub shared: usize,
}

/// The frames' features, computed before the marking starts.
struct Features(Vec<Pair>);

impl Pairs for Features {
    fn pair(&mut self, frame: u32) -> siftlab_core::Result<&Pair> {
        self.0
            .iter()
            .find(|p| p.id == frame)
            .ok_or_else(|| siftlab_core::Error::InvalidArgument(format!("frame pair {frame} was not computed")))
    }
}

/// Marks `bytes` (the student's file) as the lab's automarker does, on
/// `source`'s frame pairs: the cases of `seed`, `n` per task. `Err` only when
/// the marking itself could not run (no pairs, SIFT or Python failing).
pub async fn run(
    bytes: Vec<u8>,
    seed: u64,
    n: usize,
    source: Source,
    progress: impl Fn(String),
) -> Result<(Marks, Timing), String> {
    use crate::model::mark::{REFERENCE_NOMINAL_MS, SPEED_CAP, START_LIMIT_MS};
    use crate::platform::now_ms;
    use std::collections::{BTreeMap, BTreeSet};
    let mut timing = Timing {
        sift_ms: 0.0,
        start_ms: 0.0,
        calls_ms: 0.0,
        speeds: Vec::new(),
        call_limit_s: 0.0,
        restored: 0,
        shared: 0,
    };
    let text = match check_source(&bytes) {
        Ok(t) => t.to_string(),
        Err(r) => return Ok((Marks::rejected(seed, n, r), timing)),
    };
    let frames = siftlab_mark::markable_frames(source.frames());
    if frames.is_empty() {
        return Err("marking needs frame pairs: load the demo or a MyKITTI folder".into());
    }
    // Only wall time exists here: the limits follow the machine's speed
    // and a call over its limit is re-run once (docs/marking.md).
    let mut session = Session::new(&text, seed, n, &frames, Limits::wall_clock(SPEED_CAP));
    // SIFT of every frame the cases use, once each (the pool's workers in parallel).
    let needed = siftlab_mark::frames_needed(session.cases());
    let t0 = now_ms();
    let mut features = BTreeMap::new();
    for (k, &id) in needed.iter().enumerate() {
        progress(format!("SIFT of the {} frames the cases use: {k} done", needed.len()));
        let b = super::sources::frame_bytes(&source, id).await?;
        features.insert(id, super::sift_pool::features_async(b).await.map_err(|e| format!("frame {id}: {e}"))?);
    }
    let used: BTreeSet<u32> = session.cases().iter().map(|c| c.frame()).collect();
    let mut pairs = Features(
        used.iter().map(|&f| Pair { id: f, prev: features[&(f - 1)].clone(), cur: features[&f].clone() }).collect(),
    );
    drop(features);
    timing.sift_ms = now_ms() - t0;
    let t0 = now_ms();
    let total = session.cases().len();
    let mut worker: Option<MarkWorker> = None;
    let marks = loop {
        match session.next(&mut pairs).map_err(|e| e.to_string())? {
            Step::Start => {
                if session.retrying() {
                    drop(worker.take());
                    progress("the call went over its limit: running it once more in a fresh Python".into());
                } else if worker.take().is_some() {
                    progress("the call was stopped: restarting Python".into());
                } else {
                    progress(
                        "starting Python (Pyodide: about 12 MB the first time, then from the browser's cache)".into(),
                    );
                }
                // A restart on a slow or busy machine gets the scaled time.
                let start_limit = (f64::from(START_LIMIT_MS) * session.scale()) as i32;
                let Started { worker: w, ms, reference, restored, shared } =
                    MarkWorker::start(start_limit).await.map_err(|e| match e {
                        Failure::Crashed(m) => m,
                        Failure::Timeout => "Python did not start in time".to_string(),
                    })?;
                if timing.start_ms == 0.0 {
                    timing.start_ms = ms;
                }
                timing.restored += usize::from(restored);
                timing.shared += usize::from(shared);
                // Measured at every start: a machine that got busy since
                // gets longer limits for the re-run.
                session.measured(reference / REFERENCE_NOMINAL_MS);
                timing.speeds.push(session.speed());
                if timing.call_limit_s == 0.0 {
                    timing.call_limit_s = session.call_limit();
                }
                worker = Some(w);
                session.started();
            }
            Step::Send { id, line, limit, op, pair } => {
                let Some(w) = worker.as_ref() else {
                    return Err("no marking worker is running".into());
                };
                if let Some(case) = session.current().filter(|_| op == "call") {
                    let k = session.results().len() + 1;
                    progress(format!("{} · call {k} of {total}", case.call_text()));
                }
                let msg = js_sys::Object::new();
                if let Some(p) = pair.and_then(|f| pairs.0.iter().find(|p| p.id == f)) {
                    set_pair(&msg, p);
                }
                let c0 = now_ms();
                let reply = w.request_with(msg, op, &line, id, (limit * 1000.0).ceil() as i32).await;
                let secs = (now_ms() - c0) / 1000.0;
                let outcome = match reply {
                    Ok(line) => Outcome::Reply(line, secs),
                    Err(Failure::Timeout) => Outcome::Timeout(secs),
                    Err(Failure::Crashed(m)) => Outcome::Crashed(m, secs),
                };
                if !matches!(outcome, Outcome::Reply(..)) {
                    drop(worker.take());
                }
                session.outcome(outcome, &mut pairs).map_err(|e| e.to_string())?;
            }
            Step::Done(marks) => break marks,
        }
    };
    drop(worker);
    timing.calls_ms = now_ms() - t0;
    Ok((marks, timing))
}
