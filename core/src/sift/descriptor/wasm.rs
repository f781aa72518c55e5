//! The descriptor's kernels with WebAssembly SIMD128, four samples a step:
//! the same operations per lane as the scalar loops of `mod.rs`, so the same
//! samples in the same order and the same histogram (docs/fidelity.md
//! §SIFT-11). Sample rows use the FMA
//! of `num::wasm` (fused `relaxed_madd` or the exact emulation); the histogram
//! body has none.

use super::super::num::wasm::{dispatch_fma4, Fma4};
use super::super::num::{load4 as load, store4 as store};
use super::{cell_offsets, Rows, Samples, BINS_PER_DEG, D, HIST_LEN, N};
use core::arch::wasm32::*;

#[inline(always)]
fn lanes(v: v128) -> [f32; 4] {
    [f32x4_extract_lane::<0>(v), f32x4_extract_lane::<1>(v), f32x4_extract_lane::<2>(v), f32x4_extract_lane::<3>(v)]
}

/// Samples `0..` of one window row in blocks of four (the scalar loop
/// does the rest); returns how many columns it examined.
#[inline(always)]
#[allow(clippy::too_many_arguments)] // x86::sample_row's seven, plus the FMA
fn sample_row_with(
    s: &mut Samples,
    [row, up, down]: [&[f32]; 3],
    c0: usize,
    n: usize,
    j0: f32,
    [cos_t, sin_t, a, b]: [f32; 4],
    exp_scale: f32,
    f: impl Fma4,
) -> usize {
    let k = f32x4_splat;
    let lane = f32x4(0.0, 1.0, 2.0, 3.0);
    // Room for every column of the row plus one whole vector.
    let mut len = s.dx.len();
    for v in [&mut s.dx, &mut s.dy, &mut s.w, &mut s.rbin, &mut s.cbin] {
        v.resize(len + n + 4, 0.0);
    }
    let mut t = 0;
    while t + 4 <= n {
        let fj = f32x4_add(k(j0 + t as f32), lane);
        let c_rot = f.fma(fj, k(cos_t), k(a));
        let r_rot = f.fma(fj, k(sin_t), k(b));
        let rbin = f32x4_sub(f32x4_add(r_rot, k(D as f32 / 2.0)), k(0.5));
        let cbin = f32x4_sub(f32x4_add(c_rot, k(D as f32 / 2.0)), k(0.5));
        let inside = v128_and(
            v128_and(f32x4_gt(rbin, k(-1.0)), f32x4_lt(rbin, k(D as f32))),
            v128_and(f32x4_gt(cbin, k(-1.0)), f32x4_lt(cbin, k(D as f32))),
        );
        let m = i32x4_bitmask(inside) as usize;
        if m != 0 {
            let c = c0 + t;
            let dx = f32x4_sub(load(row, c + 1), load(row, c - 1));
            let dy = f32x4_sub(load(up, c), load(down, c));
            let w = f32x4_mul(f.fma(c_rot, c_rot, f32x4_mul(r_rot, r_rot)), k(exp_scale));
            // The kept lanes moved to the front, in order, and stored
            // whole: the lanes past them are overwritten next or cut off.
            let order = COMPRESS[m];
            for (v, x) in [(&mut s.dx, dx), (&mut s.dy, dy), (&mut s.w, w), (&mut s.rbin, rbin), (&mut s.cbin, cbin)] {
                store(v, len, i8x16_swizzle(x, order));
            }
            len += m.count_ones() as usize;
        }
        t += 4;
    }
    for v in [&mut s.dx, &mut s.dy, &mut s.w, &mut s.rbin, &mut s.cbin] {
        v.truncate(len);
    }
    t
}

