//! One point's windows at one level (docs/fidelity.md §VO-2.4): the 14-bit
//! bilinear weights, the template T and gradients X, Y interpolated from the
//! previous level, the structure tensor, and per iteration the next level's
//! window J and the mismatch vector of J − T, in the f32 accumulation orders
//! of OpenCV's 128-bit SIMD loops.
//!
//! [`Scalar`] computes them as OpenCV writes them. The vector kernels, AVX2
//! and AVX-512 (`x86`) and simd128 (`wasm`), keep 16-bit windows in the
//! layout of `wide` and return the same bits; the tracker picks one kernel
//! set for a whole call.

use super::pyramid::{Deriv, Level};
use super::{FLT_SCALE, WIN};

#[cfg(all(test, target_arch = "x86_64"))]
mod tests;
#[cfg(all(target_arch = "wasm32", target_feature = "simd128"))]
mod wasm;
#[cfg(any(target_arch = "x86_64", all(target_arch = "wasm32", target_feature = "simd128")))]
mod wide;
#[cfg(target_arch = "x86_64")]
mod x86;

#[cfg(all(target_arch = "wasm32", target_feature = "simd128"))]
pub(super) use wasm::Simd128;
#[cfg(target_arch = "x86_64")]
pub(super) use x86::{Avx2, Avx512};

const W_BITS: i32 = 14;
/// Row length of a window buffer: 21 columns padded to three 8-lane blocks.
const WS: usize = 24;
/// A 21×21 window (columns 21..23 are scratch, never summed).
type Win = [[i32; WS]; WIN];

/// The four 14-bit bilinear weights OpenCV derives from the fractional part
/// (each product an f32 operation in source order, rounded half-even:
/// §VO-2.4 "Bilinear weights"; rounding half away moved 1 % of the points,
/// §VO-2.7).
#[inline(always)]
pub(super) fn weights(a: f32, b: f32) -> [i32; 4] {
    let one = (1i32 << W_BITS) as f32;
    let w00 = ((1.0 - a) * (1.0 - b) * one).round_ties_even() as i32;
    let w01 = (a * (1.0 - b) * one).round_ties_even() as i32;
    let w10 = ((1.0 - a) * b * one).round_ties_even() as i32;
    [w00, w01, w10, (1 << W_BITS) - w00 - w01 - w10]
}

/// Interpolates a 21×21 window of a padded u8 level at top-left `(ix, iy)`
/// into values ×32 (`CV_DESCALE(..., W_BITS - 5)`, §VO-2.4 "Template patch").
#[inline(always)]
fn warp_window(level: &Level, ix: i32, iy: i32, w: &[i32; 4], out: &mut Win) {
    let stride = level.stride;
    let base = level.offset(ix, iy);
    for (y, row) in out.iter_mut().enumerate() {
        let r0 = &level.padded[base + y * stride..][..WIN + 1];
        let r1 = &level.padded[base + (y + 1) * stride..][..WIN + 1];
        for x in 0..WIN {
            let v = r0[x] as i32 * w[0] + r0[x + 1] as i32 * w[1] + r1[x] as i32 * w[2] + r1[x + 1] as i32 * w[3];
            row[x] = (v + (1 << (W_BITS - 5 - 1))) >> (W_BITS - 5);
        }
    }
}

#[inline(always)]
fn warp_deriv(plane: &[i16], stride: usize, base: usize, w: &[i32; 4], out: &mut Win) {
    for (y, row) in out.iter_mut().enumerate() {
        let r0 = &plane[base + y * stride..][..WIN + 1];
        let r1 = &plane[base + (y + 1) * stride..][..WIN + 1];
        for x in 0..WIN {
            let v = r0[x] as i32 * w[0] + r0[x + 1] as i32 * w[1] + r1[x] as i32 * w[2] + r1[x + 1] as i32 * w[3];
            row[x] = (v + (1 << (W_BITS - 1))) >> W_BITS;
        }
    }
}

/// The three structure-tensor sums over the window in the order OpenCV's
/// SSE loop plus scalar tail produce (§VO-2.4 "Structure tensor"): columns
/// 0..15 into four f32 lanes (column c → lane c mod 4, columns in increasing
/// order), columns 16..20 into a scalar, then `S + ((L0 + L2) + (L1 + L3))`.
#[inline(always)]
fn tensor_sums(gx: &Win, gy: &Win) -> (f32, f32, f32) {
    let (mut l11, mut l12, mut l22) = ([0f32; 4], [0f32; 4], [0f32; 4]);
    let (mut s11, mut s12, mut s22) = (0f32, 0f32, 0f32);
    for (rx, ry) in gx.iter().zip(gy) {
        for k in 0..4 {
            for l in 0..4 {
                let c = 4 * k + l;
                l11[l] += (rx[c] * rx[c]) as f32;
                l12[l] += (rx[c] * ry[c]) as f32;
                l22[l] += (ry[c] * ry[c]) as f32;
            }
        }
        for c in 16..WIN {
            s11 += (rx[c] * rx[c]) as f32;
            s12 += (rx[c] * ry[c]) as f32;
            s22 += (ry[c] * ry[c]) as f32;
        }
    }
    let total = |s: f32, l: [f32; 4]| s + ((l[0] + l[2]) + (l[1] + l[3]));
    (total(s11, l11), total(s12, l12), total(s22, l22))
}

