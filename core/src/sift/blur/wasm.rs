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
// million sums) is recomputed with the scalar exact FMA. Per tap and four
// pixels that is two f64 multiplies and adds, the split rounding (six
// operations) and the halfway test (three), 13 operations where the relaxed
// build has one `relaxed_madd`; docs/performance.md, "The SIMD128 path".

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

// The fast path avoids `f32x4.demote_f64x2_zero`: LLVM turns it, followed by
// a promote or a shuffle, into a scalar demote per lane (an extract, a
// demote and an insert each), which made the rounding after each tap the
// blur's largest cost (the row pass 1.8×, the column pass 1.7× slower).

/// Rounds f64 lanes to the nearest f32 value (kept in f64) with Veltkamp's
/// split, three f64 operations: `t = s·(2^29 + 1)`, `t − (t − s)` is `s`
/// rounded to nearest at 53 − 29 = 24 bits, f32's precision, for every `s`
/// in f32's normal range. Only a tie may round either way, and a tie is
/// exactly what `flag_halfway` sends to the exact scalar path, so the value
/// kept always equals the FMA's correctly rounded f32.
#[inline(always)]
fn round_split(s: v128) -> v128 {
    let t = f64x2_mul(s, f64x2_splat(536_870_913.0));
    f64x2_sub(t, f64x2_sub(t, s))
}

/// Folds the halfway test of four sums (two vectors) into `hard`: a sum lies on an
/// f32 halfway point exactly when its low 29 bits are 0x1000_0000, that is,
/// when its low word shifted left by 3 is `i32::MIN`, the smallest i32; so
/// `hard` keeps the minimum and [`any_halfway`] compares it once per block.
#[inline(always)]
fn flag_halfway(hard: v128, s0: v128, s1: v128) -> v128 {
    i32x4_min(hard, i32x4_shl(i32x4_shuffle::<0, 2, 4, 6>(s0, s1), 3))
}

#[inline(always)]
fn any_halfway(hard: v128) -> bool {
    v128_any_true(i32x4_eq(hard, i32x4_splat(i32::MIN)))
}

fn load_f64(s: &[f64], i: usize) -> v128 {
    let s = &s[i..i + 2];
    // SAFETY: `s` holds exactly two f64; v128_load needs no alignment.
    unsafe { v128_load(s.as_ptr().cast()) }
}

/// Four f32 from four f64 lanes holding tame f32 values, by their bits: the
/// low word of a normal value's f64 bits shifted right by 29 holds the low 9
/// bits of its exponent and its 23 significand bits, and subtracting the
/// bias difference (1023 − 127) << 23, modulo 2^32, leaves its f32 bits. Zero,
/// the one other tame value (a zero high word), stays zero.
#[inline(always)]
fn narrow(a: v128, b: v128) -> v128 {
    let v = i32x4_shuffle::<0, 2, 4, 6>(u64x2_shr(a, 29), u64x2_shr(b, 29));
    let nonzero = i32x4_ne(i32x4_shuffle::<1, 3, 5, 7>(a, b), i32x4_splat(0));
    v128_and(i32x4_sub(v, i32x4_splat((896u32 << 23) as i32)), nonzero)
}

/// Stores 16 f32-valued f64 accumulators as f32.
#[inline(always)]
fn store_block(dst: &mut [f32], x: usize, acc: &[v128; P]) {
    let dst = &mut dst[x..x + 2 * P];
    for q in 0..P / 2 {
        store(dst, 4 * q, narrow(acc[2 * q], acc[2 * q + 1]));
    }
}

thread_local! {
    static WIDE: core::cell::RefCell<Vec<f64>> = const { core::cell::RefCell::new(Vec::new()) };
}

