//! Component tests in headless Chromium (wasm-bindgen-test): the explorer
//! mounted on OpenCV's own SIFT output for the bundled KITTI frames
//! (`tests/fixtures/golden-avx2/ipp/*.sift`, OpenCV 8 lanes wide as the app
//! runs by default) must show exactly what OpenCV's lab code printed for the
//! same settings (`tests/fixtures/golden-avx2/get_info.jsonl`), and the
//! controls, click-to-select, keyboard, errors, URL state, self-check and the
//! odometry's frame control must behave. SIFT itself is not run here (the
//! core's wasm tests check it against the same goldens; `manual.rs` runs it for
//! the lab manual's examples); the e2e test runs the real worker.
//!
//! One test binary, its tests grouped by what they test: `explorer` (the page's
//! components, URL state and odometry control), `protocol` (the worker messages),
//! `worker_odometry` (the odometry worker's loops); `fixtures` holds the goldens
//! and frames they share.
#![cfg(target_arch = "wasm32")]

mod explorer;
mod fixtures;
mod protocol;
mod worker_odometry;

use wasm_bindgen_test::*;

wasm_bindgen_test_configure!(run_in_browser);
