//! An odometry run on the page: one tracking worker per tracker (the lab's
//! Lucas–Kanade loop, or the loop driven by a strategy's matches), all fed
//! from one SIFT computation per frame. The frames' keypoints and descriptors
//! come from the page's SIFT workers ([`sift_pool::features`]: as many workers as
//! the machine gives, results cached by content and OpenCV build), a few
//! frames ahead of the slowest tracker; each tracker gets frame i only after
//! its step on frame i − 1, so every tracker computes exactly what its
//! one-worker loop (and the CLI) computes, whatever the number of workers.
//! Frames are read from their source (the demo's files, a folder's `File`s)
//! as the SIFT reaches them and dropped once every tracker is past them, so
//! a run's memory does not grow with its length; [`replay`] recomputes what
//! the run did with an old frame in its tracker's worker.
//! Dropping the run ([`stop`], or a new [`start`]) terminates its trackers.

use crate::protocol::odometry::{Tracker, VoReply, VoRequest};
use crate::protocol::Request;
use crate::services::sift_pool;
use crate::services::sources::{frame_path, FrameSource, VoInputs};
use crate::services::worker_handle::WorkerHandle;
use siftlab_core::sift::Features;
use siftlab_core::vo::StepDetail;
use std::cell::{Cell, RefCell};
use std::collections::HashMap;
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

/// What a [`replay`] gets: the frame's points, `None` where the run recorded none.
pub type Replayed = Result<Option<Box<StepDetail>>, String>;

struct Run {
    generation: u32,
    source: FrameSource,
    /// Frame 0's size (PNG header): every later frame must have it.
    size: Option<(u32, u32)>,
    /// The files of the frames between the slowest tracker and the SIFT's
    /// look-ahead; `None` before they are read and after every tracker used them.
    bytes: Vec<Option<Rc<Vec<u8>>>>,
    slots: Vec<Slot>,
    /// Frames below this are `Gone` and their files dropped.
    released: usize,
    /// Frames asked of the SIFT workers so far, and how many are pending.
    requested: usize,
    pending: usize,
    trackers: Vec<Running>,
    on_event: Rc<dyn Fn(usize, VoReply)>,
    /// Replays asked of the trackers, by token.
    replays: HashMap<u32, Box<dyn FnOnce(Replayed)>>,
}

