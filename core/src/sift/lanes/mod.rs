//! One vector register of f32 lanes, as the SIFT kernels use it. The
//! extremum scan's 26-neighbour test (`extrema::vector`) and the
//! descriptor's sample rows and histogram (`descriptor::vector`) are written
//! once, generic over [`Lanes`], and run with AVX-512 (16 lanes), AVX2 (8) or
//! WebAssembly SIMD128 (4). Each method is the vector form of one scalar
//! operation with the same rounding, so every lane computes what the scalar
//! loop computes, whatever the width.
//!
//! A value of a [`Lanes`] type is a token: it exists only where its
//! instructions do (x86 tokens are made after the run-time check). The
//! methods are `#[inline(always)]` and the kernels too, and [`run`] calls a
//! kernel inside a `#[target_feature]` function of its ISA, so the
//! intrinsics inline into one loop per ISA.

#[macro_use]
mod token;
#[cfg(target_arch = "wasm32")]
mod wasm;
#[cfg(target_arch = "x86_64")]
mod x86;

pub(crate) use token::{Kernel, Lanes};

/// Runs `k` with the widest vectors this CPU and the SIMD cap allow, then
/// with narrower ones on what is left (AVX-512, then AVX2); returns where
/// the vectors stopped, 0 on a target without them.
#[inline(always)]
pub(crate) fn run<K: Kernel>(k: &mut K) -> usize {
    #[cfg(target_arch = "x86_64")]
    return x86::run(k);
    #[cfg(target_arch = "wasm32")]
    return wasm::run(k);
    #[cfg(not(any(target_arch = "x86_64", target_arch = "wasm32")))]
    {
        let _ = k;
        0
    }
}
