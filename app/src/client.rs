//! The page side of the SIFT workers: a small pool (one worker per frame slot,
//! since the two frames of a pair are independent), a request queue for the
//! start-up window, and a cache of finished frames keyed by the file's content.

use crate::msg::{FromWorker, SiftResult, ToWorker};
use std::cell::RefCell;
use std::collections::HashMap;
use std::sync::Arc;
use wasm_bindgen::prelude::*;
use wasm_bindgen::JsCast;

/// One analysed frame: the gray image SIFT saw and its features.
#[derive(Debug, Clone, PartialEq)]
pub struct FrameData {
    /// What the user loaded (file name or `gray/00/image_0/000001.png`).
    pub label: String,
    /// The worker's result (its fields read through `Deref`: `frame.features`, `frame.gray`, …).
    pub sift: SiftResult,
    /// The file's bytes, to re-run SIFT when the OpenCV SIMD width changes.
    pub bytes: Arc<Vec<u8>>,
    pub lanes: usize,
}

pub type Frame = Arc<FrameData>;

impl FrameData {
    pub fn from_result(label: String, sift: SiftResult, bytes: Arc<Vec<u8>>, lanes: usize) -> Self {
        FrameData { label, sift, bytes, lanes }
    }
}

impl std::ops::Deref for FrameData {
    type Target = SiftResult;

    fn deref(&self) -> &SiftResult {
        &self.sift
    }
}

/// FNV-1a over the bytes and the SIMD width: the cache key (same file content
/// and parameters → same features).
pub fn content_key(bytes: &[u8], lanes: usize) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325 ^ lanes as u64;
    for &b in bytes {
        h ^= b as u64;
        h = h.wrapping_mul(0x0100_0000_01b3);
    }
    h ^ (bytes.len() as u64).rotate_left(32)
}

/// One module worker running the worker script, and the messages waiting for
/// it to say it is ready (nothing sent during its start-up is lost). The pool's
/// SIFT workers and an odometry run's workers are all of this kind; dropping
/// one terminates its worker.
pub(crate) struct WorkerHandle {
    worker: web_sys::Worker,
    ready: bool,
    queue: Vec<JsValue>,
    // Keeps the JS callbacks alive as long as the worker.
    _handlers: [Closure<dyn FnMut(JsValue)>; 2],
}

impl WorkerHandle {
    /// Starts a module worker running `script`: its messages, decoded, go to
    /// `on_message` (an undecodable one is logged); a failed start or a panic
    /// (wasm aborts, the instance is unusable) calls `on_crash`.
    pub(crate) fn start(
        script: &str,
        on_message: impl Fn(FromWorker) + 'static,
        on_crash: impl Fn() + 'static,
    ) -> Result<WorkerHandle, String> {
        let opts = web_sys::WorkerOptions::new();
        opts.set_type(web_sys::WorkerType::Module);
        let worker =
            web_sys::Worker::new_with_options(script, &opts).map_err(|e| format!("cannot start a worker: {e:?}"))?;
        let on_message = Closure::<dyn FnMut(JsValue)>::new(move |ev: JsValue| {
            let data = ev.unchecked_into::<web_sys::MessageEvent>().data();
            match FromWorker::from_js(&data) {
                Ok(m) => on_message(m),
                Err(e) => web_sys::console::error_1(&format!("siftlab: bad worker message: {e}").into()),
            }
        });
        let on_error = Closure::<dyn FnMut(JsValue)>::new(move |ev: JsValue| {
            if let Some(e) = ev.dyn_ref::<web_sys::ErrorEvent>() {
                e.prevent_default();
            }
            on_crash();
        });
        worker.set_onmessage(Some(on_message.as_ref().unchecked_ref()));
        worker.set_onerror(Some(on_error.as_ref().unchecked_ref()));
        Ok(WorkerHandle { worker, ready: false, queue: Vec::new(), _handlers: [on_message, on_error] })
    }

