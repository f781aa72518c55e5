//! The blur's f64 fast paths with SIMD128: tame data (every value 0 or in
//! [2^-100, 2^100], a tame kernel) with the halfway test and the rare block
//! redone exactly, and the base image's sixteenths, whose f64 sums are exact.

use super::super::super::num::{load4 as load, store4 as store};
use super::{column_scalar, row_scalar};
use core::arch::wasm32::*;

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
pub(super) fn round_split(s: v128) -> v128 {
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
pub(super) fn narrow(a: v128, b: v128) -> v128 {
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
    super::super::generic::blocks(w, 2 * P)
}

/// [`row`](super::row) on tame data and a tame kernel.
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

/// [`row`](super::row) on [`sixteenths`] data with an [`exact_kernel`]: no halfway test, no redo.
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

/// [`column`](super::column) on tame rows and a tame kernel.
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