/// The mismatch vector (b1, b2) in OpenCV's SIMD order (§VO-2.4 step 3): pairs
/// of products `d(c)·Z(c) + d(c+4)·Z(c+4)` added as exact integers, then
/// rounded into eight f32 lanes (P0..P3 = x/y of columns B, B+1; Q0..Q3 =
/// x/y of columns B+2, B+3); columns 16..20 into two scalars.
#[inline(always)]
fn mismatch(d: &Win, gx: &Win, gy: &Win) -> (f32, f32) {
    let mut pq = [0f32; 8];
    let (mut s1, mut s2) = (0f32, 0f32);
    for y in 0..WIN {
        let (dr, xr, yr) = (&d[y], &gx[y], &gy[y]);
        // Exact integer products first (vectorizes), then the pair sums.
        let mut px = [0i32; 16];
        let mut py = [0i32; 16];
        for c in 0..16 {
            px[c] = dr[c] * xr[c];
            py[c] = dr[c] * yr[c];
        }
        for base in [0usize, 8] {
            let mut u = [0f32; 8];
            for k in 0..4 {
                let c = base + k;
                u[2 * k] = (px[c] + px[c + 4]) as f32;
                u[2 * k + 1] = (py[c] + py[c + 4]) as f32;
            }
            for k in 0..8 {
                pq[k] += u[k];
            }
        }
        for c in 16..WIN {
            s1 += (dr[c] * xr[c]) as f32;
            s2 += (dr[c] * yr[c]) as f32;
        }
    }
    let t = [pq[0] + pq[4], pq[1] + pq[5], pq[2] + pq[6], pq[3] + pq[7]];
    ((s1 + (t[0] + t[2])) * FLT_SCALE, (s2 + (t[1] + t[3])) * FLT_SCALE)
}

/// The window kernels of one point and level. [`Scalar`] is the reference
/// (and what wasm without SIMD runs); `x86::Avx2`, `x86::Avx512` and
/// `wasm::Simd128` keep 16-bit windows in the column layout of `wide` and get
/// the same bits.
pub(super) trait Kernels {
    /// The template and gradient windows of one point at one level.
    type Patch: NewBoxed;
    fn new_patch() -> Box<Self::Patch> {
        Self::Patch::new_boxed()
    }
    /// Interpolates T, X, Y at `(ix, iy)` of the previous level and returns
    /// the structure-tensor sums (ΣX², ΣXY, ΣY²) in OpenCV's order.
    fn load_patch(
        prev: &Level,
        deriv: &Deriv,
        ix: i32,
        iy: i32,
        w: &[i32; 4],
        patch: &mut Self::Patch,
    ) -> (f32, f32, f32);
    /// The mismatch vector (b1, b2) of the next-level window at `(jx, jy)`.
    fn mismatch(next: &Level, jx: i32, jy: i32, w: &[i32; 4], patch: &mut Self::Patch) -> (f32, f32);
    /// Σ|J − T| over the window (exact: it stays below 2^24).
    fn abs_diff_sum(next: &Level, jx: i32, jy: i32, w: &[i32; 4], patch: &mut Self::Patch) -> f32;
}

/// A kernel set's window buffers, allocated zeroed on the heap: the x86 and
/// wasm kernels share `wide::Patch`, so its allocation is written once.
pub(super) trait NewBoxed {
    fn new_boxed() -> Box<Self>;
}

/// Window buffers reused across points (every element is written before
/// it is read).
pub(super) struct Scratch {
    tmpl: Win,
    gx: Win,
    gy: Win,
    warped: Win,
}

impl NewBoxed for Scratch {
    fn new_boxed() -> Box<Scratch> {
        Box::new(Scratch { tmpl: [[0; WS]; WIN], gx: [[0; WS]; WIN], gy: [[0; WS]; WIN], warped: [[0; WS]; WIN] })
    }
}

pub(super) struct Scalar;

impl Kernels for Scalar {
    type Patch = Scratch;

    #[inline(always)]
    fn load_patch(prev: &Level, deriv: &Deriv, ix: i32, iy: i32, w: &[i32; 4], s: &mut Scratch) -> (f32, f32, f32) {
        warp_window(prev, ix, iy, w, &mut s.tmpl);
        let dbase = deriv.offset(ix, iy);
        warp_deriv(&deriv.ix, deriv.stride, dbase, w, &mut s.gx);
        warp_deriv(&deriv.iy, deriv.stride, dbase, w, &mut s.gy);
        tensor_sums(&s.gx, &s.gy)
    }

    #[inline(always)]
    fn mismatch(next: &Level, jx: i32, jy: i32, w: &[i32; 4], s: &mut Scratch) -> (f32, f32) {
        warp_window(next, jx, jy, w, &mut s.warped);
        for (wr, tr) in s.warped.iter_mut().zip(s.tmpl.iter()) {
            for (v, t) in wr.iter_mut().zip(tr) {
                *v -= t;
            }
        }
        mismatch(&s.warped, &s.gx, &s.gy)
    }

    #[inline(always)]
    fn abs_diff_sum(next: &Level, jx: i32, jy: i32, w: &[i32; 4], s: &mut Scratch) -> f32 {
        warp_window(next, jx, jy, w, &mut s.warped);
        let mut errval = 0f32;
        for (wr, tr) in s.warped.iter().zip(s.tmpl.iter()) {
            for (v, t) in wr[..WIN].iter().zip(&tr[..WIN]) {
                errval += (v - t).abs() as f32;
            }
        }
        errval
    }
}
