//! What the pipeline reports to an observer as it runs: each scan extremum,
//! each refinement drop and its reason, the oriented and deduplicated
//! keypoints. The anatomy records them; the plain path passes `()`. Its own
//! module so that the pipeline's stages need not import the anatomy, which
//! imports them.

use super::keypoint::{KeyPoint, Refined};

/// Why the refinement (§SIFT-7) dropped a scan extremum.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Rejection {
    /// Five Newton steps without the offset falling under half a pixel (or a
    /// step so large the solve diverged).
    NoConvergence,
    /// A step moved it within 5 pixels of the border or out of layers 1..=3.
    LeftScaleSpace,
    /// |D(x̂)| · layers below the contrast threshold (0.04).
    LowContrast,
    /// Principal curvature ratio ≥ 10 (or a saddle): an edge, not a blob.
    EdgeLike,
}

impl Rejection {
    pub const ALL: [Rejection; 4] =
        [Rejection::NoConvergence, Rejection::LeftScaleSpace, Rejection::LowContrast, Rejection::EdgeLike];

    /// The key used in JSON and the app.
    pub fn name(self) -> &'static str {
        match self {
            Rejection::NoConvergence => "no_convergence",
            Rejection::LeftScaleSpace => "left_border",
            Rejection::LowContrast => "low_contrast",
            Rejection::EdgeLike => "edge_like",
        }
    }
}

/// What the pipeline tells an observer. Every method has an empty default,
/// so `()` observes nothing and costs nothing.
pub trait Observer: Sync {
    /// A scan extremum of octave `o` (0 = the doubled base), DoG layer
    /// `layer`, at octave pixel (r, c).
    #[inline(always)]
    fn extremum(&self, _o: usize, _layer: usize, _r: usize, _c: usize) {}
    /// The refinement dropped that extremum, for `why`.
    #[inline(always)]
    fn rejected(&self, _o: usize, _layer: usize, _r: usize, _c: usize, _why: Rejection) {}
    /// An extremum passed the refinement.
    #[inline(always)]
    fn refined(&self, _r: &Refined) {}
    /// All oriented keypoints, before duplicates are removed (doubled-base coordinates).
    #[inline(always)]
    fn oriented(&self, _kps: &[KeyPoint]) {}
    /// The keypoints once duplicates are removed (doubled-base coordinates).
    #[inline(always)]
    fn deduplicated(&self, _kps: &[KeyPoint]) {}
}

impl Observer for () {}
