//! `cv2.calcOpticalFlowPyrLK(prev, next, pts, None, winSize=(21,21),
//! criteria=(EPS|COUNT, 30, 0.01))` as OpenCV 4.8 computes it
//! (docs/fidelity.md §VO-2), in its three stages:
//!
//! - `pyramid`: the integer pyramids (`pyrDown`, §VO-2.2) and the unscaled
//!   Scharr derivatives of the previous image (§VO-2.3);
//! - `window`: one point's 21×21 fixed-point windows at one level, the
//!   structure tensor and the mismatch vector with the f32 accumulation
//!   orders of OpenCV's 128-bit SIMD loops (§VO-2.4);
//! - `tracking`: the per-point iteration from the coarsest level to the
//!   finest, status and error (§VO-2.4, §VO-2.5), and the public calls.
//!
//! All of this is baseline code in OpenCV (no FMA), so every f32 operation
//! rounds separately. Each stage holds the plain scalar version in OpenCV's
//! order and the dispatch; its x86 (AVX2, AVX-512) and wasm (simd128)
//! kernels sit in submodules beside it and give the same bits.

mod pyramid;
#[cfg(test)]
mod tests;
mod tracking;
mod window;

pub use pyramid::Pyramid;
pub use tracking::{calc_optical_flow_pyr_lk, calc_optical_flow_pyr_lk_portable, calc_optical_flow_pyr_lk_pyramids};

/// Window side (21×21); the lab never changes it.
pub const WIN: usize = 21;
/// `FLT_SCALE = 1.f / (1 << 20)`.
const FLT_SCALE: f32 = 1.0 / (1u32 << 20) as f32;

/// The tracker's parameters as `calcOpticalFlowPyrLK` effectively uses them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LkParams {
    /// Requested pyramid depth (may be lowered by the size rule).
    pub max_level: usize,
    /// Iteration cap (`criteria.maxCount`, clamped to [0, 100]).
    pub max_count: usize,
    /// `criteria.epsilon` before squaring (clamped to [0, 10]).
    pub epsilon: f64,
    /// `minEigThreshold`.
    pub min_eig_threshold: f64,
}

impl Default for LkParams {
    /// The lab's call: maxLevel 3, 30 iterations / 0.01, minEigThreshold 1e-4.
    fn default() -> Self {
        LkParams { max_level: 3, max_count: 30, epsilon: 0.01, min_eig_threshold: 1e-4 }
    }
}

/// Output of [`calc_optical_flow_pyr_lk`], one entry per input point.
#[derive(Clone, Debug, PartialEq)]
pub struct LkResult {
    pub next_pts: Vec<[f32; 2]>,
    pub status: Vec<bool>,
    /// Mean absolute difference (8-bit units) for status-1 points; for a
    /// status-0 point OpenCV leaves uninitialized memory, here it is 0.
    pub err: Vec<f32>,
}