/// The row in f64, four pixels at a time (LLVM leaves the plain loop scalar).
fn widen(src: &[f32], wide: &mut Vec<f64>) {
    wide.clear();
    wide.resize(src.len(), 0.0);
    let mut chunks = src.chunks_exact(4);
    for (c, d) in (&mut chunks).zip(wide.chunks_exact_mut(4)) {
        let v = load(c, 0);
        let (lo, hi) = (f64x2_promote_low_f32x4(v), f64x2_promote_low_f32x4(i32x4_shuffle::<2, 3, 2, 3>(v, v)));
        // SAFETY: `d` holds exactly four f64; v128_store needs no alignment.
        unsafe {
            v128_store(d.as_mut_ptr().cast(), lo);
            v128_store(d.as_mut_ptr().add(2).cast(), hi);
        }
    }
    let done = src.len() - chunks.remainder().len();
    for (d, &v) in wide[done..].iter_mut().zip(chunks.remainder()) {
        *d = v as f64;
    }
}

/// Starts of 16-pixel blocks covering `0..w`, the last one overlapping the
/// one before, and where the scalar rest starts: the native passes' rule.
#[inline(always)]
fn blocks(w: usize) -> (impl Iterator<Item = usize>, usize) {
    super::generic::blocks(w, 2 * P)
}

/// [`row`] on tame data and a tame kernel.
pub fn row_tame(padded: &[f32], kx: &[f32], dst: &mut [f32]) {
    let w = dst.len();
    let n = w + kx.len() - 1;
    WIDE.with(|wide| {
        let mut wide = wide.borrow_mut();
        widen(&padded[..n], &mut wide);
        // The last block overlaps the one before rather than leaving up to
        // 15 pixels to the scalar emulation, a chain of dependent FMAs each
        // (5 % of the portable worker's profile); an overlapped pixel is
        // recomputed from the same taps, so it gets the same value.
        let (starts, rest) = blocks(w);
        for x in starts {
            let k0 = f64x2_splat(kx[0] as f64);
            let src = &wide[x..x + 2 * P];
            // The first tap is OpenCV's f32 product: exact in f64, then rounded.
            let mut acc: [v128; P] = core::array::from_fn(|q| f64x2_mul(load_f64(src, 2 * q), k0));
            let mut hard = i32x4_splat(i32::MAX);
            for q in 0..P / 2 {
                hard = flag_halfway(hard, acc[2 * q], acc[2 * q + 1]);
            }
            acc = acc.map(round_split);
            for (k, &kv) in kx.iter().enumerate().skip(1) {
                let kv = f64x2_splat(kv as f64);
                // One bounds check per tap, not one per vector.
                let src = &wide[x + k..x + k + 2 * P];
                for q in 0..P / 2 {
                    let s0 = f64x2_add(f64x2_mul(load_f64(src, 4 * q), kv), acc[2 * q]);
                    let s1 = f64x2_add(f64x2_mul(load_f64(src, 4 * q + 2), kv), acc[2 * q + 1]);
                    hard = flag_halfway(hard, s0, s1);
                    acc[2 * q] = round_split(s0);
                    acc[2 * q + 1] = round_split(s1);
                }
            }
            if any_halfway(hard) {
                row_scalar(padded, kx, dst, x..x + 2 * P);
            } else {
                store_block(dst, x, &acc);
            }
        }
        row_scalar(padded, kx, dst, rest..w);
    });
}

// The base image's row pass (§SIFT-2: the upsampled 8-bit image, every value
// a multiple of 1/16 below 256, so at most 12 significant bits). There every
// product is exact in f64 (12 + 24 bits), every f32 accumulator and product
// lies on the grid of the data's 1/16 times the kernel's lowest weight bit,
// and every sum stays below 256 · Σk: when that span fits f64's 53 bits
// (49 bits for the base kernel) every f64 sum is exact, so the FMA's result
// is that sum rounded once to f32, ties to even. Ties are common on such
// data (the sums have few bits): the halfway test of `row_tame` flagged
// a fifth of these blocks, each then redone by the scalar emulation.

