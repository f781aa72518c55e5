//! GaussianBlur for f32 images exactly as OpenCV 4.8's generic FilterEngine
//! runs it for SIFT (spec §3): bit-exact kernel, row pass then symmetric
//! column pass, BORDER_REFLECT_101.

use super::image::Plane;
use super::num::rne64;

/// `getGaussianKernelBitExact` for an f32 image: `ksize = rne(8σ + 1) | 1`
/// (the factor 4 because the depth is not 8U), weights computed in f64 and
/// rounded once to f32.
pub fn gaussian_kernel(sigma: f64) -> Vec<f32> {
    let n = (rne64(sigma * 4.0 * 2.0 + 1.0) | 1) as usize;
    let h = (n - 1) / 2;
    let scale2x = -0.125 / (sigma * sigma);
    let v: Vec<f64> = (0..h)
        .map(|i| {
            let x = 2.0 * i as f64 - (n as f64 - 1.0);
            (x * x * scale2x).exp()
        })
        .collect();
    let mut sum = 0.0f64;
    for &vi in &v {
        sum += vi;
    }
    let mul = 1.0 / (sum * 2.0 + 1.0);
    let mut k = vec![0f32; n];
    for i in 0..h {
        k[i] = (v[i] * mul) as f32;
        k[n - 1 - i] = k[i];
    }
    k[h] = mul as f32;
    k
}

/// BORDER_REFLECT_101, repeated until inside: the top octaves can be
/// narrower than the kernel radius.
#[inline]
fn reflect101(mut p: isize, len: usize) -> usize {
    if len == 1 {
        return 0;
    }
    let len = len as isize;
    while p < 0 || p >= len {
        p = if p < 0 { -p } else { 2 * (len - 1) - p };
    }
    p as usize
}

/// GaussianBlur(src, σ) with the same σ in x and y.
pub fn gaussian_blur(src: &Plane, sigma: f64) -> Plane {
    let (w, h) = (src.width, src.height);
    let kernel = gaussian_kernel(sigma);
    // A single row or column gets a size-1 kernel on that axis (OpenCV's
    // createGaussianKernels special case).
    let kx: Vec<f32> = if w == 1 { vec![1.0] } else { kernel.clone() };
    let ky: Vec<f32> = if h == 1 { vec![1.0] } else { kernel };
    let mut out = Plane::for_overwrite(w, h);
    if w == 0 || h == 0 {
        return out;
    }
    if kx.len() == 1 && ky.len() == 1 {
        out.data.copy_from_slice(&src.data);
        return out;
    }
    super::par::for_each_chunk(&mut out.data, w, |y0, chunk| blur_rows(src, &kx, &ky, y0, chunk));
    out
}

/// Output rows `y0..` (as many as `out` holds) of the separable filter, in
/// bands: the row pass of the band's source rows (its 2c neighbours above
/// and below included) goes to a buffer that stays in L2, then the column
/// pass reads it from there. Two passes over a whole intermediate plane
/// would move 15 MB more per blur of a KITTI first octave through memory,
/// which bounds this stage on a 2-core machine.
fn blur_rows(src: &Plane, kx: &[f32], ky: &[f32], y0: usize, out: &mut [f32]) {
    let (w, h) = (src.width, src.height);
    let (r, c) = (kx.len() / 2, ky.len() / 2);
    let n = out.len() / w;
    let band = (BAND_BYTES / (4 * w)).saturating_sub(2 * c).max(16);
    // The band buffer comes from the plane pool (every row is written before
    // it is read): a fresh 1.5 MB allocation per call was zeroed page by page.
    let mut buf = super::image::Plane::for_overwrite((band.min(n) + 2 * c) * w, 1);
    let buf = &mut buf.data;
    let mut padded = vec![0f32; w + 2 * r];
    for b0 in (0..n).step_by(band) {
        let b1 = (b0 + band).min(n);
        let (ya, yb) = ((y0 + b0) as isize, (y0 + b1) as isize);
        // Buffer row j holds the row pass of source row ya − c + j, reflected
        // into the image as the column filter's border rule does.
        for (j, v) in (ya - c as isize..yb + c as isize).enumerate() {
            row_filter(src.row(reflect101(v, h)), kx, &mut padded, &mut buf[j * w..(j + 1) * w]);
        }
        let row = |m: usize, x0: usize, x1: usize| &buf[m * w + x0..m * w + x1];
        let mut pairs: Vec<(&[f32], &[f32])> = Vec::with_capacity(c);
        // Vertical strips narrow enough that the 2c+1 source rows of one
        // output row stay in L1 while the next row reuses 2c of them.
        for x0 in (0..w).step_by(STRIP) {
            let x1 = (x0 + STRIP).min(w);
            for dy in b0..b1 {
                let m = dy - b0 + c;
                pairs.clear();
                pairs.extend((1..=c).map(|k| (row(m + k, x0, x1), row(m - k, x0, x1))));
                accumulate_column(row(m, x0, x1), &pairs, &ky[c..], &mut out[dy * w + x0..dy * w + x1]);
            }
        }
    }
}

