//! The "see inside" worker: one worker of its own for the anatomy and the
//! whole-frame sweep, so neither waits behind (or holds up) the SIFT pool or
//! an odometry run. A new request while one runs replaces it: the old
//! worker is terminated and its late answer can never arrive.

use crate::protocol::inside::{AnatomyData, InsideReply, InsideRequest, SweepData};
use crate::protocol::Request;
use crate::services::sift_pool::worker_script;
use crate::services::worker_handle::WorkerHandle;
use siftlab_core::dataset::PoseRow;
use siftlab_core::sift::Features;
use std::cell::RefCell;
use std::rc::Rc;

/// The job waiting for its answer: its progress callback and what to do
/// with the final reply (taken once).
struct Waiting {
    progress: Box<dyn Fn(String)>,
    done: Option<Box<dyn FnOnce(InsideReply)>>,
}

type Listener = Rc<RefCell<Option<Waiting>>>;

struct Inside {
    handle: WorkerHandle,
    listener: Listener,
}

thread_local! {
    static INSIDE: RefCell<Option<Inside>> = const { RefCell::new(None) };
}

fn start() -> Result<Inside, String> {
    let listener: Listener = Rc::new(RefCell::new(None));
    let (l, l2) = (listener.clone(), listener.clone());
    let handle = WorkerHandle::start(
        &worker_script(),
        InsideReply::from_js,
        move |m| {
            if let InsideReply::Progress { stage, .. } = &m {
                if let Some(w) = l.borrow().as_ref() {
                    (w.progress)(stage.clone());
                }
                return;
            }
            // Taken out before the call: `done` may start the next job.
            let done = l.borrow_mut().as_mut().and_then(|w| w.done.take());
            if let Some(done) = done {
                done(m);
            }
        },
        move || {
            let done = l2.borrow_mut().as_mut().and_then(|w| w.done.take());
            if let Some(done) = done {
                done(InsideReply::Failed { id: 0, message: "the worker failed (out of memory?); try again".into() });
            }
        },
    )?;
    Ok(Inside { handle, listener })
}

/// Sends `req`; `progress` gets its stages, `done` its final reply.
fn run(
    req: InsideRequest,
    progress: impl Fn(String) + 'static,
    done: impl FnOnce(InsideReply) + 'static,
) -> Result<(), String> {
    INSIDE.with(|cell| {
        let mut cell = cell.borrow_mut();
        if cell.as_ref().is_some_and(|i| i.listener.borrow().as_ref().is_some_and(|w| w.done.is_some())) {
            // Busy with an older request: drop it (terminates the worker).
            *cell = None;
        }
        if cell.is_none() {
            *cell = Some(start()?);
        }
        let inside = cell.as_ref().ok_or("no worker")?;
        *inside.listener.borrow_mut() = Some(Waiting { progress: Box::new(progress), done: Some(Box::new(done)) });
        inside.handle.send(&Request::Inside(req));
        Ok(())
    })
}

/// SIFT's anatomy of the image `bytes` at OpenCV SIMD width `lanes`.
pub fn anatomy(
    bytes: Vec<u8>,
    lanes: u32,
    progress: impl Fn(String) + 'static,
    done: impl FnOnce(Result<Box<AnatomyData>, String>) + 'static,
) -> Result<(), String> {
    run(InsideRequest::Anatomy { id: 1, bytes, lanes }, progress, move |m| {
        done(match m {
            InsideReply::Anatomy { data, .. } => Ok(data),
            InsideReply::Failed { message, .. } => Err(message),
            InsideReply::Progress { .. } | InsideReply::WholeFrame { .. } => {
                Err("the worker answered another job".into())
            }
        })
    })
}

/// The threshold sweep of `prev` against `cur`, judged by the poses'
/// epipolar geometry (seen by `camera`) within `px` pixels when the poses are known.
pub fn sweep(
    prev: Features,
    cur: Features,
    poses: Option<Box<[PoseRow; 2]>>,
    camera: siftlab_core::vo::Camera,
    px: f64,
    progress: impl Fn(String) + 'static,
    done: impl FnOnce(Result<Box<SweepData>, String>) + 'static,
) -> Result<(), String> {
    run(InsideRequest::WholeFrame { id: 1, prev, cur, poses, camera, px }, progress, move |m| {
        done(match m {
            InsideReply::WholeFrame { data, .. } => Ok(data),
            InsideReply::Failed { message, .. } => Err(message),
            InsideReply::Progress { .. } | InsideReply::Anatomy { .. } => Err("the worker answered another job".into()),
        })
    })
}
