//! SIFT exactly as OpenCV 4.8.0 computes it
//! (`cv2.SIFT_create(nfeatures=1500).detectAndCompute(gray, None)`), stage by
//! stage as `docs/fidelity.md` describes it. The pipeline ([`detect`],
//! [`detect_and_compute`]) calls the stages in this order, each handing its
//! output to the next:
//!
//! 1. [`initial`] — float, ×2 bilinear upsample, blur to σ = 1.6 (§SIFT-2)
//! 2. [`pyramid`] — the Gaussian pyramid (§SIFT-4); DoG rows are taken in the scan (§SIFT-5)
//! 3. [`extrema`] — DoG rows, 26-neighbour scan and sub-pixel refinement (§SIFT-5 to §SIFT-7)
//! 4. [`orientation`] — 36-bin orientation histogram peaks (§SIFT-8)
//! 5. [`order`] — dedup, `retainBest` via libstdc++ introselect, rescale (§SIFT-10)
//! 6. [`descriptor`] — 4×4×8 histograms, clipped, scaled to 0..255 (§SIFT-11)
//!
//! [`anatomy`] records what each stage kept and dropped (the app's "see
//! inside" view) through an observer the pipeline takes; the plain path
//! passes `()`, so it costs nothing there.
//!
//! The stages are built from [`blur`] (the bit-exact Gaussian kernel and
//! separable filter, §SIFT-3) and [`num`] (the exact math kernels, §SIFT-12,
//! and the FMA used throughout), and pass [`keypoint`]'s types; [`image`]
//! holds the planes and their buffer pool (the scoped threads are the
//! crate's `par`), and
//! `params` the parameters (§SIFT-1). A stage's module holds the plain
//! algorithm in OpenCV's order and the dispatch; its x86 and wasm kernels
//! live in `x86.rs` and `wasm.rs` beside it.

// The pipeline observed stage by stage (the app's "see inside" view, `siftlab anatomy`).
pub mod anatomy;
pub(crate) mod blur;
pub(crate) mod descriptor;
pub(crate) mod extrema;
pub(crate) mod image;
pub(crate) mod initial;
pub(crate) mod keypoint;
pub(crate) mod lanes;
pub(crate) mod num;
pub(crate) mod observer;
pub(crate) mod order;
pub(crate) mod orientation;

mod params;
mod pipeline;
pub(crate) mod pyramid;

pub use keypoint::{Features, KeyPoint};
pub use num::fma_engine;
pub use params::{host_opencv_lanes, SiftParams};
pub use pipeline::{detect, detect_and_compute};