/// Bytes of row-pass buffer per band (a share of a 2 MB L2).
const BAND_BYTES: usize = 1_500_000;

/// Row filter of one row: a plain (non-symmetric) filter accumulated left to
/// right, the first tap a product and every further tap one FMA — the order
/// of OpenCV's AVX2 loop and its GCC-contracted scalar tail — over the row
/// extended by BORDER_REFLECT_101. Interior pixels read the row in place;
/// only the r pixels at each end go through a small reflected copy (copying
/// every row first was 3 % of a VO frame's CPU time). Each pixel's taps are
/// the same either way.
fn row_filter(row: &[f32], kx: &[f32], padded: &mut [f32], dst: &mut [f32]) {
    let (w, r) = (row.len(), kx.len() / 2);
    if w > 2 * r {
        accumulate_row(row, kx, &mut dst[r..w - r]);
        let edge = &mut padded[..3 * r];
        for (i, e) in edge.iter_mut().enumerate() {
            *e = row[reflect101(i as isize - r as isize, w)];
        }
        accumulate_row(edge, kx, &mut dst[..r]);
        for (i, e) in edge.iter_mut().enumerate() {
            *e = row[reflect101((w - 2 * r + i) as isize, w)];
        }
        accumulate_row(edge, kx, &mut dst[w - r..]);
    } else {
        for (i, p) in padded.iter_mut().enumerate() {
            *p = row[reflect101(i as isize - r as isize, w)];
        }
        accumulate_row(padded, kx, dst);
    }
}

/// Columns per strip of the column pass (1 KB of each row).
const STRIP: usize = 256;

// The accumulation loops keep a block of output pixels in registers while
// every tap is applied (x blocks outer, taps inner), so each tap costs one
// load and one FMA per vector instead of a load-modify-store of the output;
// each pixel still sees its taps in OpenCV's order, so results are unchanged.
// On x86-64 they are compiled again with FMA (AVX2, and AVX-512 where the CPU
// has it) and picked at run time, because `mul_add` without the `fma` target
// feature is a library call per tap. On wasm the FMA is `num::fma`.

/// Pixels per register block: 4 AVX-512 or 8 AVX2 vectors; the rest of a
/// row goes in blocks of one AVX-512 vector, then pixel by pixel.
const BLOCK: usize = 64;
const SMALL_BLOCK: usize = 16;

#[inline(always)]
fn row_block<const B: usize>(src: &[f32], kx: &[f32], dst: &mut [f32], fma: &impl Fn(f32, f32, f32) -> f32) {
    let mut acc = [0f32; B];
    for (a, &s) in acc.iter_mut().zip(&src[..B]) {
        *a = s * kx[0];
    }
    for (k, &kv) in kx.iter().enumerate().skip(1) {
        for (a, &s) in acc.iter_mut().zip(&src[k..k + B]) {
            *a = fma(s, kv, *a);
        }
    }
    dst[..B].copy_from_slice(&acc);
}

#[inline(always)]
fn accumulate_row_generic<const B: usize>(padded: &[f32], kx: &[f32], dst: &mut [f32], fma: impl Fn(f32, f32, f32) -> f32) {
    let w = dst.len();
    let mut x = 0;
    while x + B <= w {
        row_block::<B>(&padded[x..], kx, &mut dst[x..], &fma);
        x += B;
    }
    while x + SMALL_BLOCK <= w {
        row_block::<SMALL_BLOCK>(&padded[x..], kx, &mut dst[x..], &fma);
        x += SMALL_BLOCK;
    }
    for (i, d) in dst.iter_mut().enumerate().skip(x) {
        let mut a = padded[i] * kx[0];
        for (k, &kv) in kx.iter().enumerate().skip(1) {
            a = fma(padded[i + k], kv, a);
        }
        *d = a;
    }
}