/// Every value is a multiple of 1/16 in [0, 256): at most 12 significant bits.
pub fn sixteenths(values: &[f32]) -> bool {
    let (zero, top, sixteen) = (f32x4_splat(0.0), f32x4_splat(256.0), f32x4_splat(16.0));
    let mut ok = i32x4_splat(-1);
    let mut chunks = values.chunks_exact(4);
    for c in &mut chunks {
        let v = load(c, 0);
        let t = f32x4_mul(v, sixteen);
        ok = v128_and(ok, v128_and(f32x4_eq(f32x4_nearest(t), t), v128_and(f32x4_ge(v, zero), f32x4_lt(v, top))));
    }
    i32x4_all_true(ok)
        && chunks.remainder().iter().all(|&v| (0.0..256.0).contains(&v) && (v * 16.0).round_ties_even() == v * 16.0)
}

/// Whether every f64 sum of the row pass over [`sixteenths`] data is exact
/// with the kernel `k` (tame, its weights' lowest set bit and sum decide).
pub fn exact_kernel(k: &[f32]) -> bool {
    if !tame_kernel(k) {
        return false;
    }
    // The exponent of the lowest set bit of any weight (all are normal).
    let lsb = k
        .iter()
        .map(|&v| {
            let b = v.to_bits();
            ((b >> 23) & 0xFF) as i32 - 150 + ((b & 0x7F_FFFF) | 0x80_0000).trailing_zeros() as i32
        })
        .min()
        .unwrap_or(0);
    // Sums below 2^top (a margin for the accumulators' roundings up), on the grid 2^(lsb − 4).
    let sum: f64 = k.iter().map(|&v| v as f64).sum();
    let top = (256.0 * sum * 1.001).log2().floor() as i32 + 1;
    top - (lsb - 4) <= 53
}

/// An exact, non-negative f64 sum in f32's normal range (or 0) rounded to
/// f32, ties to even, kept in f64: add just under half an f32 ulp plus the
/// f32 lowest bit, then clear the 29 bits f32 lacks (a carry reaches the
/// exponent as it should).
#[inline(always)]
fn round_even(s: v128) -> v128 {
    let lsb = v128_and(u64x2_shr(s, 29), i64x2_splat(1));
    v128_and(i64x2_add(i64x2_add(s, i64x2_splat(0x0FFF_FFFF)), lsb), i64x2_splat(!0x1FFF_FFFF))
}