/// Byte shuffles that move the lanes set in a 4-bit mask to the front.
const COMPRESS: [v128; 16] = {
    let mut table = [u8x16(0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0); 16];
    let mut m = 0;
    while m < 16 {
        let mut bytes = [0u8; 16];
        let (mut lane, mut at) = (0, 0);
        while lane < 4 {
            if m & (1 << lane) != 0 {
                let mut b = 0;
                while b < 4 {
                    bytes[4 * at + b] = (4 * lane + b) as u8;
                    b += 1;
                }
                at += 1;
            }
            lane += 1;
        }
        table[m] = u8x16(
            bytes[0], bytes[1], bytes[2], bytes[3], bytes[4], bytes[5], bytes[6], bytes[7], bytes[8], bytes[9],
            bytes[10], bytes[11], bytes[12], bytes[13], bytes[14], bytes[15],
        );
        m += 1;
    }
    table
};

dispatch_fma4! {
    pub fn sample_row(s: &mut Samples, rows: [&[f32]; 3], c0: usize, n: usize, j0: f32, rot: [f32; 4], exp_scale: f32) -> usize = sample_row_with
}

/// The histogram update of OpenCV's SIMD body, bins and weights of four
/// samples at once, added to the bins sample by sample in order.
pub fn accumulate(s: &Rows, simd_len: usize, ori: f32, hist: &mut [f32; HIST_LEN]) -> usize {
    let k = f32x4_splat;
    let (zero, n_v) = (i32x4_splat(0), i32x4_splat(N as i32));
    let offs = cell_offsets();
    let floor = |v: v128| i32x4_trunc_sat_f32x4(f32x4_floor(v));
    let mut i = 0;
    while i + 4 <= simd_len {
        let (mut rbin, mut cbin) = (load(s.rbin, i), load(s.cbin, i));
        let mut obin = f32x4_mul(f32x4_sub(load(s.ori, i), k(ori)), k(BINS_PER_DEG));
        let mag = f32x4_mul(load(s.mag, i), load(s.wt, i));
        let (r0, c0, mut o0) = (floor(rbin), floor(cbin), floor(obin));
        rbin = f32x4_sub(rbin, f32x4_convert_i32x4(r0));
        cbin = f32x4_sub(cbin, f32x4_convert_i32x4(c0));
        obin = f32x4_sub(obin, f32x4_convert_i32x4(o0));
        o0 = i32x4_add(o0, v128_and(i32x4_lt(o0, zero), n_v));
        o0 = i32x4_sub(o0, v128_and(i32x4_ge(o0, n_v), n_v));
        let v_r1 = f32x4_mul(mag, rbin);
        let v_r0 = f32x4_sub(mag, v_r1);
        let v_rc11 = f32x4_mul(v_r1, cbin);
        let v_rc10 = f32x4_sub(v_r1, v_rc11);
        let v_rc01 = f32x4_mul(v_r0, cbin);
        let v_rc00 = f32x4_sub(v_r0, v_rc01);
        let one = i32x4_splat(1);
        let idx = i32x4_add(
            i32x4_mul(
                i32x4_add(i32x4_mul(i32x4_add(r0, one), i32x4_splat(D as i32 + 2)), i32x4_add(c0, one)),
                i32x4_splat(N as i32 + 2),
            ),
            o0,
        );
        let idx = [
            i32x4_extract_lane::<0>(idx),
            i32x4_extract_lane::<1>(idx),
            i32x4_extract_lane::<2>(idx),
            i32x4_extract_lane::<3>(idx),
        ];
        let mut w = [[0f32; 4]; 8];
        for (c, rc) in [v_rc00, v_rc01, v_rc10, v_rc11].into_iter().enumerate() {
            let rco1 = f32x4_mul(rc, obin);
            w[2 * c] = lanes(f32x4_sub(rc, rco1));
            w[2 * c + 1] = lanes(rco1);
        }
        for l in 0..4 {
            // r0, c0 in [-1, 3] and o0 in [0, 7] keep idx in 0..=287.
            let idx = idx[l].clamp(0, 287) as usize;
            for (c, off) in offs.into_iter().enumerate() {
                hist[idx + off] += w[2 * c][l];
                hist[idx + off + 1] += w[2 * c + 1][l];
            }
        }
        i += 4;
    }
    i
}
