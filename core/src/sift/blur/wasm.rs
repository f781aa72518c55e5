//! The blur's passes with WebAssembly SIMD128: four pixels per vector with
//! the lane-wise exact FMA emulation, four vectors per block; the rest of the
//! row pixel by pixel. A fast path keeps tame data's sums in f64 and redoes
//! the rare block that needs the exact rounding; the relaxed-SIMD build uses
//! the engine's fused `relaxed_madd` where it has one. Either way each tap is
//! the single-rounding FMA of docs/fidelity.md §SIFT-3 (§SIFT-15).

use super::super::num::{fma, fma_emulated_x4, load4 as load, store4 as store};
use core::arch::wasm32::*;

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

// The fast path. `fma_emulated_x4` checks every sum for the two cases
// where rounding the f64 sum to f32 can differ from a fused multiply-add:
// a sum on an f32 halfway point, and an f32-subnormal magnitude. On tame
// data the second cannot occur: with every input 0 or in [2^-100, 2^100]
// and every weight in [2^-20, 1] (Gaussian weights are ≥ 1.8e-5), every
// product and every partial sum of these non-negative terms is 0 or at
// least 2^-120, and far below the f32 maximum. The accumulators then stay
// in f64 (each holding its f32-rounded value), the halfway test is ORed
// over the whole block, and a block where it fired (about one in a
// million sums) is recomputed with the scalar exact FMA. Half the
// operations of the per-FMA check, on the stage that is most of wasm SIFT.

const TAME_MIN: f32 = 7.888_609e-31; // 2^-100
const TAME_MAX: f32 = 1.267_650_6e30; // 2^100

/// Every value is 0 or in [2^-100, 2^100] (so none is negative, NaN or infinite).
pub fn tame(values: &[f32]) -> bool {
    let (lo, hi, zero) = (f32x4_splat(TAME_MIN), f32x4_splat(TAME_MAX), f32x4_splat(0.0));
    let mut ok = i32x4_splat(-1);
    let mut chunks = values.chunks_exact(4);
    for c in &mut chunks {
        let v = load(c, 0);
        ok = v128_and(ok, v128_or(f32x4_eq(v, zero), v128_and(f32x4_ge(v, lo), f32x4_le(v, hi))));
    }
    i32x4_all_true(ok) && chunks.remainder().iter().all(|&v| v == 0.0 || (TAME_MIN..=TAME_MAX).contains(&v))
}

/// Every weight is in [2^-20, 1].
pub fn tame_kernel(k: &[f32]) -> bool {
    k.iter().all(|&v| (9.536_743e-7..=1.0).contains(&v))
}

/// f64 pairs per block: 16 pixels.
const P: usize = 8;

#[inline(always)]
fn round_to_f32(s: v128) -> v128 {
    f64x2_promote_low_f32x4(f32x4_demote_f64x2_zero(s))
}

/// Lanes whose f64 value lies exactly on an f32 halfway point.
#[inline(always)]
fn halfway(s: v128) -> v128 {
    i64x2_eq(v128_and(s, i64x2_splat(0x1FFF_FFFF)), i64x2_splat(0x1000_0000))
}

fn load_f64(s: &[f64], i: usize) -> v128 {
    let s = &s[i..i + 2];
    // SAFETY: `s` holds exactly two f64; v128_load needs no alignment.
    unsafe { v128_load(s.as_ptr().cast()) }
}

/// Stores 16 f32-valued f64 accumulators as f32.
#[inline(always)]
fn store_block(dst: &mut [f32], x: usize, acc: &[v128; P]) {
    for q in 0..P / 2 {
        let v =
            i32x4_shuffle::<0, 1, 4, 5>(f32x4_demote_f64x2_zero(acc[2 * q]), f32x4_demote_f64x2_zero(acc[2 * q + 1]));
        store(dst, x + 4 * q, v);
    }
}

thread_local! {
    static WIDE: core::cell::RefCell<Vec<f64>> = const { core::cell::RefCell::new(Vec::new()) };
}