/// [`row`] on [`sixteenths`] data with an [`exact_kernel`]: no halfway test, no redo.
pub fn row_exact(padded: &[f32], kx: &[f32], dst: &mut [f32]) {
    let w = dst.len();
    let n = w + kx.len() - 1;
    WIDE.with(|wide| {
        let mut wide = wide.borrow_mut();
        widen(&padded[..n], &mut wide);
        let (starts, rest) = blocks(w);
        for x in starts {
            let k0 = f64x2_splat(kx[0] as f64);
            let src = &wide[x..x + 2 * P];
            let mut acc: [v128; P] = core::array::from_fn(|q| round_even(f64x2_mul(load_f64(src, 2 * q), k0)));
            for (k, &kv) in kx.iter().enumerate().skip(1) {
                let kv = f64x2_splat(kv as f64);
                let src = &wide[x + k..x + k + 2 * P];
                for (q, a) in acc.iter_mut().enumerate() {
                    *a = round_even(f64x2_add(f64x2_mul(load_f64(src, 2 * q), kv), *a));
                }
            }
            store_block(dst, x, &acc);
        }
        row_scalar(padded, kx, dst, rest..w);
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
    let high = |v: v128| i32x4_shuffle::<2, 3, 2, 3>(v, v);
    // Blocks as in `row_tame`, the last one overlapping.
    let (starts, rest) = blocks(w);
    for x in starts {
        let kc = f32x4_splat(ky[0]);
        let mid = &centre[x..x + 2 * P];
        // The centre tap is an f32 product, as OpenCV's first multiply.
        let mut acc: [v128; P] = core::array::from_fn(|q| {
            let v = f32x4_mul(load(mid, 4 * (q / 2)), kc);
            f64x2_promote_low_f32x4(if q % 2 == 0 { v } else { high(v) })
        });
        let mut hard = i32x4_splat(i32::MAX);
        for (k, (up, down)) in pairs.iter().enumerate() {
            let kv = f64x2_splat(ky[k + 1] as f64);
            let (up, down) = (&up[x..x + 2 * P], &down[x..x + 2 * P]);
            for q in 0..P / 2 {
                // The pair's f32 sum, rounded as OpenCV's; its product with
                // the weight is exact in f64.
                let sum = f32x4_add(load(up, 4 * q), load(down, 4 * q));
                let s0 = f64x2_add(f64x2_mul(f64x2_promote_low_f32x4(sum), kv), acc[2 * q]);
                let s1 = f64x2_add(f64x2_mul(f64x2_promote_low_f32x4(high(sum)), kv), acc[2 * q + 1]);
                hard = flag_halfway(hard, s0, s1);
                acc[2 * q] = round_split(s0);
                acc[2 * q + 1] = round_split(s1);
            }
        }
        if any_halfway(hard) {
            column_scalar(centre, pairs, ky, dst, x..x + 2 * P);
        } else {
            store_block(dst, x, &acc);
        }
    }
    column_scalar(centre, pairs, ky, dst, rest..w);
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
    use super::super::kernel::gaussian_kernel;
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

    /// The fast path's rounding and narrowing against Rust's f64 → f32 conversion,
    /// on random tame values of every binade (2^-120 to 2^100) and zero: the
    /// split rounds every value that is not a tie as the conversion does, and
    /// `narrow` returns the f32 of every f32-valued lane.
    #[wasm_bindgen_test]
    fn split_rounding_and_narrowing_equal_the_conversion() {
        use core::arch::wasm32::*;
        let mut state = 0x9E37_79B9_7F4A_7C15u64;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        let lane = |v: v128| [f64x2_extract_lane::<0>(v), f64x2_extract_lane::<1>(v)];
        let (mut checked, mut ties) = (0, 0);
        for i in 0..400_000u32 {
            let r = next();
            // Exponent 2^-120 ..= 2^100, random significand; every 64th a
            // sum with few low bits, where ties are common.
            let e = (r >> 52) % 221;
            let bits = ((1023 - 120 + e) << 52) | (r & ((1 << 52) - 1));
            let bits = if i % 64 == 0 { bits & !((1 << 27) - 1) } else { bits };
            let s = [f64::from_bits(bits), if i % 97 == 0 { 0.0 } else { f64::from_bits(bits ^ (r >> 40)) }];
            let v = f64x2(s[0], s[1]);
            let got = lane(wasm::round_split(v));
            for (k, &x) in s.iter().enumerate() {
                if x.to_bits() & 0x1FFF_FFFF == 0x1000_0000 {
                    ties += 1;
                    continue;
                }
                let want = x as f32;
                assert_eq!(got[k].to_bits(), (want as f64).to_bits(), "{x:e}");
                checked += 1;
            }
            let n = wasm::narrow(f64x2(got[0], got[1]), f64x2(got[1], 0.0));
            let n = [f32x4_extract_lane::<0>(n), f32x4_extract_lane::<1>(n), f32x4_extract_lane::<2>(n)];
            assert_eq!(n.map(f32::to_bits), [got[0] as f32, got[1] as f32, got[1] as f32].map(f32::to_bits));
            assert_eq!(f32x4_extract_lane::<3>(wasm::narrow(v, f64x2_splat(0.0))).to_bits(), 0);
        }
        assert!(checked > 790_000 && ties > 10, "{checked} {ties}");
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
