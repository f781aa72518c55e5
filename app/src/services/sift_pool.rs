//! The page side of the SIFT workers: a pool sized from the machine's cores
//! ([`worker_count`]), a request queue for the start-up window, and a cache of
//! finished frames keyed by the file's content and the OpenCV build, bounded
//! to [`CACHE_BUDGET`] bytes. The pair's frames and every odometry run's
//! frames ([`features`]) go through it, so a frame's SIFT is computed once.

use crate::model::frame::content_key;
use crate::protocol::sift::{SiftReply, SiftRequest, SiftResult};
use crate::protocol::Request;
use crate::services::worker_handle::WorkerHandle;
use std::cell::RefCell;
use std::collections::HashMap;

type Progress = Box<dyn Fn(String)>;
type Done = Box<dyn FnOnce(Result<SiftResult, String>)>;

struct Waiter {
    progress: Progress,
    done: Done,
}

struct Job {
    key: u64,
    gray: bool,
    slot: usize,
    waiters: Vec<Waiter>,
}

/// A finished frame in the cache, with the tick of its last use.
struct Cached {
    result: SiftResult,
    used: u64,
}

/// What a cached result holds in memory: the gray image (absent for an
/// odometry frame), 20 bytes of keypoint and 128 of descriptor per feature.
fn result_bytes(r: &SiftResult) -> usize {
    r.gray.len() + r.features.keypoints.len() * (std::mem::size_of::<siftlab_core::sift::KeyPoint>() + 128)
}

/// The cache's bound: 128 MB, about 560 odometry frames of KITTI (0.23 MB
/// each: 1500 keypoints and descriptors) or 180 frames of the pair view
/// (0.7 MB with the gray image). The least recently used go first.
pub const CACHE_BUDGET: usize = 128 << 20;

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
    /// Jobs by (content key, with the gray image).
    in_flight: HashMap<(u64, bool), u32>,
    cache: HashMap<u64, Cached>,
    cache_bytes: usize,
    tick: u64,
    /// The largest wasm memory a SIFT worker reported.
    peak_memory: u32,
}

impl Pool {
    fn cache_get(&mut self, key: u64) -> Option<SiftResult> {
        self.tick += 1;
        let tick = self.tick;
        self.cache.get_mut(&key).map(|c| {
            c.used = tick;
            c.result.clone()
        })
    }

    /// Stores `r` (a result with the gray image replaces one without), then
    /// drops the least recently used until the cache is within budget.
    fn cache_put(&mut self, key: u64, r: SiftResult) {
        self.tick += 1;
        if let Some(old) = self.cache.get(&key) {
            if !old.result.gray.is_empty() || r.gray.is_empty() {
                return;
            }
            self.cache_bytes -= result_bytes(&old.result);
        }
        self.cache_bytes += result_bytes(&r);
        self.cache.insert(key, Cached { result: r, used: self.tick });
        while self.cache_bytes > CACHE_BUDGET && self.cache.len() > 1 {
            let Some((&old, _)) = self.cache.iter().min_by_key(|(_, c)| c.used) else { break };
            if let Some(c) = self.cache.remove(&old) {
                self.cache_bytes -= result_bytes(&c.result);
            }
        }
    }
}

thread_local! {
    static POOL: RefCell<Pool> = RefCell::new(Pool {
        script: "./worker.js".into(),
        ..Default::default()
    });
}

thread_local! {
    /// The `workers=N` URL parameter, if given.
    static WORKERS_OVERRIDE: std::cell::Cell<Option<usize>> = const { std::cell::Cell::new(None) };
}

/// Sets the number of SIFT workers (`workers=N`); call before any SIFT runs.
pub fn set_workers(n: Option<usize>) {
    WORKERS_OVERRIDE.with(|w| w.set(n));
}

/// The number of SIFT workers: `workers=N` if given, else from the browser's
/// core count (`parse::default_workers`: cores − 1, 2 to 8).
pub fn worker_count() -> usize {
    WORKERS_OVERRIDE
        .with(|w| w.get())
        .unwrap_or_else(|| crate::model::parse::default_workers(crate::platform::hardware_concurrency()))
}

/// The largest wasm memory (bytes) a SIFT worker of this page has reported.
pub fn worker_memory_peak() -> u32 {
    POOL.with(|p| p.borrow().peak_memory)
}

fn spawn(index: usize, script: &str) -> Result<Slot, String> {
    let handle = WorkerHandle::start(
        script,
        SiftReply::from_js,
        move |m| on_worker_message(index, m),
        move || on_worker_crash(index),
    )?;
    Ok(Slot { handle, load: 0 })
}

