//! The f32 plane every pyramid level is stored in.

use std::sync::Mutex;

/// A row-major f32 image: one Gaussian level (or a scratch buffer).
#[derive(Debug)]
pub struct Plane {
    pub width: usize,
    pub height: usize,
    pub data: Vec<f32>,
    /// How many floats of `data`'s buffer have been written (at least its
    /// length), and the buffer's address: a spare buffer that held a
    /// longer plane can be that long again without being filled first.
    init: (usize, *const f32),
}

// SAFETY: the raw pointer is only compared, never dereferenced; the rest
// of a Plane is plain owned data.
unsafe impl Send for Plane {}
// SAFETY: as for Send: nothing is reached through the pointer.
unsafe impl Sync for Plane {}

impl PartialEq for Plane {
    fn eq(&self, other: &Self) -> bool {
        (self.width, self.height) == (other.width, other.height) && self.data == other.data
    }
}

impl Plane {
    fn assemble(width: usize, height: usize, data: Vec<f32>, init: usize) -> Self {
        let at = data.as_ptr();
        Plane { width, height, data, init: (init, at) }
    }

    /// A zeroed plane, its buffer taken from this thread's spare buffers
    /// when one is big enough.
    pub fn new(width: usize, height: usize) -> Self {
        let n = width * height;
        let (mut data, init) = take_spare(n).unwrap_or_default();
        data.clear();
        data.resize(n, 0.0);
        Plane::assemble(width, height, data, init.max(n))
    }

    /// A plane whose every pixel the caller is about to write: a spare
    /// buffer is reused as it is (stale but initialised values), without
    /// the zeroing pass.
    pub fn for_overwrite(width: usize, height: usize) -> Self {
        let n = width * height;
        let (mut data, init) = take_spare(n).unwrap_or_default();
        if init >= n {
            // SAFETY: the buffer's first `init` floats were all written
            // while it held an earlier plane (`init` only ever counts
            // written floats), and nothing un-writes memory: f32 has no
            // drop and every bit pattern is a valid f32.
            unsafe { data.set_len(n) };
        } else {
            data.resize(n, 0.0);
        }
        Plane::assemble(width, height, data, init.max(n))
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

/// Spare buffers, each with how many of its floats have been written.
static SPARE: Mutex<Vec<(Vec<f32>, usize)>> = Mutex::new(Vec::new());

/// The smallest spare buffer holding at least `n` floats, and how many of
/// its floats have been written.
fn take_spare(n: usize) -> Option<(Vec<f32>, usize)> {
    if n < 4096 {
        return None; // small planes: the allocator is fast enough
    }
    let mut spare = SPARE.lock().ok()?;
    let best = spare
        .iter()
        .enumerate()
        .filter(|(_, (b, _))| b.capacity() >= n)
        .min_by_key(|(_, (b, _))| b.capacity())
        .map(|(i, _)| i)?;
    Some(spare.swap_remove(best))
}

impl Drop for Plane {
    fn drop(&mut self) {
        if self.data.capacity() < 4096 {
            return;
        }
        if let Ok(mut spare) = SPARE.lock() {
            let held: usize = spare.iter().map(|(b, _)| b.capacity()).sum();
            if spare.len() < MAX_SPARE_BUFFERS && held + self.data.capacity() <= MAX_SPARE_FLOATS {
                // The count is the buffer's only while it is the same buffer.
                let (init, at) = self.init;
                let len = self.data.len();
                let init = if at == self.data.as_ptr() && init <= self.data.capacity() { init.max(len) } else { len };
                spare.push((std::mem::take(&mut self.data), init));
            }
        }
    }
}
