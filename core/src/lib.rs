//! siftlab-core: the COMP24011 feature-matching lab, reproduced in pure Rust.
//!
//! Every lab rule lives here once (see `docs/architecture.md`):
//! SIFT exactly as OpenCV 4.8.0 computes it ([`sift`]), the brute-force
//! matcher and the dt / nn / nndr strategies with `matching_info`
//! ([`matching`]), the lab's monocular visual odometry ([`vo`]) and the images
//! the lab's commands draw ([`render`]). The CLI and the web app only load
//! input, call this crate and show what it returns.

mod border;
#[cfg(all(feature = "cli", not(target_arch = "wasm32")))]
pub mod cli;
pub mod dataset;
pub mod error;
mod gray_png;
pub mod image;
pub mod manual;
pub mod matching;
pub mod pyfmt;
pub mod render;
pub mod sift;
pub mod simd;
#[cfg(test)]
mod testutil;
pub mod vo;

pub use error::{Error, Result};
pub use image::GrayImage;
