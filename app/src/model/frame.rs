//! One analysed frame as the page keeps it, and the key its SIFT is cached by.

use crate::protocol::sift::SiftResult;
use std::sync::Arc;

/// One analysed frame: the gray image SIFT saw and its features.
#[derive(Debug, Clone, PartialEq)]
pub struct FrameData {
    /// What the user loaded (file name or `gray/00/image_0/000001.png`).
    pub label: String,
    /// The worker's result (its fields read through `Deref`: `frame.features`, `frame.gray`, …).
    pub sift: SiftResult,
    /// The file's bytes, to re-run SIFT when the OpenCV SIMD width changes.
    pub bytes: Arc<Vec<u8>>,
    pub lanes: usize,
}

pub type Frame = Arc<FrameData>;

impl FrameData {
    pub fn from_result(label: String, sift: SiftResult, bytes: Arc<Vec<u8>>, lanes: usize) -> Self {
        FrameData { label, sift, bytes, lanes }
    }
}

impl std::ops::Deref for FrameData {
    type Target = SiftResult;

    fn deref(&self) -> &SiftResult {
        &self.sift
    }
}

/// FNV-1a over the bytes and the SIMD width: the cache key (same file content
/// and parameters → same features).
pub fn content_key(bytes: &[u8], lanes: usize) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325 ^ lanes as u64;
    for &b in bytes {
        h ^= b as u64;
        h = h.wrapping_mul(0x0100_0000_01b3);
    }
    h ^ (bytes.len() as u64).rotate_left(32)
}
