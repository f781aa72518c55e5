//! The orientation histogram's size, shared by the plain code and its AVX2 kernel.

// §SIFT-1: 36 bins.
pub(super) const ORI_HIST_BINS: usize = 36;
