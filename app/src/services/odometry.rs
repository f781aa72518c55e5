//! An odometry run on the page: one tracking worker per tracker (the lab's
//! Lucas–Kanade loop, or the loop driven by a strategy's matches), all fed
//! from one SIFT computation per frame. The frames' keypoints and descriptors
//! come from the page's SIFT workers ([`sift_pool::features`]: as many workers as
//! the machine gives, results cached by content and OpenCV build), a few
//! frames ahead of the slowest tracker; each tracker gets frame i only after
//! its step on frame i − 1, so every tracker computes exactly what its
//! one-worker loop (and the CLI) computes, whatever the number of workers.
//! Dropping the run ([`stop`], or a new [`start`]) terminates its trackers.

use crate::protocol::odometry::{Tracker, VoReply, VoRequest};
use crate::protocol::Request;
use crate::services::loading::VoInputs;
use crate::services::sift_pool;
use crate::services::worker_handle::WorkerHandle;
use siftlab_core::sift::Features;
use std::cell::{Cell, RefCell};
use std::rc::Rc;
use std::sync::Arc;

/// The id every tracker's session uses (each tracker is its own worker).
const VO_ID: u32 = 1;

/// A frame's features, as far as the run knows.
enum Slot {
    Pending,
    Ready(Arc<Features>),
    /// The SIFT workers could not compute them (a broken file, a crashed
    /// worker): the trackers get the image and fail, or compute, there, in
    /// frame order with the one-worker loop's message.
    Failed,
    /// Every tracker is past this frame.
    Gone,
}

/// One tracking worker of the run and where it is.
struct Running {
    handle: WorkerHandle,
    tracker: Tracker,
    /// The next frame to send.
    next: usize,
    busy: bool,
    over: bool,
}

struct Run {
    generation: u32,
    frames: Vec<Vec<u8>>,
    slots: Vec<Slot>,
    /// Frames asked of the SIFT workers so far, and how many are pending.
    requested: usize,
    pending: usize,
    trackers: Vec<Running>,
    on_event: Rc<dyn Fn(usize, VoReply)>,
}

thread_local! {
    static RUN: RefCell<Option<Run>> = const { RefCell::new(None) };
    static GENERATION: Cell<u32> = const { Cell::new(0) };
}

/// Frames whose SIFT may be pending at once: two per worker keeps every
/// worker busy between replies.
fn max_pending() -> usize {
    2 * sift_pool::worker_count()
}

/// How far the SIFT may run ahead of the slowest tracker: the features
/// held for the trackers stay within this many frames (0.23 MB each on
/// KITTI) besides the cache.
fn lookahead() -> usize {
    4 * sift_pool::worker_count()
}

/// Starts `trackers` (the lab's LK loop or a strategy's matched loop) side by
/// side on `inputs` (frames, ground truth and camera); `on_event(k, m)` gets
/// tracker k's `VoStep`s, `VoMetrics` and `VoDone`, or its `Failed`. A new
/// run replaces the previous one.
pub fn start(
    inputs: VoInputs,
    trackers: &[Tracker],
    on_event: impl Fn(usize, VoReply) + 'static,
) -> Result<(), String> {
    stop();
    let VoInputs { frames, poses, camera } = inputs;
    let generation = GENERATION.with(|g| {
        g.set(g.get().wrapping_add(1));
        g.get()
    });
    let script = sift_pool::worker_script();
    let total = frames.len() as u32;
    let mut started = Vec::with_capacity(trackers.len());
    for (k, &tracker) in trackers.iter().enumerate() {
        let handle = WorkerHandle::start(
            &script,
            VoReply::from_js,
            move |m| on_tracker_message(generation, k, m),
            move || on_tracker_crash(generation, k),
        )?;
        handle.send(&Request::Odometry(VoRequest::Start { id: VO_ID, total, poses: poses.clone(), camera, tracker }));
        started.push(Running { handle, tracker, next: 0, busy: false, over: false });
    }
    let slots = frames.iter().map(|_| Slot::Pending).collect();
    let run =
        Run { generation, frames, slots, requested: 0, pending: 0, trackers: started, on_event: Rc::new(on_event) };
    RUN.with(|r| *r.borrow_mut() = Some(run));
    feed(generation);
    Ok(())
}