#[inline(always)]
fn column_block<const B: usize>(
    x: usize,
    centre: &[f32],
    pairs: &[(&[f32], &[f32])],
    ky: &[f32],
    dst: &mut [f32],
    fma: &impl Fn(f32, f32, f32) -> f32,
) {
    let mut acc = [0f32; B];
    for (a, &s) in acc.iter_mut().zip(&centre[x..x + B]) {
        *a = s * ky[0];
    }
    for (k, (up, down)) in pairs.iter().enumerate() {
        let kv = ky[k + 1];
        for ((a, &u), &d) in acc.iter_mut().zip(&up[x..x + B]).zip(&down[x..x + B]) {
            *a = fma(u + d, kv, *a);
        }
    }
    dst[x..x + B].copy_from_slice(&acc);
}

#[inline(always)]
fn accumulate_column_generic(
    centre: &[f32],
    pairs: &[(&[f32], &[f32])],
    ky: &[f32],
    dst: &mut [f32],
    fma: impl Fn(f32, f32, f32) -> f32,
) {
    let w = dst.len();
    let mut x = 0;
    while x + BLOCK <= w {
        column_block::<BLOCK>(x, centre, pairs, ky, dst, &fma);
        x += BLOCK;
    }
    while x + SMALL_BLOCK <= w {
        column_block::<SMALL_BLOCK>(x, centre, pairs, ky, dst, &fma);
        x += SMALL_BLOCK;
    }
    for i in x..w {
        let mut a = centre[i] * ky[0];
        for (k, (up, down)) in pairs.iter().enumerate() {
            a = fma(up[i] + down[i], ky[k + 1], a);
        }
        dst[i] = a;
    }
}

#[cfg(target_arch = "x86_64")]
mod x86 {
    #[target_feature(enable = "avx2,fma")]
    pub unsafe fn row_avx2(padded: &[f32], kx: &[f32], dst: &mut [f32]) {
        super::accumulate_row_generic::<{ super::BLOCK }>(padded, kx, dst, f32::mul_add)
    }

    /// Eight independent accumulators: each tap is one load and one FMA per
    /// vector, so with four the FMA latency (4 cycles) would be the limit.
    #[target_feature(enable = "avx512f,avx2,fma")]
    pub unsafe fn row_avx512(padded: &[f32], kx: &[f32], dst: &mut [f32]) {
        super::accumulate_row_generic::<{ 2 * super::BLOCK }>(padded, kx, dst, f32::mul_add)
    }

    #[target_feature(enable = "avx2,fma")]
    pub unsafe fn column_avx2(centre: &[f32], pairs: &[(&[f32], &[f32])], ky: &[f32], dst: &mut [f32]) {
        super::accumulate_column_generic(centre, pairs, ky, dst, f32::mul_add)
    }

    #[target_feature(enable = "avx512f,avx2,fma")]
    pub unsafe fn column_avx512(centre: &[f32], pairs: &[(&[f32], &[f32])], ky: &[f32], dst: &mut [f32]) {
        super::accumulate_column_generic(centre, pairs, ky, dst, f32::mul_add)
    }
}

/// WebAssembly: four pixels per vector with the lane-wise exact FMA
/// emulation, four vectors per block; the rest of the row pixel by pixel.
#[cfg(target_arch = "wasm32")]
mod wasm {
    use super::super::num::{fma, fma_emulated_x4};
    use core::arch::wasm32::*;

    const V: usize = 4; // vectors per block

    fn load(s: &[f32], i: usize) -> v128 {
        let s = &s[i..i + 4];
        // SAFETY: `s` holds exactly four f32; v128_load needs no alignment.
        unsafe { v128_load(s.as_ptr().cast()) }
    }

    fn store(d: &mut [f32], i: usize, v: v128) {
        let d = &mut d[i..i + 4];
        // SAFETY: `d` holds exactly four f32; v128_store needs no alignment.
        unsafe { v128_store(d.as_mut_ptr().cast(), v) }
    }

    pub fn row(padded: &[f32], kx: &[f32], dst: &mut [f32]) {
        let w = dst.len();
        let mut x = 0;
        while x + 4 * V <= w {
            let k0 = f32x4_splat(kx[0]);
            let mut acc: [v128; V] = core::array::from_fn(|v| f32x4_mul(load(padded, x + 4 * v), k0));
            for (k, &kv) in kx.iter().enumerate().skip(1) {
                for (v, a) in acc.iter_mut().enumerate() {
                    *a = fma_emulated_x4(load(padded, x + k + 4 * v), kv, *a);
                }
            }
            for (v, a) in acc.into_iter().enumerate() {
                store(dst, x + 4 * v, a);
            }
            x += 4 * V;
        }
        for i in x..w {
            let mut a = padded[i] * kx[0];
            for (k, &kv) in kx.iter().enumerate().skip(1) {
                a = fma(padded[i + k], kv, a);
            }
            dst[i] = a;
        }
    }

