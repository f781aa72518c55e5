//! `cv::RNG`, OpenCV's multiply-with-carry generator: RANSAC draws its
//! samples from one reset to 2^64 − 1 on every call (docs/fidelity.md
//! §VO-3.3), the Jacobi SVD completes its null space from one seeded with
//! 0x12345678 (§VO-3.5 step 6), and `drawMatchesKnn` colours its matches
//! from `cv::theRNG()`, which starts at 0xffffffff in every thread and which
//! SIFT, the matcher and findEssentialMat never touch (so one drawing in a
//! fresh process, as in the lab, always gets the same colours).

/// `cv::RNG`: the multiply-with-carry generator OpenCV seeds per call.
#[derive(Clone, Copy, Debug)]
pub struct CvRng {
    state: u64,
}

impl CvRng {
    /// `CV_RNG_COEFF` in core/include/opencv2/core/operations.hpp.
    const COEFF: u64 = 4_164_903_690;

    pub fn new(seed: u64) -> Self {
        CvRng { state: seed }
    }

    /// `cv::theRNG()` of a fresh thread.
    pub fn the_rng() -> Self {
        CvRng { state: 0xffff_ffff }
    }

    #[inline]
    pub fn next_u32(&mut self) -> u32 {
        self.state = (self.state & 0xFFFF_FFFF).wrapping_mul(Self::COEFF).wrapping_add(self.state >> 32);
        self.state as u32
    }

    /// `RNG::uniform(0, n)` for ints: `next() % n` in unsigned 32-bit.
    #[inline]
    pub fn uniform(&mut self, n: u32) -> u32 {
        self.next_u32() % n
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rng_follows_the_mwc_recurrence() {
        // The first draws of cv::RNG((uint64)-1), the state findEssentialMat's
        // RANSAC starts from (state = lo32 * 4164903690 + hi32).
        let mut rng = CvRng::new(u64::MAX);
        assert_eq!([rng.next_u32(), rng.next_u32(), rng.next_u32()], [130_063_605, 3_133_359_004, 2_578_348_940]);
        assert_eq!(CvRng::new(u64::MAX).uniform(1000), 605);
    }
}