/// Stops the run (its trackers are terminated; SIFT already asked for
/// finishes into the cache, for the next run).
pub fn stop() {
    // Take it out first: dropping terminates the workers, outside the borrow.
    let old = RUN.with(|r| r.borrow_mut().take());
    drop(old);
}

/// Runs `f` on the current run if it is run `generation`.
fn with_run<T>(generation: u32, f: impl FnOnce(&mut Run) -> T) -> Option<T> {
    RUN.with(|r| r.borrow_mut().as_mut().filter(|run| run.generation == generation).map(f))
}

/// Asks for the next frames' features and gives each idle tracker its next
/// frame once that frame's features (or their failure) are in.
fn feed(generation: u32) {
    let asks = with_run(generation, |run| {
        for t in run.trackers.iter_mut().filter(|t| !t.busy && !t.over) {
            let i = t.next;
            if i >= run.frames.len() {
                continue;
            }
            // The LK loop never re-detects on frame 1: it needs no keypoints there.
            let lk_frame_one = t.tracker == Tracker::Lk && i == 1;
            let msg = match (&run.slots[i], &t.tracker) {
                (Slot::Pending, _) if !lk_frame_one => continue,
                (Slot::Ready(f), Tracker::Matched(_)) => {
                    VoRequest::Features { id: VO_ID, frame: i as u32, features: (**f).clone() }
                }
                (Slot::Ready(f), Tracker::Lk) if !lk_frame_one => VoRequest::Frame {
                    id: VO_ID,
                    frame: i as u32,
                    bytes: run.frames[i].clone(),
                    points: Some(f.keypoints.iter().map(|k| [k.x, k.y]).collect()),
                },
                _ => VoRequest::Frame { id: VO_ID, frame: i as u32, bytes: run.frames[i].clone(), points: None },
            };
            t.busy = true;
            t.next += 1;
            t.handle.send(&Request::Odometry(msg));
        }
        // Features no tracker needs any more.
        let slowest = run.trackers.iter().filter(|t| !t.over).map(|t| t.next).min().unwrap_or(run.frames.len());
        for s in run.slots.iter_mut().take(slowest.min(run.frames.len())) {
            *s = Slot::Gone;
        }
        let mut asks = Vec::new();
        while run.requested < run.frames.len()
            && run.pending < max_pending()
            && run.requested < slowest + lookahead()
            && run.trackers.iter().any(|t| !t.over)
        {
            asks.push((run.requested, run.frames[run.requested].clone()));
            run.requested += 1;
            run.pending += 1;
        }
        asks
    });
    // Outside the borrow: a cache hit calls back at once.
    for (i, bytes) in asks.into_iter().flatten() {
        sift_pool::features(bytes, move |r| {
            let fed = with_run(generation, |run| {
                run.pending -= 1;
                if matches!(run.slots[i], Slot::Pending) {
                    run.slots[i] = match r {
                        Ok(res) => Slot::Ready(Arc::new(res.features)),
                        Err(_) => Slot::Failed,
                    };
                }
            });
            if fed.is_some() {
                feed(generation);
            }
        });
    }
}

fn on_tracker_message(generation: u32, k: usize, m: VoReply) {
    // Update the run, then call the page's handler outside the borrow (it may
    // start a new run or stop this one).
    let forward = with_run(generation, |run| {
        let t = &mut run.trackers[k];
        if t.over {
            return None;
        }
        match &m {
            VoReply::Step { .. } => t.busy = false,
            VoReply::Metrics { .. } => {}
            VoReply::Done { .. } | VoReply::Failed { .. } => t.over = true,
        }
        Some(run.on_event.clone())
    })
    .flatten();
    if let Some(on_event) = forward {
        on_event(k, m);
        feed(generation);
    }
}

/// A tracker crashed (out of memory, or it could not start): its run ends
/// with a message; the other trackers go on.
fn on_tracker_crash(generation: u32, k: usize) {
    let forward = with_run(generation, |run| {
        let t = &mut run.trackers[k];
        if t.over {
            return None;
        }
        t.over = true;
        Some(run.on_event.clone())
    })
    .flatten();
    if let Some(on_event) = forward {
        let message = "the odometry worker failed (it could not start, or ran out of memory)";
        on_event(k, VoReply::Failed { id: VO_ID, message: message.into() });
        feed(generation);
    }
}