    pub fn column(centre: &[f32], pairs: &[(&[f32], &[f32])], ky: &[f32], dst: &mut [f32]) {
        let w = dst.len();
        let mut x = 0;
        while x + 4 * V <= w {
            let kc = f32x4_splat(ky[0]);
            let mut acc: [v128; V] = core::array::from_fn(|v| f32x4_mul(load(centre, x + 4 * v), kc));
            for (k, (up, down)) in pairs.iter().enumerate() {
                for (v, a) in acc.iter_mut().enumerate() {
                    let sum = f32x4_add(load(up, x + 4 * v), load(down, x + 4 * v));
                    *a = fma_emulated_x4(sum, ky[k + 1], *a);
                }
            }
            for (v, a) in acc.into_iter().enumerate() {
                store(dst, x + 4 * v, a);
            }
            x += 4 * V;
        }
        for i in x..w {
            let mut a = centre[i] * ky[0];
            for (k, (up, down)) in pairs.iter().enumerate() {
                a = fma(up[i] + down[i], ky[k + 1], a);
            }
            dst[i] = a;
        }
    }
}

fn accumulate_row(padded: &[f32], kx: &[f32], dst: &mut [f32]) {
    #[cfg(target_arch = "x86_64")]
    {
        // SAFETY (both calls): the CPU supports the features the function was compiled for.
        if std::is_x86_feature_detected!("avx512f") && std::is_x86_feature_detected!("fma") {
            return unsafe { x86::row_avx512(padded, kx, dst) };
        }
        if std::is_x86_feature_detected!("fma") && std::is_x86_feature_detected!("avx2") {
            return unsafe { x86::row_avx2(padded, kx, dst) };
        }
    }
    #[cfg(target_arch = "wasm32")]
    return wasm::row(padded, kx, dst);
    #[allow(unreachable_code)]
    accumulate_row_generic::<BLOCK>(padded, kx, dst, super::num::fma)
}

fn accumulate_column(centre: &[f32], pairs: &[(&[f32], &[f32])], ky: &[f32], dst: &mut [f32]) {
    #[cfg(target_arch = "x86_64")]
    {
        // SAFETY (both calls): the CPU supports the features the function was compiled for.
        if std::is_x86_feature_detected!("avx512f") && std::is_x86_feature_detected!("fma") {
            return unsafe { x86::column_avx512(centre, pairs, ky, dst) };
        }
        if std::is_x86_feature_detected!("fma") && std::is_x86_feature_detected!("avx2") {
            return unsafe { x86::column_avx2(centre, pairs, ky, dst) };
        }
    }
    #[cfg(target_arch = "wasm32")]
    return wasm::column(centre, pairs, ky, dst);
    #[allow(unreachable_code)]
    accumulate_column_generic(centre, pairs, ky, dst, super::num::fma)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn hex(k: &[f32]) -> Vec<u32> {
        k[..k.len() / 2 + 1].iter().map(|v| v.to_bits()).collect()
    }

    #[test]
    fn kernels_match_appendix_b() {
        let base = 1.2489997f32 as f64;
        assert_eq!(
            hex(&gaussian_kernel(base)),
            [0x38ddd952, 0x3af825b8, 0x3c9234fd, 0x3db581b9, 0x3e6d6298, 0x3ea389e6]
        );
        assert_eq!(
            hex(&gaussian_kernel(1.5450077936447955)),
            [0x390fc865, 0x3ab40040, 0x3c14382a, 0x3d208e6a, 0x3de4cae5, 0x3e567243, 0x3e84353b]
        );
        let k5 = gaussian_kernel(3.090015587289591);
        assert_eq!(k5.len(), 27);
        assert_eq!(hex(&k5)[13], 0x3e0434fb);
        assert_eq!(hex(&k5)[0], 0x379b5026);
    }

    #[test]
    fn reflect101_repeats_on_tiny_images() {
        assert_eq!(reflect101(-1, 5), 1);
        assert_eq!(reflect101(5, 5), 3);
        assert_eq!(reflect101(-7, 3), 1); // 7 -> 4-7=-3 -> 3 -> 1
        assert_eq!(reflect101(4, 1), 0);
    }

    #[test]
    fn blur_preserves_constant_image_and_mass() {
        let mut p = Plane::new(9, 7);
        p.data.iter_mut().for_each(|v| *v = 100.0);
        let b = gaussian_blur(&p, 1.6);
        for v in &b.data {
            assert!((v - 100.0).abs() < 1e-3, "{v}");
        }
    }
}
