//! Which x86 SIMD level the SIFT and LK kernels may use.
//!
//! The kernels are picked at run time from what the CPU has: AVX-512, else
//! AVX2 with FMA, else plain Rust. Every level computes the same bits (each
//! pixel and histogram bin sees OpenCV's operations in OpenCV's order), but
//! a machine only ever runs its own level. Capping the level lets an AVX-512
//! machine run, and test against the OpenCV goldens, the code a student's
//! AVX2 laptop runs (`core/tests/simd_levels.rs`), and time it
//! (`SIFTLAB_SIMD=avx2 siftlab sift …`). It never changes a result.

use std::sync::atomic::{AtomicU8, Ordering};

/// A cap on the x86 instruction sets the kernels may use.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum SimdLevel {
    /// Plain Rust (the FMA is `f32::mul_add`, a library call without the
    /// `fma` target feature).
    Scalar = 0,
    /// AVX2 with FMA, what most laptops have.
    Avx2 = 1,
    /// AVX-512 where the CPU has it (no cap).
    Avx512 = 2,
}

impl SimdLevel {
    /// Parses `scalar`, `avx2` or `avx512` (as `SIFTLAB_SIMD` takes them).
    pub fn parse(s: &str) -> Option<SimdLevel> {
        match s.trim().to_ascii_lowercase().as_str() {
            "scalar" => Some(SimdLevel::Scalar),
            "avx2" => Some(SimdLevel::Avx2),
            "avx512" => Some(SimdLevel::Avx512),
            _ => None,
        }
    }
}

static CAP: AtomicU8 = AtomicU8::new(SimdLevel::Avx512 as u8);

/// Caps the kernels of every later SIFT and LK call in this process.
pub fn set_cap(level: SimdLevel) {
    CAP.store(level as u8, Ordering::Relaxed);
}

/// The current cap.
pub fn cap() -> SimdLevel {
    match CAP.load(Ordering::Relaxed) {
        0 => SimdLevel::Scalar,
        1 => SimdLevel::Avx2,
        _ => SimdLevel::Avx512,
    }
}

/// AVX-512 F kernels may run.
#[cfg(target_arch = "x86_64")]
#[inline]
pub(crate) fn avx512f() -> bool {
    cap() >= SimdLevel::Avx512 && std::is_x86_feature_detected!("avx512f")
}

/// AVX-512 BW kernels (16-bit lanes) may run.
#[cfg(target_arch = "x86_64")]
#[inline]
pub(crate) fn avx512bw() -> bool {
    avx512f() && std::is_x86_feature_detected!("avx512bw")
}

/// AVX-512 F kernels compiled with FMA may run.
#[cfg(target_arch = "x86_64")]
#[inline]
pub(crate) fn avx512f_fma() -> bool {
    avx512f() && std::is_x86_feature_detected!("fma")
}

/// AVX2 kernels may run.
#[cfg(target_arch = "x86_64")]
#[inline]
pub(crate) fn avx2() -> bool {
    cap() >= SimdLevel::Avx2 && std::is_x86_feature_detected!("avx2")
}

/// AVX2 kernels compiled with FMA may run.
#[cfg(target_arch = "x86_64")]
#[inline]
pub(crate) fn avx2_fma() -> bool {
    avx2() && std::is_x86_feature_detected!("fma")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn levels_parse_and_order() {
        assert_eq!(SimdLevel::parse("AVX2 "), Some(SimdLevel::Avx2));
        assert_eq!(SimdLevel::parse("scalar"), Some(SimdLevel::Scalar));
        assert_eq!(SimdLevel::parse("avx512"), Some(SimdLevel::Avx512));
        assert_eq!(SimdLevel::parse("sse4"), None);
        assert!(SimdLevel::Scalar < SimdLevel::Avx2 && SimdLevel::Avx2 < SimdLevel::Avx512);
        assert_eq!(cap(), SimdLevel::Avx512, "uncapped by default");
    }
}