fn on_worker_message(_index: usize, m: SiftReply) {
    match m {
        SiftReply::Progress { id, stage } => with_progress(id, &stage),
        SiftReply::Done { id, result } => finish(id, Ok(result)),
        SiftReply::Failed { id, message } => finish(id, Err(message)),
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
        p.in_flight.remove(&(job.key, job.gray));
        if let Some(Some(s)) = p.slots.get_mut(job.slot) {
            s.load = s.load.saturating_sub(1);
        }
        if let Ok(res) = &r {
            p.peak_memory = p.peak_memory.max(res.memory);
            p.cache_put(job.key, res.clone());
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

/// A frame already analysed with these exact bytes, if the cache holds it
/// with its gray image.
pub fn cached(bytes: &[u8], lanes: usize) -> Option<SiftResult> {
    let key = content_key(bytes, lanes);
    POOL.with(|p| p.borrow_mut().cache_get(key)).filter(has_gray)
}

/// The pool's features of `bytes` (from its cache or a worker), awaited:
/// the marking's and the odometry's one way to ask.
pub async fn features_async(bytes: Vec<u8>) -> Result<siftlab_core::sift::Features, String> {
    let (tx, rx) = futures_channel::oneshot::channel();
    features(bytes, move |r| {
        let _ = tx.send(r.map(|r| r.features));
    });
    rx.await.map_err(|_| "the SIFT workers stopped".to_string())?
}

/// Whether `r` can be drawn: an odometry frame's result is cached without
/// its gray image (0.47 MB per KITTI frame), and the page has no image
/// decoder of its own (it stays small), so such a hit goes to a worker again.
fn has_gray(r: &SiftResult) -> bool {
    !r.gray.is_empty() || r.width * r.height == 0
}

/// Runs SIFT on `bytes` in a worker. `done` is called exactly once (immediately
/// on a cache hit); identical requests in flight share one computation.
pub fn sift(
    bytes: Vec<u8>,
    lanes: usize,
    progress: impl Fn(String) + 'static,
    done: impl FnOnce(Result<SiftResult, String>) + 'static,
) {
    request(bytes, lanes, true, Box::new(progress), Box::new(done));
}

/// SIFT's keypoints and descriptors of `bytes` with the host's OpenCV build
/// (`SiftParams::for_host`, what the odometry uses), through the same pool
/// and cache as [`sift`], without the gray image.
pub fn features(bytes: Vec<u8>, done: impl FnOnce(Result<SiftResult, String>) + 'static) {
    request(bytes, siftlab_core::sift::host_opencv_lanes(), false, Box::new(|_| {}), Box::new(done));
}

fn request(bytes: Vec<u8>, lanes: usize, gray: bool, progress: Progress, done: Done) {
    let key = content_key(&bytes, lanes);
    if let Some(hit) = POOL.with(|p| p.borrow_mut().cache_get(key)).filter(|r| !gray || has_gray(r)) {
        done(Ok(hit));
        return;
    }
    let waiter = Waiter { progress, done };
    let failed: Result<(), (String, Waiter)> = POOL.with(|p| {
        let mut p = p.borrow_mut();
        // A features request shares a job that also draws the image; not the reverse.
        let joined = p.in_flight.get(&(key, true)).or(if gray { None } else { p.in_flight.get(&(key, false)) });
        if let Some(id) = joined.copied() {
            if let Some(job) = p.jobs.get_mut(&id) {
                job.waiters.push(waiter);
                return Ok(());
            }
        }
        let workers = worker_count();
        p.slots.resize_with(workers, || None);
        for i in 0..workers {
            if p.slots[i].is_none() {
                let script = p.script.clone();
                match spawn(i, &script) {
                    Ok(s) => p.slots[i] = Some(s),
                    Err(e) => return Err((e, waiter)),
                }
            }
        }
        let load = |s: &Option<Slot>| s.as_ref().map(|s| s.load).unwrap_or(usize::MAX);
        let slot = (0..workers).min_by_key(|&i| load(&p.slots[i])).unwrap_or(0);
        p.next_id = p.next_id.wrapping_add(1);
        let id = p.next_id;
        p.jobs.insert(id, Job { key, gray, slot, waiters: vec![waiter] });
        p.in_flight.insert((key, gray), id);
        if let Some(s) = p.slots[slot].as_mut() {
            s.load += 1;
            let lanes = lanes as u32;
            let req =
                if gray { SiftRequest::Sift { id, bytes, lanes } } else { SiftRequest::Features { id, bytes, lanes } };
            s.handle.send(&Request::Sift(req));
        }
        Ok(())
    });
    if let Err((e, w)) = failed {
        (w.done)(Err(e));
    }
}
