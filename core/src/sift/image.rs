//! The f32 plane every pyramid level is stored in.

use std::sync::Mutex;

/// A row-major f32 image: one Gaussian level (or a scratch buffer).
#[derive(Debug, PartialEq)]
pub struct Plane {
    pub width: usize,
    pub height: usize,
    pub data: Vec<f32>,
}

impl Plane {
    /// A zeroed plane, its buffer taken from this thread's spare buffers
    /// when one is big enough.
    pub fn new(width: usize, height: usize) -> Self {
        let n = width * height;
        let mut data = take_spare(n).unwrap_or_default();
        data.clear();
        data.resize(n, 0.0);
        Plane { width, height, data }
    }

    /// A plane whose every pixel the caller is about to write: a spare
    /// buffer is reused as it is (stale but initialised values), without
    /// the zeroing pass.
    pub fn for_overwrite(width: usize, height: usize) -> Self {
        let n = width * height;
        let mut data = take_spare(n).unwrap_or_default();
        if data.len() >= n {
            data.truncate(n);
        } else {
            data.resize(n, 0.0);
        }
        Plane { width, height, data }
    }

    #[inline(always)]
    pub fn row(&self, y: usize) -> &[f32] {
        &self.data[y * self.width..(y + 1) * self.width]
    }

    #[inline(always)]
    pub fn row_mut(&mut self, y: usize) -> &mut [f32] {
        &mut self.data[y * self.width..(y + 1) * self.width]
    }

    #[inline(always)]
    pub fn at(&self, y: usize, x: usize) -> f32 {
        self.data[y * self.width + x]
    }
}

impl Clone for Plane {
    fn clone(&self) -> Self {
        let mut p = Plane::for_overwrite(self.width, self.height);
        p.data.copy_from_slice(&self.data);
        p
    }
}

// One SIFT call allocates and frees about 100 MB of planes (KITTI frame:
// 2482×752 floats per level of the first octave). Fresh allocations that
// large come from the kernel as zero pages, and page faults plus trimming
// cost a fifth of the run; the video loop and the app run SIFT frame after
// frame (the video loop on a new thread each time), so a freed plane's
// buffer is kept for the next one instead, in one process-wide set.
// One KITTI frame frees about 40 buffers of 4096 floats or more (octaves
// 0–5: 6 Gaussian levels each, 45 MB, plus the upsampled base's and the
// blurs' band buffers); keep a frame's worth with room to spare.
const MAX_SPARE_BUFFERS: usize = 160;
const MAX_SPARE_FLOATS: usize = 64 << 20; // 256 MB

static SPARE: Mutex<Vec<Vec<f32>>> = Mutex::new(Vec::new());

/// The smallest spare buffer holding at least `n` floats.
fn take_spare(n: usize) -> Option<Vec<f32>> {
    if n < 4096 {
        return None; // small planes: the allocator is fast enough
    }
    let mut spare = SPARE.lock().ok()?;
    let best = spare
        .iter()
        .enumerate()
        .filter(|(_, b)| b.capacity() >= n)
        .min_by_key(|(_, b)| b.capacity())
        .map(|(i, _)| i)?;
    Some(spare.swap_remove(best))
}

impl Drop for Plane {
    fn drop(&mut self) {
        if self.data.capacity() < 4096 {
            return;
        }
        if let Ok(mut spare) = SPARE.lock() {
            let held: usize = spare.iter().map(Vec::capacity).sum();
            if spare.len() < MAX_SPARE_BUFFERS && held + self.data.capacity() <= MAX_SPARE_FLOATS {
                spare.push(std::mem::take(&mut self.data));
            }
        }
    }
}