    /// Posts `m`, or queues it until the worker is ready.
    pub(crate) fn send(&mut self, m: ToWorker) {
        let m = m.to_js();
        if self.ready {
            let _ = self.worker.post_message(&m);
        } else {
            self.queue.push(m);
        }
    }

    /// The worker said `Ready`: what was queued goes out, in order.
    pub(crate) fn set_ready(&mut self) {
        self.ready = true;
        for m in std::mem::take(&mut self.queue) {
            let _ = self.worker.post_message(&m);
        }
    }
}

impl Drop for WorkerHandle {
    fn drop(&mut self) {
        self.worker.terminate();
    }
}

type Progress = Box<dyn Fn(String)>;
type Done = Box<dyn FnOnce(Result<SiftResult, String>)>;

struct Waiter {
    progress: Progress,
    done: Done,
}

struct Job {
    key: u64,
    slot: usize,
    waiters: Vec<Waiter>,
}

/// A SIFT worker of the pool and the number of jobs it has.
struct Slot {
    handle: WorkerHandle,
    load: usize,
}

#[derive(Default)]
struct Pool {
    script: String,
    /// `None` after a crash: respawned on the next request, never in a loop.
    slots: Vec<Option<Slot>>,
    next_id: u32,
    jobs: HashMap<u32, Job>,
    in_flight: HashMap<u64, u32>,
    cache: HashMap<u64, SiftResult>,
}

thread_local! {
    static POOL: RefCell<Pool> = RefCell::new(Pool {
        script: "./worker.js".into(),
        ..Default::default()
    });
}

/// Number of workers: one per frame of a pair.
const WORKERS: usize = 2;

fn spawn(index: usize, script: &str) -> Result<Slot, String> {
    let handle = WorkerHandle::start(script, move |m| on_worker_message(index, m), move || on_worker_crash(index))?;
    Ok(Slot { handle, load: 0 })
}

fn on_worker_message(index: usize, m: FromWorker) {
    match m {
        FromWorker::Ready => POOL.with(|p| {
            if let Some(Some(slot)) = p.borrow_mut().slots.get_mut(index) {
                slot.handle.set_ready();
            }
        }),
        FromWorker::Progress { id, stage } => with_progress(id, &stage),
        FromWorker::Done { id, result } => finish(id, Ok(result)),
        FromWorker::Failed { id, message } => finish(id, Err(message)),
        // Odometry runs have their own workers (see `run_vo`).
        FromWorker::VoStep { .. }
        | FromWorker::VoDone { .. }
        | FromWorker::Detected { .. }
        | FromWorker::VoMetrics { .. }
        | FromWorker::Inside(_) => {}
    }
}

fn with_progress(id: u32, stage: &str) {
    // Take the waiters out, call them, put them back: no borrow is held while
    // user callbacks run.
    let waiters = POOL.with(|p| p.borrow_mut().jobs.get_mut(&id).map(|j| std::mem::take(&mut j.waiters)));
    let Some(waiters) = waiters else { return };
    for w in &waiters {
        (w.progress)(stage.to_string());
    }
    POOL.with(|p| {
        if let Some(j) = p.borrow_mut().jobs.get_mut(&id) {
            let mut added = std::mem::take(&mut j.waiters);
            j.waiters = waiters;
            j.waiters.append(&mut added);
        }
    });
}

fn finish(id: u32, r: Result<SiftResult, String>) {
    let job = POOL.with(|p| {
        let mut p = p.borrow_mut();
        let job = p.jobs.remove(&id)?;
        p.in_flight.remove(&job.key);
        if let Some(Some(s)) = p.slots.get_mut(job.slot) {
            s.load = s.load.saturating_sub(1);
        }
        if let Ok(res) = &r {
            p.cache.insert(job.key, res.clone());
        }
        Some(job)
    });
    if let Some(job) = job {
        for w in job.waiters {
            (w.done)(r.clone());
        }
    }
}

