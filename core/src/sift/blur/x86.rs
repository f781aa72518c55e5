//! The blur's passes compiled for x86-64 with FMA (AVX2, and AVX-512 where
//! the CPU has it), picked at run time by the dispatch in `mod.rs`: the plain
//! loops again, because `mul_add` without the `fma` target feature is a
//! library call per tap; and the AVX2 two-row column pass. Every pixel sees
//! the taps of docs/fidelity.md §SIFT-3 in its order, fused where it fuses.

use super::generic::{accumulate_column_generic, accumulate_row_generic, blocks, BLOCK};
use std::arch::x86_64::*;

#[target_feature(enable = "avx2,fma")]
pub fn row_avx2(padded: &[f32], kx: &[f32], dst: &mut [f32]) {
    accumulate_row_generic::<{ BLOCK }>(padded, kx, dst, f32::mul_add)
}

/// Eight independent accumulators: each tap is one load and one FMA per
/// vector, so with four the FMA latency (4 cycles) would be the limit.
#[target_feature(enable = "avx512f,avx2,fma")]
pub fn row_avx512(padded: &[f32], kx: &[f32], dst: &mut [f32]) {
    accumulate_row_generic::<{ 2 * BLOCK }>(padded, kx, dst, f32::mul_add)
}

#[target_feature(enable = "avx2,fma")]
pub fn column_avx2(centre: &[f32], pairs: &[(&[f32], &[f32])], ky: &[f32], dst: &mut [f32]) {
    accumulate_column_generic(centre, pairs, ky, dst, f32::mul_add)
}

#[target_feature(enable = "avx512f,avx2,fma")]
pub fn column_avx512(centre: &[f32], pairs: &[(&[f32], &[f32])], ky: &[f32], dst: &mut [f32]) {
    accumulate_column_generic(centre, pairs, ky, dst, f32::mul_add)
}

/// AVX2 vectors a row in [`column_pair_avx2`]'s blocks.
const PAIR_V: usize = 3;
/// Largest kernel half-width the AVX2 pair pass takes (SIFT's largest is 12).
const MAX_HALF: usize = 32;
/// How far ahead of a block its output lines are asked for, in pixels
/// (512 bytes, five blocks; 64 to 512 all helped, 128–256 most).
const PREFETCH_AHEAD: usize = 128;

/// Output rows y and y + 1 of the column pass at once, from `rows` = the
/// 2c + 2 ring rows y − c ..= y + c + 1 and `ky` = the kernel's centre and
/// right half. Row y + 1's taps reuse row y's loads shifted by one tap
/// (R[y+1+k] is R[y+(k+1)], R[y+1−k] is R[y−(k−1)]), so a tap costs two
/// loads per vector for both rows instead of two per row: the ring is read
/// from L2, and that read bounded the one-row pass. Each pixel still sees
/// OpenCV's operations in OpenCV's order (§SIFT-3): centre·k0, then
/// fma(up + down, kk, acc) for k = 1..=c.
///
/// In intrinsics, three vectors a row (the generic form,
/// [`column_pair_block`], compiled to partial-vector shuffles for its carried
/// arrays): acc, up and down of both rows take 12 registers.
#[target_feature(enable = "avx2,fma")]
pub fn column_pair_avx2(rows: &[&[f32]], ky: &[f32], d0: &mut [f32], d1: &mut [f32]) {
    const V: usize = PAIR_V;
    let (c, w) = (ky.len() - 1, d0.len());
    assert!(rows.len() == 2 * c + 2 && d1.len() == w && rows.iter().all(|r| r.len() >= w));
    if w < 8 * V || c > MAX_HALF {
        return accumulate_column_pair_generic(rows, ky, d0, d1, f32::mul_add);
    }
    // The two rows each tap k = 1..=c adds, as plain pointers: indexing
    // `rows` in the tap loop cost a bounds check and a fat-pointer load
    // per row and tap, on a loop of a dozen vector instructions.
    let mut ups = [std::ptr::null::<f32>(); MAX_HALF];
    let mut downs = [std::ptr::null::<f32>(); MAX_HALF];
    for k in 1..=c {
        ups[k - 1] = rows[c + 1 + k].as_ptr();
        downs[k - 1] = rows[c - k].as_ptr();
    }
    let (ups, downs) = (&ups[..c], &downs[..c]);
    let centres = (rows[c].as_ptr(), rows[c + 1].as_ptr());
    let outs = (d0.as_mut_ptr(), d1.as_mut_ptr());
    for x in blocks(w, 8 * V).0 {
        // The output rows are fresh memory: without asking for their
        // lines ahead, each block's stores waited on those lines being
        // read in (over a quarter of this function's time); with it, a
        // first-octave blur took about a tenth less.
        if x + PREFETCH_AHEAD + 16 < w {
            for o in [outs.0, outs.1] {
                // SAFETY: x + PREFETCH_AHEAD + 16 < w, inside both output
                // rows; a prefetch never faults.
                unsafe {
                    _mm_prefetch::<_MM_HINT_ET0>(o.add(x + PREFETCH_AHEAD) as *const i8);
                    _mm_prefetch::<_MM_HINT_ET0>(o.add(x + PREFETCH_AHEAD + 16) as *const i8);
                }
            }
        }
        // Pixels x..x + 24 of both output rows. Every ring row and both
        // output rows hold at least w ≥ x + 24 floats (asserted above; the
        // last block of `blocks` ends at w).
        let load = |r: *const f32| -> [__m256; V] {
            std::array::from_fn(|v| {
                // SAFETY: x + 8·v + 8 <= w for v < V, inside every row (see above).
                unsafe { _mm256_loadu_ps(r.add(x + 8 * v)) }
            })
        };
        let k0 = _mm256_set1_ps(ky[0]);
        let (centre0, centre1) = (load(centres.0), load(centres.1));
        let mut acc0: [__m256; V] = std::array::from_fn(|v| _mm256_mul_ps(centre0[v], k0));
        let mut acc1: [__m256; V] = std::array::from_fn(|v| _mm256_mul_ps(centre1[v], k0));
        // up of row y at tap k, and down of row y + 1 at tap k.
        let (mut up0, mut down1) = (centre1, centre0);
        for k in 0..c {
            // SAFETY: k < c = ups.len() = downs.len() and k + 1 <= c < ky.len().
            let (kv, up, down) = unsafe { (*ky.get_unchecked(k + 1), *ups.get_unchecked(k), *downs.get_unchecked(k)) };
            let kv = _mm256_set1_ps(kv);
            let (up1, down0) = (load(up), load(down));
            for v in 0..V {
                acc0[v] = _mm256_fmadd_ps(_mm256_add_ps(up0[v], down0[v]), kv, acc0[v]);
                acc1[v] = _mm256_fmadd_ps(_mm256_add_ps(up1[v], down1[v]), kv, acc1[v]);
            }
            up0 = up1;
            down1 = down0;
        }
        for v in 0..V {
            // SAFETY: x + 8·v + 8 <= w = d0.len() = d1.len().
            unsafe {
                _mm256_storeu_ps(outs.0.add(x + 8 * v), acc0[v]);
                _mm256_storeu_ps(outs.1.add(x + 8 * v), acc1[v]);
            }
        }
    }
}

