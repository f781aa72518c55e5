//! The "see inside" worker: one worker of its own for the anatomy and the
//! whole-frame sweep, so neither waits behind (or holds up) the SIFT pool or
//! an odometry run. A new request while one runs replaces it: the old
//! worker is terminated and its late answer can never arrive.

use crate::client::{worker_script, WorkerHandle};
use crate::msg::{FromWorker, ToWorker};
use crate::msg_inside::InsideRequest;
use std::cell::RefCell;
use std::rc::Rc;

type Listener = Rc<RefCell<Option<Box<dyn Fn(FromWorker)>>>>;

struct Inside {
    handle: Rc<RefCell<Option<WorkerHandle>>>,
    busy: Rc<RefCell<bool>>,
    listener: Listener,
}

thread_local! {
    static INSIDE: RefCell<Option<Inside>> = const { RefCell::new(None) };
}

fn start() -> Result<Inside, String> {
    let listener: Listener = Rc::new(RefCell::new(None));
    let busy = Rc::new(RefCell::new(false));
    let handle: Rc<RefCell<Option<WorkerHandle>>> = Rc::new(RefCell::new(None));
    let (l, b, h) = (listener.clone(), busy.clone(), handle.clone());
    let (l2, b2) = (listener.clone(), busy.clone());
    let w = WorkerHandle::start(
        &worker_script(),
        move |m| {
            if let FromWorker::Ready = m {
                if let Some(w) = h.borrow_mut().as_mut() {
                    w.set_ready();
                }
                return;
            }
            if matches!(m, FromWorker::Inside(_) | FromWorker::Failed { .. }) {
                *b.borrow_mut() = false;
            }
            if let Some(f) = l.borrow().as_ref() {
                f(m);
            }
        },
        move || {
            *b2.borrow_mut() = false;
            if let Some(f) = l2.borrow().as_ref() {
                f(FromWorker::Failed { id: 0, message: "the worker failed (out of memory?); try again".into() });
            }
        },
    )?;
    *handle.borrow_mut() = Some(w);
    Ok(Inside { handle, busy, listener })
}

/// Sends `req` to the "see inside" worker; `on_event` gets its `Progress`,
/// then its `Inside` reply or `Failed`.
pub fn run(req: InsideRequest, on_event: impl Fn(FromWorker) + 'static) -> Result<(), String> {
    INSIDE.with(|cell| {
        let mut cell = cell.borrow_mut();
        if cell.as_ref().is_some_and(|i| *i.busy.borrow()) {
            // Busy with an older request: drop it (terminates the worker).
            *cell = None;
        }
        if cell.is_none() {
            *cell = Some(start()?);
        }
        let inside = cell.as_ref().ok_or("no worker")?;
        *inside.listener.borrow_mut() = Some(Box::new(on_event));
        *inside.busy.borrow_mut() = true;
        if let Some(w) = inside.handle.borrow_mut().as_mut() {
            w.send(ToWorker::Inside(req));
        }
        Ok(())
    })
}