fn on_worker_crash(index: usize) {
    let (old, failed): (Option<Slot>, Vec<u32>) = POOL.with(|p| {
        let mut p = p.borrow_mut();
        let old = p.slots.get_mut(index).and_then(Option::take);
        (old, p.jobs.iter().filter(|(_, j)| j.slot == index).map(|(id, _)| *id).collect())
    });
    // Dropping the slot terminates its worker.
    drop(old);
    for id in failed {
        finish(id, Err("the SIFT worker failed (it could not start, or ran out of memory); try again".into()));
    }
}

/// Where the worker script lives (tests point it elsewhere).
pub fn set_worker_script(url: &str) {
    POOL.with(|p| p.borrow_mut().script = url.to_string());
}

/// The worker script's URL.
pub(crate) fn worker_script() -> String {
    POOL.with(|p| p.borrow().script.clone())
}

/// A frame already analysed with these exact bytes, if any.
pub fn cached(bytes: &[u8], lanes: usize) -> Option<SiftResult> {
    let key = content_key(bytes, lanes);
    POOL.with(|p| p.borrow().cache.get(&key).cloned())
}

/// Stores a result computed elsewhere (tests, or a frame analysed in-process).
pub fn insert_cache(bytes: &[u8], lanes: usize, r: SiftResult) {
    let key = content_key(bytes, lanes);
    POOL.with(|p| {
        p.borrow_mut().cache.insert(key, r);
    });
}

/// Runs SIFT on `bytes` in a worker. `done` is called exactly once (immediately
/// on a cache hit); identical requests in flight share one computation.
pub fn sift(
    bytes: Vec<u8>,
    lanes: usize,
    progress: impl Fn(String) + 'static,
    done: impl FnOnce(Result<SiftResult, String>) + 'static,
) {
    let key = content_key(&bytes, lanes);
    if let Some(hit) = POOL.with(|p| p.borrow().cache.get(&key).cloned()) {
        done(Ok(hit));
        return;
    }
    let waiter = Waiter { progress: Box::new(progress), done: Box::new(done) };
    let failed: Result<(), (String, Waiter)> = POOL.with(|p| {
        let mut p = p.borrow_mut();
        if let Some(id) = p.in_flight.get(&key).copied() {
            if let Some(job) = p.jobs.get_mut(&id) {
                job.waiters.push(waiter);
                return Ok(());
            }
        }
        p.slots.resize_with(WORKERS, || None);
        for i in 0..WORKERS {
            if p.slots[i].is_none() {
                let script = p.script.clone();
                match spawn(i, &script) {
                    Ok(s) => p.slots[i] = Some(s),
                    Err(e) => return Err((e, waiter)),
                }
            }
        }
        let load = |s: &Option<Slot>| s.as_ref().map(|s| s.load).unwrap_or(usize::MAX);
        let slot = (0..WORKERS).min_by_key(|&i| load(&p.slots[i])).unwrap_or(0);
        p.next_id = p.next_id.wrapping_add(1);
        let id = p.next_id;
        p.jobs.insert(id, Job { key, slot, waiters: vec![waiter] });
        p.in_flight.insert(key, id);
        if let Some(s) = p.slots[slot].as_mut() {
            s.load += 1;
            s.handle.send(ToWorker::Sift { id, bytes, lanes: lanes as u32 });
        }
        Ok(())
    });
    if let Err((e, w)) = failed {
        (w.done)(Err(e));
    }
}