thread_local! {
    static RUN: RefCell<Option<Run>> = const { RefCell::new(None) };
    static GENERATION: Cell<u32> = const { Cell::new(0) };
    /// The last replay's token.
    static TOKEN: Cell<u32> = const { Cell::new(0) };
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
/// run replaces the previous one. Returns the run's generation, which
/// [`replay`] names it by.
pub fn start(
    inputs: VoInputs,
    trackers: &[Tracker],
    on_event: impl Fn(usize, VoReply) + 'static,
) -> Result<u32, String> {
    stop();
    let VoInputs { frames: source, poses, camera, size } = inputs;
    let generation = GENERATION.with(|g| {
        g.set(g.get().wrapping_add(1));
        g.get()
    });
    let script = sift_pool::worker_script();
    let total = source.frame_count() as u32;
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
    let n = source.frame_count();
    let run = Run {
        generation,
        source,
        size,
        bytes: vec![None; n],
        slots: (0..n).map(|_| Slot::Pending).collect(),
        released: 0,
        requested: 0,
        pending: 0,
        trackers: started,
        on_event: Rc::new(on_event),
        replays: HashMap::new(),
    };
    RUN.with(|r| *r.borrow_mut() = Some(run));
    feed(generation);
    Ok(generation)
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

/// Asks for the next frames' features (reading their files first) and gives
/// each idle tracker its next frame once that frame's features (or their
/// failure) are in.
fn feed(generation: u32) {
    let asks = with_run(generation, |run| {
        let n = run.slots.len();
        for t in run.trackers.iter_mut().filter(|t| !t.busy && !t.over) {
            let i = t.next;
            if i >= n {
                continue;
            }
            let Some(bytes) = run.bytes[i].clone() else { continue };
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
                    bytes: bytes.to_vec(),
                    points: Some(f.keypoints.iter().map(|k| [k.x, k.y]).collect()),
                },
                _ => VoRequest::Frame { id: VO_ID, frame: i as u32, bytes: bytes.to_vec(), points: None },
            };
            t.busy = true;
            t.next += 1;
            t.handle.send(&Request::Odometry(msg));
        }
        // Files and features no tracker needs any more.
        let slowest = run.trackers.iter().filter(|t| !t.over).map(|t| t.next).min().unwrap_or(n);
        // From where the last call stopped: a long run calls this a few times a frame.
        for i in run.released..slowest.min(n) {
            run.slots[i] = Slot::Gone;
            run.bytes[i] = None;
        }
        run.released = run.released.max(slowest.min(n));
        let mut asks = Vec::new();
        while run.requested < n
            && run.pending < max_pending()
            && run.requested < slowest + lookahead()
            && run.trackers.iter().any(|t| !t.over)
        {
            asks.push(run.requested);
            run.requested += 1;
            run.pending += 1;
        }
        (run.source.clone(), asks)
    });
    let Some((source, asks)) = asks else { return };
    for i in asks {
        let source = source.clone();
        leptos::task::spawn_local(async move {
            let bytes = source.bytes(i).await;
            let bytes = match bytes.and_then(|b| with_run(generation, |run| check_size(run, i, b)).transpose()) {
                Ok(Some(b)) => b,
                Ok(None) => return, // the run is gone
                Err(message) => return fail(generation, message),
            };
            // Outside the borrow: a cache hit calls back at once.
            sift_pool::features(bytes.to_vec(), move |r| {
                let fed = with_run(generation, |run| {
                    run.pending -= 1;
                    if matches!(run.slots[i], Slot::Pending) {
                        run.bytes[i] = Some(bytes);
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
        });
    }
}

/// Frame `i`'s file, if it has frame 0's size (PNG frames; other formats
/// are checked when the tracker decodes them), as the CLI checks a folder.
fn check_size(run: &Run, i: usize, bytes: Vec<u8>) -> Result<Rc<Vec<u8>>, String> {
    let size = crate::model::odometry::frame::png_size(&bytes);
    if let (Some(first), Some(size)) = (run.size, size) {
        if first != size {
            let wh = |(w, h): (u32, u32)| (w as usize, h as usize);
            let path = frame_path(i as u32);
            return Err(siftlab_core::dataset::frame_size_error(&path, i, wh(size), 0, wh(first)).to_string());
        }
    }
    Ok(Rc::new(bytes))
}

/// A frame could not be read: every tracker still going ends with `message`.
fn fail(generation: u32, message: String) {
    let ended = with_run(generation, |run| {
        let ended: Vec<usize> = (0..run.trackers.len()).filter(|&k| !run.trackers[k].over).collect();
        for &k in &ended {
            run.trackers[k].over = true;
        }
        (ended, run.on_event.clone())
    });
    if let Some((ended, on_event)) = ended {
        for k in ended {
            on_event(k, VoReply::Failed { id: VO_ID, message: message.clone() });
        }
    }
}

/// Recomputes what tracker `k` of run `generation` did with frame `frame`
/// (its points and masks, which the page keeps for the newest frame only) in
/// that tracker's worker: for LK from `from`, the last frame the loop
/// detected on (frame 0, or the last before `frame` whose step re-detected),
/// reading the files `from` … `frame` again; `redetected`: whether the loop
/// re-detected on `frame`. A matched run needs frames `frame − 1` and `frame`.
pub fn replay(
    generation: u32,
    k: usize,
    frame: usize,
    from: usize,
    redetected: bool,
    done: impl FnOnce(Replayed) + 'static,
) {
    let Some((source, tracker)) =
        with_run(generation, |run| (run.source.clone(), run.trackers.get(k).map(|t| t.tracker)))
    else {
        return done(Err("another run replaced this one: run the odometry again to see its frames".into()));
    };
    let Some(tracker) = tracker else { return done(Err(format!("the run has no tracker {k}"))) };
    let token = TOKEN.with(|t| {
        t.set(t.get().wrapping_add(1));
        t.get()
    });
    leptos::task::spawn_local(async move {
        let request = match replay_request(&source, tracker, token, frame, from, redetected).await {
            Ok(r) => r,
            Err(e) => return done(Err(e)),
        };
        let mut done = Some(done);
        with_run(generation, |run| {
            if let Some(d) = done.take() {
                run.replays.insert(token, Box::new(d));
            }
            run.trackers[k].handle.send(&Request::Odometry(request));
        });
        // The run ended while the files were read.
        if let Some(d) = done {
            d(Err("another run replaced this one: run the odometry again to see its frames".into()));
        }
    });
}

/// The files and features a [`VoRequest::Replay`] of `frame` carries.
async fn replay_request(
    source: &FrameSource,
    tracker: Tracker,
    token: u32,
    frame: usize,
    from: usize,
    redetected: bool,
) -> Result<VoRequest, String> {
    let points = |f: &Features| f.keypoints.iter().map(|k| [k.x, k.y]).collect::<Vec<_>>();
    let request = |frames, refs, detected, features| VoRequest::Replay {
        token,
        from: from as u32,
        frame: frame as u32,
        frames,
        refs,
        detected,
        features,
    };
    if let Tracker::Matched(_) = tracker {
        if frame == 0 {
            return Ok(request(Vec::new(), Vec::new(), None, Vec::new()));
        }
        let prev = sift_pool::features_async(source.bytes(frame - 1).await?).await?;
        let cur = sift_pool::features_async(source.bytes(frame).await?).await?;
        return Ok(request(Vec::new(), Vec::new(), None, vec![prev, cur]));
    }
    let mut frames = Vec::with_capacity(frame + 1 - from);
    for i in from..=frame {
        frames.push(source.bytes(i).await?);
    }
    let refs = points(&sift_pool::features_async(frames[0].clone()).await?);
    let detected = match (redetected && frame > from, frames.last()) {
        (true, Some(last)) => Some(points(&sift_pool::features_async(last.clone()).await?)),
        _ => None,
    };
    Ok(request(frames, refs, detected, Vec::new()))
}

fn on_tracker_message(generation: u32, k: usize, m: VoReply) {
    if let VoReply::Replayed { token, detail, .. } = m {
        if let Some(done) = with_run(generation, |run| run.replays.remove(&token)).flatten() {
            done(detail);
        }
        return;
    }
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
            VoReply::Replayed { .. } => {}
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