/// [`column_pair_avx2`]'s operations on plain arrays of `B` pixels, for rows
/// too narrow for its blocks.
#[inline(always)]
fn column_pair_block<const B: usize>(
    x: usize,
    rows: &[&[f32]],
    ky: &[f32],
    d0: &mut [f32],
    d1: &mut [f32],
    fma: &impl Fn(f32, f32, f32) -> f32,
) {
    let c = ky.len() - 1;
    let load = |r: &[f32]| -> [f32; B] {
        let mut v = [0f32; B];
        v.copy_from_slice(&r[x..x + B]);
        v
    };
    let (centre0, centre1) = (load(rows[c]), load(rows[c + 1]));
    let (mut acc0, mut acc1) = ([0f32; B], [0f32; B]);
    for l in 0..B {
        acc0[l] = centre0[l] * ky[0];
        acc1[l] = centre1[l] * ky[0];
    }
    // up of row y at tap k, and down of row y + 1 at tap k.
    let (mut up0, mut down1) = (centre1, centre0);
    for (k, &kv) in ky.iter().enumerate().skip(1) {
        let up1 = load(rows[c + 1 + k]);
        let down0 = load(rows[c - k]);
        for l in 0..B {
            acc0[l] = fma(up0[l] + down0[l], kv, acc0[l]);
            acc1[l] = fma(up1[l] + down1[l], kv, acc1[l]);
        }
        up0 = up1;
        down1 = down0;
    }
    d0[x..x + B].copy_from_slice(&acc0);
    d1[x..x + B].copy_from_slice(&acc1);
}

/// Pixels per block of the two-row column pass: two AVX2 vectors a row
/// (acc, up and down of both rows fill 12 of the 16 registers).
const PAIR_BLOCK: usize = 16;

#[inline(always)]
fn accumulate_column_pair_generic(
    rows: &[&[f32]],
    ky: &[f32],
    d0: &mut [f32],
    d1: &mut [f32],
    fma: impl Fn(f32, f32, f32) -> f32,
) {
    let w = d0.len();
    let (starts, mut x) = blocks(w, PAIR_BLOCK);
    for x in starts {
        column_pair_block::<PAIR_BLOCK>(x, rows, ky, d0, d1, &fma);
    }
    while x < w {
        column_pair_block::<1>(x, rows, ky, d0, d1, &fma);
        x += 1;
    }
}
