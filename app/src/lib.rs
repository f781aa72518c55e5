//! siftlab-app: the COMP24011 matching lab in the browser (leptos CSR).
//!
//! The page loads two frames, runs SIFT on them in web workers ([`client`],
//! [`worker`]) and shows, for one feature and one strategy, every step the
//! lab's `get_info` takes. All lab rules — SIFT, the strategies, validation,
//! `matching_info` and its Python formatting — are the core's; this crate
//! only loads input, calls `siftlab_core` and draws what it returns.

pub mod client;
pub mod codec;
pub mod components;
pub mod exercise;
pub mod frameset;
pub mod inside;
pub mod jobs;
pub mod lab_manual;
pub mod loading;
pub mod msg;
pub mod msg_inside;
pub mod parse;
pub mod platform;
pub mod plot;
pub mod pylit;
pub mod seeinside;
pub mod selfcheck;
pub mod state;
pub mod urlstate;
pub mod vo_run;
pub mod vo_view;
pub mod worker;

pub use components::App;

/// Panics go to the console (and fail the e2e test's console check) instead of
/// vanishing into an `unreachable` trap.
pub fn install_panic_hook() {
    std::panic::set_hook(Box::new(|info| {
        web_sys::console::error_1(&format!("siftlab panicked: {info}").into());
    }));
}
