//! siftlab-app: the COMP24011 matching lab in the browser (leptos CSR).
//!
//! The page loads two frames, runs SIFT on them in web workers and shows, for
//! one feature and one strategy, every step the lab's `get_info` takes; it
//! runs the lab's odometry and shows SIFT's anatomy. All lab rules — SIFT, the
//! strategies, validation, `matching_info` and its Python formatting — are
//! the core's; this crate only loads input, calls `siftlab_core` and draws
//! what it returns. Its folders, from the bottom up (each imports only below):
//!
//! - [`protocol`]: the messages between the page and its workers, one codec;
//! - [`platform`]: what the crate takes from the JavaScript platform;
//! - [`model`]: the page's state and plain logic, no DOM;
//! - [`worker`]: what runs inside a Web Worker;
//! - [`services`]: the page side of the workers and of file I/O;
//! - [`page`]: the leptos components, in the order of the page.

// The page's layers need leptos (the `page` feature, on by default); the worker's build
// compiles only protocol, platform and worker.
#[cfg(feature = "page")]
pub mod model;
#[cfg(feature = "page")]
pub mod page;
pub mod platform;
pub mod protocol;
#[cfg(feature = "page")]
pub mod services;
pub mod worker;

#[cfg(feature = "page")]
pub use page::App;

/// Panics go to the console (and fail the e2e test's console check) instead of
/// vanishing into an `unreachable` trap.
pub fn install_panic_hook() {
    std::panic::set_hook(Box::new(|info| {
        web_sys::console::error_1(&format!("siftlab panicked: {info}").into());
    }));
}
