//! The blur's passes with WebAssembly SIMD128: four pixels per vector with
//! the lane-wise exact FMA emulation, four vectors per block; the rest of the
//! row pixel by pixel. A fast path keeps tame data's sums in f64 and redoes
//! the rare block that needs the exact rounding; the relaxed-SIMD build uses
//! the engine's fused `relaxed_madd` where it has one. Either way each tap is
//! the single-rounding FMA of docs/fidelity.md §SIFT-3 (§SIFT-15).
//!
//! This file holds the exact emulated passes and the scalar rest every kernel
//! ends with; beside it, `wasm/fast.rs` the f64 fast paths for tame data and
//! `wasm/relaxed.rs` the relaxed-SIMD build's fused passes.

use super::super::num::{fma, fma_emulated_x4, load4 as load, store4 as store};
use core::arch::wasm32::*;

mod fast;
#[cfg(feature = "relaxed-simd")]
mod relaxed;
#[cfg(all(test, target_arch = "wasm32"))]
mod tests;

pub use fast::{column_tame, exact_kernel, row_exact, row_tame, sixteenths, tame, tame_kernel};
#[cfg(feature = "relaxed-simd")]
pub use relaxed::{column_fused, row_fused};

const V: usize = 4; // vectors per block

/// Whether this is the relaxed build on an engine whose `relaxed_madd`
/// is fused: then both passes take the `*_fused` kernels.
#[inline(always)]
pub fn fused() -> bool {
    #[cfg(feature = "relaxed-simd")]
    return super::super::num::relaxed_madd_is_fused();
    #[cfg(not(feature = "relaxed-simd"))]
    false
}

fn row_scalar(padded: &[f32], kx: &[f32], dst: &mut [f32], xs: core::ops::Range<usize>) {
    for i in xs {
        let mut a = padded[i] * kx[0];
        for (k, &kv) in kx.iter().enumerate().skip(1) {
            a = fma(padded[i + k], kv, a);
        }
        dst[i] = a;
    }
}

fn column_scalar(centre: &[f32], pairs: &[(&[f32], &[f32])], ky: &[f32], dst: &mut [f32], xs: core::ops::Range<usize>) {
    for i in xs {
        let mut a = centre[i] * ky[0];
        for (k, (up, down)) in pairs.iter().enumerate() {
            a = fma(up[i] + down[i], ky[k + 1], a);
        }
        dst[i] = a;
    }
}

pub fn row(padded: &[f32], kx: &[f32], dst: &mut [f32]) {
    let w = dst.len();
    let mut x = 0;
    while x + 4 * V <= w {
        let k0 = f32x4_splat(kx[0]);
        let mut acc: [v128; V] = core::array::from_fn(|v| f32x4_mul(load(padded, x + 4 * v), k0));
        for (k, &kv) in kx.iter().enumerate().skip(1) {
            let kv = f32x4_splat(kv);
            for (v, a) in acc.iter_mut().enumerate() {
                *a = fma_emulated_x4(load(padded, x + k + 4 * v), kv, *a);
            }
        }
        for (v, a) in acc.into_iter().enumerate() {
            store(dst, x + 4 * v, a);
        }
        x += 4 * V;
    }
    row_scalar(padded, kx, dst, x..w);
}

pub fn column(centre: &[f32], pairs: &[(&[f32], &[f32])], ky: &[f32], dst: &mut [f32]) {
    let w = dst.len();
    let mut x = 0;
    while x + 4 * V <= w {
        let kc = f32x4_splat(ky[0]);
        let mut acc: [v128; V] = core::array::from_fn(|v| f32x4_mul(load(centre, x + 4 * v), kc));
        for (k, (up, down)) in pairs.iter().enumerate() {
            let kv = f32x4_splat(ky[k + 1]);
            for (v, a) in acc.iter_mut().enumerate() {
                let sum = f32x4_add(load(up, x + 4 * v), load(down, x + 4 * v));
                *a = fma_emulated_x4(sum, kv, *a);
            }
        }
        for (v, a) in acc.into_iter().enumerate() {
            store(dst, x + 4 * v, a);
        }
        x += 4 * V;
    }
    column_scalar(centre, pairs, ky, dst, x..w);
}
