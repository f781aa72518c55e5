//! The descriptor's histogram layout and the per-sample rows, shared by the
//! plain code and the vector kernel beside it.

// §SIFT-1: 4×4 cells of 8 bins.
pub(in crate::sift) const D: usize = 4; // SIFT_DESCR_WIDTH
pub(in crate::sift) const N: usize = 8; // SIFT_DESCR_HIST_BINS

pub(in crate::sift) const BINS_PER_DEG: f32 = N as f32 / 360.0;
pub(in crate::sift) const HIST_LEN: usize = (D + 2) * (D + 2) * (N + 2);

/// The gradient samples inside the descriptor window, in OpenCV's order
/// (row by row, left to right): pixel differences, the Gaussian weight's
/// exponent and the (row, column) bin coordinates.
#[derive(Default)]
pub(in crate::sift) struct Samples {
    pub(in crate::sift) dx: Vec<f32>,
    pub(in crate::sift) dy: Vec<f32>,
    pub(in crate::sift) w: Vec<f32>,
    pub(in crate::sift) rbin: Vec<f32>,
    pub(in crate::sift) cbin: Vec<f32>,
}

/// Per-sample inputs of the histogram loop.
pub(in crate::sift) struct Rows<'a> {
    pub(in crate::sift) rbin: &'a [f32],
    pub(in crate::sift) cbin: &'a [f32],
    pub(in crate::sift) ori: &'a [f32],
    pub(in crate::sift) mag: &'a [f32],
    pub(in crate::sift) wt: &'a [f32],
}

/// Offsets of the (r, c) = 00, 01, 10, 11 cells' "0" orientation bin.
#[inline(always)]
pub(in crate::sift) fn cell_offsets() -> [usize; 4] {
    let n2 = N + 2;
    [0, n2, (D + 2) * n2, (D + 2) * n2 + n2]
}
