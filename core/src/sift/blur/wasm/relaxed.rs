//! The blur's passes in the relaxed-SIMD build, where the engine fuses
//! `relaxed_madd`.

use super::super::super::num::{load4 as load, store4 as store};
use super::{column_scalar, row_scalar};
use core::arch::wasm32::*;

// The relaxed-SIMD build, where the engine fuses `relaxed_madd` (probed
// by `num::relaxed_madd_is_fused`): every tap is one fused multiply-add,
// the operation OpenCV's AVX2 loop performs, so no check is needed. Eight
// vectors a block keep eight FMA chains in flight; then single vectors,
// then the last pixels through the exact scalar emulation.

#[target_feature(enable = "relaxed-simd")]
fn row_fused_block<const B: usize>(padded: &[f32], kx: &[f32], dst: &mut [f32], x: usize) {
    let k0 = f32x4_splat(kx[0]);
    let mut acc: [v128; B] = core::array::from_fn(|v| f32x4_mul(load(padded, x + 4 * v), k0));
    for (k, &kv) in kx.iter().enumerate().skip(1) {
        let kv = f32x4_splat(kv);
        // One bounds check per tap, not one per vector.
        let src = &padded[x + k..x + k + 4 * B];
        for (v, a) in acc.iter_mut().enumerate() {
            *a = f32x4_relaxed_madd(load(src, 4 * v), kv, *a);
        }
    }
    for (v, a) in acc.into_iter().enumerate() {
        store(dst, x + 4 * v, a);
    }
}

#[target_feature(enable = "relaxed-simd")]
pub fn row_fused(padded: &[f32], kx: &[f32], dst: &mut [f32]) {
    let w = dst.len();
    let mut x = 0;
    while x + 4 * FUSED_V <= w {
        row_fused_block::<FUSED_V>(padded, kx, dst, x);
        x += 4 * FUSED_V;
    }
    while x + 4 <= w {
        row_fused_block::<1>(padded, kx, dst, x);
        x += 4;
    }
    row_scalar(padded, kx, dst, x..w);
}

#[target_feature(enable = "relaxed-simd")]
fn column_fused_block<const B: usize>(
    centre: &[f32],
    pairs: &[(&[f32], &[f32])],
    ky: &[f32],
    dst: &mut [f32],
    x: usize,
) {
    let kc = f32x4_splat(ky[0]);
    let mut acc: [v128; B] = core::array::from_fn(|v| f32x4_mul(load(centre, x + 4 * v), kc));
    for (k, (up, down)) in pairs.iter().enumerate() {
        let kv = f32x4_splat(ky[k + 1]);
        let (up, down) = (&up[x..x + 4 * B], &down[x..x + 4 * B]);
        for (v, a) in acc.iter_mut().enumerate() {
            let sum = f32x4_add(load(up, 4 * v), load(down, 4 * v));
            *a = f32x4_relaxed_madd(sum, kv, *a);
        }
    }
    for (v, a) in acc.into_iter().enumerate() {
        store(dst, x + 4 * v, a);
    }
}

#[target_feature(enable = "relaxed-simd")]
pub fn column_fused(centre: &[f32], pairs: &[(&[f32], &[f32])], ky: &[f32], dst: &mut [f32]) {
    let w = dst.len();
    let mut x = 0;
    while x + 4 * FUSED_V <= w {
        column_fused_block::<FUSED_V>(centre, pairs, ky, dst, x);
        x += 4 * FUSED_V;
    }
    while x + 4 <= w {
        column_fused_block::<1>(centre, pairs, ky, dst, x);
        x += 4;
    }
    column_scalar(centre, pairs, ky, dst, x..w);
}

const FUSED_V: usize = 8;
