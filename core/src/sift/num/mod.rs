//! The exact math OpenCV's SIFT is built from (docs/fidelity.md §SIFT-12),
//! and the one fused multiply-add every stage uses (§SIFT-0, §SIFT-15):
//!
//! - [`fma`](fma()) — the FMA, its exact WebAssembly emulation and the relaxed-SIMD probe
//!   (`fma.rs`, with the `with_hw_fma!` macro);
//! - [`fast_atan2_deg`] — OpenCV's `fastAtan2` (`atan.rs`);
//! - [`exp32f`] — OpenCV's `exp32f` without IPP (`exp.rs`);
//! - [`pow2f`] — glibc's `powf(2, y)` for the keypoint size (`pow.rs`);
//! - [`gradient_samples`] — the three run over whole sample arrays, with
//!   [`magnitude`], as OpenCV's `hal` calls do (`gradient.rs`);
//!
//! and the vector kernels beside them: `x86.rs` (`exp32f` in AVX2 lanes) and
//! `wasm.rs` (`fastAtan2`, magnitude and `exp32f` in SIMD128 lanes).

mod atan;
mod exp;
mod fma;
mod gradient;
mod pow;
#[cfg(target_arch = "wasm32")]
pub(crate) mod wasm;
#[cfg(target_arch = "x86_64")]
mod x86;

pub use atan::fast_atan2_deg;
pub use exp::exp32f;
#[cfg(target_arch = "wasm32")]
pub use fma::fma_emulated_x4;
#[cfg(all(target_arch = "wasm32", feature = "relaxed-simd"))]
pub use fma::relaxed_madd_is_fused;
pub use fma::{fma, fma_emulated, fma_engine};
pub use gradient::{exp32f_into, gradient_directions, gradient_directions_into, gradient_samples, magnitude};
pub use pow::pow2f;
#[cfg(target_arch = "wasm32")]
pub(crate) use wasm::{load4, store4};

/// `cvRound` on floats: `lrintf` in the default rounding mode.
#[inline(always)]
pub fn rne(x: f32) -> i32 {
    x.round_ties_even() as i32
}

/// `cvRound` on doubles.
#[inline(always)]
pub fn rne64(x: f64) -> i32 {
    x.round_ties_even() as i32
}

/// `cvFloor`.
#[inline(always)]
pub fn floor(x: f32) -> i32 {
    x.floor() as i32
}

pub const FLT_EPSILON: f32 = f32::EPSILON;