/// A visual-odometry run: a tracking worker that runs the lab's loop a frame
/// at a time, and two detection helpers that find each frame's keypoints
/// ahead of it, two frames at once (detection needs only the image, and is
/// nine tenths of a frame's work in wasm). The page hands frames to the
/// helpers as they free up and each detected frame to the tracker in order,
/// so the results are those of the one-worker loop (and of the CLI), only
/// sooner. Dropping it (a new run, or [`stop_vo`]) terminates the workers.
struct VoRun {
    tracker: WorkerHandle,
    helpers: Vec<Helper>,
    frames: Vec<Vec<u8>>,
    /// Per frame: `None` until detected; `Some(None)` for frame 1, which never re-detects.
    detected: Vec<Option<Option<Vec<[f32; 2]>>>>,
    next_detect: usize,
    next_track: usize,
    tracking: bool,
    over: bool,
    on_event: std::rc::Rc<dyn Fn(FromWorker)>,
}

/// A detection helper of an odometry run.
struct Helper {
    handle: WorkerHandle,
    /// The frame it is detecting.
    busy: Option<usize>,
    /// A helper that crashed gets no more frames.
    dead: bool,
}

thread_local! {
    static VO_RUN: RefCell<Option<VoRun>> = const { RefCell::new(None) };
}

/// Which worker of the run a message came from.
#[derive(Clone, Copy)]
enum Role {
    Tracker,
    Helper(usize),
}

const VO_ID: u32 = 1;
const VO_HELPERS: usize = 2;

/// Starts the lab's odometry loop on `frames`; `on_event` gets every
/// `VoStep`, then `VoDone` or `Failed`. A new run replaces the previous one.
pub fn run_vo(frames: Vec<Vec<u8>>, poses: String, on_event: impl Fn(FromWorker) + 'static) -> Result<(), String> {
    let start = ToWorker::VoStart { id: VO_ID, total: frames.len() as u32, poses };
    start_vo(frames, start, VO_HELPERS, on_event)
}

/// [`run_vo`] with the student's matcher instead of LK (`vo::matched`): the
/// tracking worker runs SIFT on every frame itself, so no helpers.
pub fn run_vo_matched(
    frames: Vec<Vec<u8>>,
    poses: String,
    strategy: siftlab_core::matching::Strategy,
    on_event: impl Fn(FromWorker) + 'static,
) -> Result<(), String> {
    let start = ToWorker::VoMatchedStart {
        id: VO_ID,
        total: frames.len() as u32,
        poses,
        algo: strategy.name().into(),
        threshold: strategy.threshold(),
    };
    start_vo(frames, start, 0, on_event)
}

fn start_vo(
    frames: Vec<Vec<u8>>,
    start_msg: ToWorker,
    helpers: usize,
    on_event: impl Fn(FromWorker) + 'static,
) -> Result<(), String> {
    stop_vo();
    let script = POOL.with(|p| p.borrow().script.clone());
    let start = |role: Role| WorkerHandle::start(&script, move |m| on_vo_message(role, m), move || on_vo_crash(role));
    let mut tracker = start(Role::Tracker)?;
    let helpers = (0..helpers)
        .map(|i| start(Role::Helper(i)).map(|handle| Helper { handle, busy: None, dead: false }))
        .collect::<Result<Vec<_>, _>>()?;
    let matched = matches!(start_msg, ToWorker::VoMatchedStart { .. });
    tracker.send(start_msg);
    let mut detected = vec![None; frames.len()];
    for (i, d) in detected.iter_mut().enumerate() {
        // Frame 1 never re-detects; a matched run detects in the tracker.
        if i == 1 || matched {
            *d = Some(None);
        }
    }
    let mut run = VoRun {
        tracker,
        helpers,
        frames,
        detected,
        next_detect: 0,
        next_track: 0,
        tracking: false,
        over: false,
        on_event: std::rc::Rc::new(on_event),
    };
    run.feed();
    VO_RUN.with(|r| *r.borrow_mut() = Some(run));
    Ok(())
}

