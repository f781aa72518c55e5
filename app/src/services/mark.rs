//! The page side of "Mark my code": one Pyodide worker (`www/mark-worker.js`)
//! running the student's file, one request at a time, each with a time limit.
//! Python cannot be interrupted from outside, so a call over its limit ends
//! the worker: the caller starts a fresh one (Pyodide comes from
//! the browser's cache the second time).

use crate::model::lab::Source;
use crate::protocol::mark::set_pair;
use crate::worker::MARK_WORKER_NAME;
use siftlab_core::mark::{
    call_message, check_source, failed_call, judge, load_message, pair_message, parse_reply, plan, reference,
    CaseResult, Diagnosis, Marks, Pair, Rejection, Reply,
};
use std::cell::Cell;
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

#[derive(Default)]
struct State {
    next: u32,
    pending: HashMap<u32, Resolver>,
    ready: Option<Resolver>,
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
    /// Starts the worker and waits until Python is up (at most `ms`):
    /// returns the start-up time the worker measured, in ms.
    pub async fn start(ms: i32) -> Result<(MarkWorker, f64), Failure> {
        let opts = web_sys::WorkerOptions::new();
        opts.set_type(web_sys::WorkerType::Module);
        opts.set_name(MARK_WORKER_NAME);
        let worker = web_sys::Worker::new_with_options("mark-worker.js", &opts)
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
                        let _ = res.call1(&JsValue::NULL, &get("ms"));
                    }
                }
                Some("markFailed") => {
                    if let Some((_, rej)) = st.borrow_mut().ready.take() {
                        let _ = rej.call1(&JsValue::NULL, &get("message"));
                    }
                }
                Some("markReply") => {
                    let id = get("id").as_f64().unwrap_or(-1.0) as u32;
                    if let Some((res, _)) = st.borrow_mut().pending.remove(&id) {
                        let _ = res.call1(&JsValue::NULL, &get("line"));
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
            for (_, (_, rej)) in s.pending.drain() {
                let _ = rej.call1(&JsValue::NULL, &msg);
            }
            if let Some((_, rej)) = s.ready.take() {
                let _ = rej.call1(&JsValue::NULL, &msg);
            }
        });
        worker.set_onmessage(Some(on_message.as_ref().unchecked_ref()));
        worker.set_onerror(Some(on_error.as_ref().unchecked_ref()));
        let w = MarkWorker { worker, state, _handlers: [on_message, on_error] };
        reject_after(&resolver.1, ms);
        match wasm_bindgen_futures::JsFuture::from(ready).await {
            Ok(v) => Ok((w, v.as_f64().unwrap_or(0.0))),
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

    /// Sends one request (`op`: the protocol's op, the worker keeps pairs
    /// for its matcher) and waits at most `ms` for the reply line. Over the
    /// limit the worker is terminated: start another.
    pub async fn request(&self, op: &str, line: &str, ms: i32) -> Result<String, Failure> {
        self.request_with(js_sys::Object::new(), op, line, ms).await
    }

    /// [`MarkWorker::request`] with more fields in the message (a pair's
    /// features for the worker's matcher: `protocol::mark::set_pair`).
    pub async fn request_with(&self, msg: js_sys::Object, op: &str, line: &str, ms: i32) -> Result<String, Failure> {
        let (p, (res, rej)) = promise();
        let id = {
            let mut s = self.state.borrow_mut();
            s.next += 1;
            let id = s.next;
            s.pending.insert(id, (res, rej.clone()));
            id
        };
        let set = |k: &str, v: JsValue| js_sys::Reflect::set(&msg, &k.into(), &v);
        let _ = set("id", id.into());
        let _ = set("op", op.into());
        let _ = set("line", line.into());
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

/// SIFT's features of `bytes` through the page's pool (and its cache).
async fn features_of(bytes: Vec<u8>) -> Result<siftlab_core::sift::Features, String> {
    let (p, (res, rej)) = promise();
    let slot: Rc<RefCell<Option<Result<siftlab_core::sift::Features, String>>>> = Rc::default();
    let out = slot.clone();
    super::sift_pool::features(bytes, move |r| {
        let ok = r.is_ok();
        *out.borrow_mut() = Some(r.map(|r| r.features));
        let _ = if ok { res.call0(&JsValue::NULL) } else { rej.call0(&JsValue::NULL) };
    });
    let _ = wasm_bindgen_futures::JsFuture::from(p).await;
    let r = slot.borrow_mut().take();
    r.unwrap_or_else(|| Err("SIFT did not answer".into()))
}

/// Starts a worker and loads the student's file in it: `Err` is the file's
/// rejection (it scores 0) or why Python could not run at all.
async fn start_loaded(text: &str, progress: &dyn Fn(String)) -> Result<MarkWorker, Result<Rejection, String>> {
    use crate::model::mark::{CALL_LIMIT_MS, START_LIMIT_MS};
    progress("starting Python (Pyodide: about 12 MB the first time, then from the browser's cache)".into());
    let (w, ms) = MarkWorker::start(START_LIMIT_MS).await.map_err(|e| match e {
        Failure::Crashed(m) => Err(m),
        Failure::Timeout => Err("Python did not start in time".to_string()),
    })?;
    LAST_START_MS.with(|c| c.set(ms));
    progress(format!("Python ready in {:.1} s; loading your file", ms / 1000.0));
    let t0 = crate::platform::now_ms();
    match w.request("load", &load_message(text), CALL_LIMIT_MS).await {
        Ok(line) => match parse_reply(&line) {
            Ok(Reply::Error { message, kind }) => Err(Ok(Rejection::Load { kind, message })),
            Ok(_) => Ok(w),
            Err(e) => Err(Err(format!("the harness answered {line:?}: {e}"))),
        },
        Err(Failure::Timeout) => Err(Ok(Rejection::LoadTimeout { seconds: (crate::platform::now_ms() - t0) / 1000.0 })),
        Err(Failure::Crashed(m)) => Err(Err(m)),
    }
}

thread_local! {
    /// How long the last start of Python took, in ms.
    static LAST_START_MS: Cell<f64> = const { Cell::new(0.0) };
}

/// How long the last start of Python took, in ms (shown with the report).
pub fn last_start_ms() -> f64 {
    LAST_START_MS.with(Cell::get)
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
    use crate::model::mark::{CALL_LIMIT_MS, TASK_LIMIT_MS};
    use crate::platform::now_ms;
    use std::collections::{BTreeMap, BTreeSet};
    let mut timing = Timing { sift_ms: 0.0, start_ms: 0.0, calls_ms: 0.0 };
    let text = match check_source(&bytes) {
        Ok(t) => t.to_string(),
        Err(r) => return Ok((Marks::rejected(seed, n, r), timing)),
    };
    let ids = source.frames();
    let frames: Vec<u32> = ids.iter().copied().filter(|&f| f >= 1 && ids.contains(&(f - 1))).collect();
    if frames.is_empty() {
        return Err("marking needs frame pairs: load the demo or a MyKITTI folder".into());
    }
    let cases = plan(seed, n, &frames);
    // SIFT of every frame the cases use, once each (the pool's workers in parallel).
    let needed: BTreeSet<u32> = cases.iter().flat_map(|c| [c.frame() - 1, c.frame()]).collect();
    let t0 = now_ms();
    let mut features = BTreeMap::new();
    for (k, &id) in needed.iter().enumerate() {
        progress(format!("SIFT of the {} frames the cases use: {k} done", needed.len()));
        let b = super::loading::frame_bytes(&source, id).await?;
        features.insert(id, features_of(b).await.map_err(|e| format!("frame {id}: {e}"))?);
    }
    timing.sift_ms = now_ms() - t0;
    let t0 = now_ms();
    let mut worker = match start_loaded(&text, &progress).await {
        Ok(w) => w,
        Err(Ok(rejection)) => return Ok((Marks::rejected(seed, n, rejection), timing)),
        Err(Err(e)) => return Err(e),
    };
    timing.start_ms = last_start_ms();
    let mut sent = BTreeSet::new();
    let mut results: Vec<CaseResult> = Vec::with_capacity(cases.len());
    let mut task_ms: BTreeMap<&'static str, f64> = BTreeMap::new();
    for (k, case) in cases.iter().enumerate() {
        let f = case.frame();
        let (prev, cur) = (&features[&(f - 1)], &features[&f]);
        let expected = reference(case, prev, cur).map_err(|e| e.to_string())?;
        let task = case.task().name();
        let used = task_ms.get(task).copied().unwrap_or(0.0);
        if used > TASK_LIMIT_MS {
            results.push(failed_call(case, &expected, Diagnosis::TaskTimeLimit { seconds: used / 1000.0 }, 0.0));
            continue;
        }
        progress(format!("{} · call {} of {}", case.call_text(), k + 1, cases.len()));
        if sent.insert(f) {
            let msg = js_sys::Object::new();
            set_pair(&msg, &Pair { id: f, prev: prev.clone(), cur: cur.clone() });
            if let Err(e) = worker.request_with(msg, "pair", &pair_message(f, prev, cur), CALL_LIMIT_MS).await {
                return Err(format!("sending frames {} and {f} to Python: {e:?}", f - 1));
            }
        }
        let c0 = now_ms();
        let reply = worker.request("call", &call_message(case, f, &expected), CALL_LIMIT_MS).await;
        let secs = (now_ms() - c0) / 1000.0;
        *task_ms.entry(task).or_default() += secs * 1000.0;
        let restart = match reply {
            Ok(line) => match parse_reply(&line) {
                Ok(r) => {
                    results.push(judge(case, &expected, &r, prev, cur, secs));
                    false
                }
                Err(e) => {
                    results.push(failed_call(case, &expected, Diagnosis::Crashed(e.to_string()), secs));
                    true
                }
            },
            Err(Failure::Timeout) => {
                results.push(failed_call(
                    case,
                    &expected,
                    Diagnosis::Timeout { seconds: CALL_LIMIT_MS as f64 / 1000.0 },
                    secs,
                ));
                true
            }
            Err(Failure::Crashed(m)) => {
                results.push(failed_call(case, &expected, Diagnosis::Crashed(m), secs));
                true
            }
        };
        if restart {
            // A fresh Python with the file loaded again; the pairs go again when used.
            drop(worker);
            sent.clear();
            progress("the call was stopped: restarting Python".into());
            worker = match start_loaded(&text, &progress).await {
                Ok(w) => w,
                Err(Ok(r)) => return Ok((Marks::rejected(seed, n, r), timing)),
                Err(Err(e)) => return Err(e),
            };
        }
    }
    drop(worker);
    timing.calls_ms = now_ms() - t0;
    Ok((Marks::new(seed, n, results), timing))
}
