//! The matcher of the "Mark my code" worker (`www/mark-worker.js`): the
//! student's `BFMatcher().knnMatch` reaches siftlab's k-NN here. The worker
//! hands over each pair the page sends ([`mark_host_pair`]) and each knn
//! request of the Python harness ([`mark_host_knn`], docs/marking.md).

use crate::protocol::mark::get_pair;
use siftlab_mark::{knn_answer, Pair};
use std::cell::RefCell;
use wasm_bindgen::prelude::*;

thread_local! {
    /// The pairs sent so far, by id (the worker marks one file at a time).
    static PAIRS: RefCell<Vec<Pair>> = const { RefCell::new(Vec::new()) };
}

/// Keeps the pair of a `pair` message (see `protocol::mark`).
#[wasm_bindgen]
pub fn mark_host_pair(message: JsValue) -> Result<(), JsValue> {
    let pair = get_pair(&message).map_err(|e| JsValue::from_str(&e))?;
    PAIRS.with(|p| {
        let mut p = p.borrow_mut();
        p.retain(|q| q.id != pair.id);
        p.push(pair);
    });
    Ok(())
}

/// Answers one knn request line of the harness with siftlab's matcher.
#[wasm_bindgen]
pub fn mark_host_knn(request: &str) -> String {
    PAIRS.with(|p| knn_answer(request, &p.borrow()))
}
