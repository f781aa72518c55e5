//! siftlab-core: the COMP24011 feature-matching lab, reproduced in pure Rust.
//!
//! Every lab rule lives here once (see `docs/architecture.md`):
//! SIFT exactly as OpenCV 4.8.0 computes it ([`sift`]), the brute-force
//! matcher and the dt / nn / nndr strategies with `matching_info`
//! ([`matching`]), the lab's monocular visual odometry ([`vo`]) and the images
//! the lab's commands draw ([`render`]). The CLI and the web app only load
//! input, call this crate and show what it returns.

// Every unsafe operation sits in its own block with the reason it is sound.
#![deny(unsafe_op_in_unsafe_fn)]
#![deny(clippy::undocumented_unsafe_blocks)]

mod border;
mod camera;
pub mod dataset;
pub mod error;
mod gray_png;
pub mod image;
pub mod json;
pub mod manual;
pub mod matching;
mod par;
pub mod pyfmt;
pub mod render;
pub mod rng;
pub mod sift;
pub mod simd;
#[cfg(test)]
mod testutil;
pub mod vo;

pub use error::{Error, Result};

/// The stage kernels, exposed for the benches (`core/benches`), the SIMD-level
/// tests and the browser oracle tests, which time or check one stage alone.
/// Not part of the API: the CLI and the app use the re-exports above.
#[doc(hidden)]
pub mod internals {
    pub use crate::par::{serial, with_threads};
    pub use crate::sift::blur::{gaussian_blur, gaussian_kernel};
    pub use crate::sift::image::Plane;
    pub use crate::sift::initial::initial_image;
    pub use crate::sift::pyramid::level_sigmas;
    pub use crate::simd::set_cap;
    pub use crate::vo::lk::calc_optical_flow_pyr_lk_portable;

    /// The exact math kernels (docs/fidelity.md §SIFT-12) and the FMA.
    pub mod num {
        #[cfg(target_arch = "wasm32")]
        pub use crate::sift::num::fma_emulated_x4;
        #[cfg(all(target_arch = "wasm32", feature = "relaxed-simd"))]
        pub use crate::sift::num::relaxed_madd_is_fused;
        pub use crate::sift::num::{
            exp32f, fast_atan2_deg, fma, fma_emulated, fma_engine, gradient_directions, gradient_samples, magnitude,
        };
    }
}
pub use image::GrayImage;