/// [`row`] on tame data and a tame kernel.
pub fn row_tame(padded: &[f32], kx: &[f32], dst: &mut [f32]) {
    let w = dst.len();
    let n = w + kx.len() - 1;
    WIDE.with(|wide| {
        let mut wide = wide.borrow_mut();
        wide.clear();
        wide.extend(padded[..n].iter().map(|&v| v as f64));
        let mut x = 0;
        while x + 2 * P <= w {
            let k0 = f64x2_splat(kx[0] as f64);
            let mut acc: [v128; P] = core::array::from_fn(|q| round_to_f32(f64x2_mul(load_f64(&wide, x + 2 * q), k0)));
            let mut hard = i64x2_splat(0);
            for (k, &kv) in kx.iter().enumerate().skip(1) {
                let kv = f64x2_splat(kv as f64);
                // One bounds check per tap, not one per vector.
                let src = &wide[x + k..x + k + 2 * P];
                for (q, a) in acc.iter_mut().enumerate() {
                    let s = f64x2_add(f64x2_mul(load_f64(src, 2 * q), kv), *a);
                    hard = v128_or(hard, halfway(s));
                    *a = round_to_f32(s);
                }
            }
            if v128_any_true(hard) {
                row_scalar(padded, kx, dst, x..x + 2 * P);
            } else {
                store_block(dst, x, &acc);
            }
            x += 2 * P;
        }
        row_scalar(padded, kx, dst, x..w);
    });
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

/// [`column`] on tame rows and a tame kernel.
pub fn column_tame(centre: &[f32], pairs: &[(&[f32], &[f32])], ky: &[f32], dst: &mut [f32]) {
    let w = dst.len();
    let high = |v: v128| i32x4_shuffle::<2, 3, 0, 1>(v, v);
    let mut x = 0;
    while x + 2 * P <= w {
        let kc = f32x4_splat(ky[0]);
        // The centre tap is an f32 product, as OpenCV's first multiply.
        let mut acc: [v128; P] = core::array::from_fn(|q| {
            let v = f32x4_mul(load(centre, x + 4 * (q / 2)), kc);
            f64x2_promote_low_f32x4(if q % 2 == 0 { v } else { high(v) })
        });
        let mut hard = i64x2_splat(0);
        for (k, (up, down)) in pairs.iter().enumerate() {
            let kv = f64x2_splat(ky[k + 1] as f64);
            let (up, down) = (&up[x..x + 2 * P], &down[x..x + 2 * P]);
            for q in 0..P / 2 {
                let sum = f32x4_add(load(up, 4 * q), load(down, 4 * q));
                for (h, part) in [sum, high(sum)].into_iter().enumerate() {
                    let a = &mut acc[2 * q + h];
                    let s = f64x2_add(f64x2_mul(f64x2_promote_low_f32x4(part), kv), *a);
                    hard = v128_or(hard, halfway(s));
                    *a = round_to_f32(s);
                }
            }
        }
        if v128_any_true(hard) {
            column_scalar(centre, pairs, ky, dst, x..x + 2 * P);
        } else {
            store_block(dst, x, &acc);
        }
        x += 2 * P;
    }
    column_scalar(centre, pairs, ky, dst, x..w);
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

// The relaxed-SIMD build, where the engine fuses `relaxed_madd` (probed
// by `num::relaxed_madd_is_fused`): every tap is one fused multiply-add,
// the operation OpenCV's AVX2 loop performs, so no check is needed. Eight
// vectors a block keep eight FMA chains in flight; then single vectors,
// then the last pixels through the exact scalar emulation.

#[cfg(feature = "relaxed-simd")]
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

#[cfg(feature = "relaxed-simd")]
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

#[cfg(feature = "relaxed-simd")]
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

#[cfg(feature = "relaxed-simd")]
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

#[cfg(feature = "relaxed-simd")]
const FUSED_V: usize = 8;

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

/// The wasm fast path's fallback, in the browser (`cargo test --target
/// wasm32-unknown-unknown`): a block holding one sum that lands, rounded to
/// f64, exactly on an f32 halfway point it does not lie on, so rounding that
/// f64 to f32 goes the wrong way. Real images hit such a sum about once in a
/// million FMAs, too rarely for a random test to be sure of one.
#[cfg(all(test, target_arch = "wasm32"))]
mod tests {
    use super as wasm;
    use super::super::super::num::fma_emulated;
    use super::super::gaussian_kernel;
    use wasm_bindgen_test::*;

    wasm_bindgen_test_configure!(run_in_browser);

    /// A tap t in `taps` and a value p1 such that, with acc = k[t−1] (the sum
    /// so far when the previous tap saw a 1 and all before it 0), acc + p1·k[t]
    /// is a hard sum: its f64 rounding is the f32 halfway point above an odd
    /// f32 `low` (so that tie goes up) and the exact value lies just below it,
    /// so the FMA gives `low`. Returns (t, p1, low).
    fn hard_sum(k: &[f32], taps: std::ops::Range<usize>) -> (usize, f32, f32) {
        for t in taps {
            let acc = k[t - 1];
            for j in 0..1u32 << 20 {
                let low = f32::from_bits(acc.to_bits() + j);
                if low.to_bits() & 1 == 0 {
                    continue;
                }
                let midpoint = (low as f64 + f32::from_bits(low.to_bits() + 1) as f64) / 2.0;
                let target = midpoint - acc as f64;
                let p1 = (target / k[t] as f64) as f32;
                let product = p1 as f64 * k[t] as f64;
                if acc as f64 + product == midpoint && product < target {
                    assert_eq!(fma_emulated(p1, k[t], acc), low);
                    assert_ne!(((acc as f64 + product) as f32).to_bits(), low.to_bits());
                    return (t, p1, low);
                }
            }
        }
        panic!("no hard sum found");
    }

    #[wasm_bindgen_test]
    fn a_block_with_a_hard_sum_is_redone_exactly() {
        // The pyramid's second level; its kernel has hard sums in both halves.
        let k = gaussian_kernel(1.5450077936447955);
        let c = k.len() / 2;
        assert!(wasm::tame_kernel(&k));
        // Row pass: output pixel 3 of a 16-pixel block sees 1·k[t−1] + p1·k[t].
        let (t, p1, want) = hard_sum(&k, 1..k.len());
        let mut padded = vec![0f32; 16 + k.len() - 1];
        padded[3 + t - 1] = 1.0;
        padded[3 + t] = p1;
        assert!(wasm::tame(&padded));
        let (mut fast, mut exact) = (vec![0f32; 16], vec![0f32; 16]);
        wasm::row_tame(&padded, &k, &mut fast);
        for (i, e) in exact.iter_mut().enumerate() {
            let mut a = padded[i] * k[0];
            for (t, &kv) in k.iter().enumerate().skip(1) {
                a = fma_emulated(padded[i + t], kv, a);
            }
            *e = a;
        }
        assert_eq!(fast[3], want);
        assert_eq!(fast, exact);
        // Column pass: pixel 5 sees the same two taps in the kernel's upper half
        // (pair q of rows has weight k[c+1+q]; the centre row has k[c]).
        let (t, p1, want) = hard_sum(&k, c + 1..k.len());
        let zeros = [0f32; 16];
        let mut rows = vec![vec![0f32; 16]; k.len() - c];
        rows[t - 1 - c][5] = 1.0;
        rows[t - c][5] = p1;
        let pairs: Vec<(&[f32], &[f32])> = rows[1..].iter().map(|r| (&r[..], &zeros[..])).collect();
        let mut fast = vec![0f32; 16];
        wasm::column_tame(&rows[0], &pairs, &k[c..], &mut fast);
        assert_eq!(fast[5], want);
        assert!(fast.iter().enumerate().all(|(i, &v)| i == 5 || v == 0.0));
    }
}