impl VoRun {
    /// Gives every idle helper the next frame to detect, and the tracker the
    /// next frame once its keypoints are in.
    fn feed(&mut self) {
        if self.over {
            return;
        }
        for h in 0..self.helpers.len() {
            while self.next_detect < self.frames.len() && self.detected[self.next_detect].is_some() {
                self.next_detect += 1;
            }
            let helper = &self.helpers[h];
            if helper.busy.is_some() || helper.dead || self.next_detect >= self.frames.len() {
                continue;
            }
            let i = self.next_detect;
            self.next_detect += 1;
            self.helpers[h].busy = Some(i);
            self.helpers[h].handle.send(ToWorker::Detect { frame: i as u32, bytes: self.frames[i].clone() });
        }
        if self.tracking || self.next_track >= self.frames.len() {
            return;
        }
        let i = self.next_track;
        let Some(points) = self.detected[i].take() else { return };
        self.next_track += 1;
        self.tracking = true;
        self.tracker.send(ToWorker::VoFrame { id: VO_ID, frame: i as u32, bytes: self.frames[i].clone(), points });
    }

    /// A helper that could not detect its frame (a broken file, or the
    /// helper crashed): the tracker detects that frame itself, so a broken
    /// frame fails there, in frame order after the steps before it, with
    /// the one-worker loop's message.
    fn detect_in_tracker(&mut self, h: usize) {
        if let Some(i) = self.helpers[h].busy.take() {
            self.detected[i] = Some(None);
        }
    }
}

/// A worker of the run crashed: a helper's frame goes to the tracker and
/// the run goes on without it; the tracker's crash ends the run.
fn on_vo_crash(role: Role) {
    let forward = VO_RUN.with(|r| {
        let mut r = r.borrow_mut();
        let run = r.as_mut()?;
        if run.over {
            return None;
        }
        match role {
            Role::Helper(h) => {
                run.helpers[h].dead = true;
                run.detect_in_tracker(h);
                run.feed();
                None
            }
            Role::Tracker => {
                run.over = true;
                let message = "the odometry worker failed (it could not start, or ran out of memory)";
                Some((run.on_event.clone(), FromWorker::Failed { id: VO_ID, message: message.into() }))
            }
        }
    });
    if let Some((on_event, m)) = forward {
        on_event(m);
    }
}

fn on_vo_message(role: Role, m: FromWorker) {
    // Update the run, then call the page's handler outside the borrow (it may
    // start a new run or stop this one).
    let forward = VO_RUN.with(|r| {
        let mut r = r.borrow_mut();
        let run = r.as_mut()?;
        if let FromWorker::Ready = m {
            match role {
                Role::Tracker => run.tracker.set_ready(),
                Role::Helper(h) => run.helpers[h].handle.set_ready(),
            }
            return None;
        }
        if run.over {
            return None;
        }
        let forward = match (&role, &m) {
            (Role::Helper(h), FromWorker::Detected { frame, points }) => {
                run.helpers[*h].busy = None;
                if let Some(d) = run.detected.get_mut(*frame as usize) {
                    *d = Some(Some(points.clone()));
                }
                None
            }
            (Role::Helper(h), FromWorker::Failed { .. }) => {
                run.detect_in_tracker(*h);
                None
            }
            (Role::Tracker, FromWorker::VoStep { .. }) => {
                run.tracking = false;
                Some(m)
            }
            (Role::Tracker, FromWorker::VoMetrics { .. }) => Some(m),
            (_, FromWorker::VoDone { .. }) => {
                run.over = true;
                Some(m)
            }
            (_, FromWorker::Failed { message, .. }) => {
                run.over = true;
                Some(FromWorker::Failed { id: VO_ID, message: message.clone() })
            }
            _ => None,
        };
        run.feed();
        forward.map(|m| (run.on_event.clone(), m))
    });
    if let Some((on_event, m)) = forward {
        on_event(m);
    }
}

/// Stops a running odometry (its workers are terminated).
pub fn stop_vo() {
    // Take it out first: dropping terminates the workers, outside the borrow.
    let old = VO_RUN.with(|r| r.borrow_mut().take());
    drop(old);
}
