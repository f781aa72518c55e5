//! GaussianBlur for f32 images exactly as OpenCV 4.8's generic FilterEngine
//! runs it for SIFT (docs/fidelity.md §SIFT-3): bit-exact kernel, row pass then symmetric
//! column pass, BORDER_REFLECT_101.
//!
//! This file is the algorithm in OpenCV's order and the dispatch: the kernel,
//! the ring of row-pass rows, and the two passes as plain Rust loops (register
//! blocks around OpenCV's per-pixel operation order). The vector kernels live
//! beside it: `x86.rs` (the same loops compiled with AVX2/AVX-512 and FMA, and
//! the AVX2 two-row column pass) and `wasm.rs` (SIMD128 with the exact FMA
//! emulation, or the engine's fused `relaxed_madd`).

use super::image::Plane;
use crate::border::reflect101;

mod generic;
mod kernel;
#[cfg(target_arch = "wasm32")]
mod wasm;
#[cfg(target_arch = "x86_64")]
mod x86;

use generic::{accumulate_column_generic, accumulate_row_generic, BLOCK};
pub use kernel::gaussian_kernel;

/// A plane as the blur reads it: row by row, each row either stored or
/// made on demand into a buffer (the pyramid base's vertical upsampling, so
/// the upsampled plane never goes to memory).
pub trait Rows: Sync {
    fn width(&self) -> usize;
    fn height(&self) -> usize;
    /// Row `y`, from the plane or written into `buf` (`width` floats).
    fn row<'a>(&'a self, y: usize, buf: &'a mut [f32]) -> &'a [f32];
}

impl Rows for Plane {
    fn width(&self) -> usize {
        self.width
    }
    fn height(&self) -> usize {
        self.height
    }
    #[inline]
    fn row<'a>(&'a self, y: usize, _buf: &'a mut [f32]) -> &'a [f32] {
        Plane::row(self, y)
    }
}

/// GaussianBlur(src, σ) with the same σ in x and y.
pub fn gaussian_blur(src: &Plane, sigma: f64) -> Plane {
    gaussian_blur_rows(src, sigma)
}

/// [`gaussian_blur`] of a plane given by its rows.
pub fn gaussian_blur_rows<R: Rows>(src: &R, sigma: f64) -> Plane {
    let (w, h) = (src.width(), src.height());
    let kernel = gaussian_kernel(sigma);
    // A single row or column gets a size-1 kernel on that axis (§SIFT-3, OpenCV's
    // createGaussianKernels special case).
    let kx: Vec<f32> = if w == 1 { vec![1.0] } else { kernel.clone() };
    let ky: Vec<f32> = if h == 1 { vec![1.0] } else { kernel };
    let mut out = Plane::for_overwrite(w, h);
    if w == 0 || h == 0 {
        return out;
    }
    if kx.len() == 1 && ky.len() == 1 {
        let mut buf = vec![0f32; w];
        for (y, row) in out.data.chunks_exact_mut(w).enumerate() {
            row.copy_from_slice(src.row(y, &mut buf));
        }
        return out;
    }
    crate::par::for_each_chunk(&mut out.data, w, |y0, chunk| blur_rows(src, &kx, &ky, y0, chunk));
    out
}

/// Output rows `y0..` (as many as `out` holds) of the separable filter, one
/// row at a time: the row pass of source row y + c goes into a ring of the
/// 2c + 1 latest row-pass rows, then the column pass writes output row y from
/// the ring. The ring (270 KB for the largest first-octave kernel) stays in
/// L2, so nothing is filtered twice and the intermediate rows never go to
/// memory; whole rows keep every stream sequential for the prefetchers. On a
/// KITTI first octave this took 2.5-4.8 ns a pixel per blur on one core,
/// against 3.0-5.9 for bands of 1.5 MB run through by column strips of 1 KB,
/// whose short strided runs the prefetchers followed badly (Zen 3).
fn blur_rows<R: Rows>(src: &R, kx: &[f32], ky: &[f32], y0: usize, out: &mut [f32]) {
    let (w, h) = (src.width(), src.height());
    let (r, c) = (kx.len() / 2, ky.len() / 2);
    let n = out.len() / w;
    // Two output rows at a time where the kernel exists (see
    // `accumulate_column_pair`): the ring then holds their 2c + 2 rows.
    let pairs_mode = column_pairs_available();
    let slots = 2 * c + 1 + pairs_mode as usize;
    // The ring comes from the plane pool (every row is written before it is read).
    let mut ring = super::image::Plane::for_overwrite(slots * w, 1);
    let ring = &mut ring.data;
    let mut padded = vec![0f32; w + 2 * r];
    let mut made = vec![0f32; w];
    // Ring slot of source row v (v may lie outside the image: the column
    // filter's border rule reflects it, so the slot holds a reflected row).
    let slot = |v: isize| v.rem_euclid(slots as isize) as usize;
    // Whether each slot's row is tame (see `wasm::tame`), so the wasm column
    // pass may take its fast path; checked once per row as it is written.
    // (Not needed where the relaxed build has a fused multiply-add.)
    #[cfg(target_arch = "wasm32")]
    let tame_ky = !wasm::fused() && wasm::tame_kernel(&ky[c..]);
    let mut tame = vec![false; slots];
    let mut fill = |ring: &mut [f32], tame: &mut [bool], v: isize| {
        let sl = slot(v);
        let dst = &mut ring[sl * w..(sl + 1) * w];
        row_filter(src.row(reflect101(v, h), &mut made), kx, &mut padded, dst);
        #[cfg(target_arch = "wasm32")]
        {
            tame[sl] = tame_ky && wasm::tame(dst);
        }
        #[cfg(not(target_arch = "wasm32"))]
        {
            tame[sl] = false;
        }
    };
    let first = y0 as isize;
    for v in first - c as isize..first + c as isize {
        fill(ring, &mut tame, v);
    }
    let mut dy = 0;
    while dy < n {
        let y = first + dy as isize;
        if pairs_mode && dy + 1 < n {
            fill(ring, &mut tame, y + c as isize);
            fill(ring, &mut tame, y + c as isize + 1);
            let row = |v: isize| &ring[slot(v) * w..(slot(v) + 1) * w];
            let rows: Vec<&[f32]> = (y - c as isize..=y + c as isize + 1).map(row).collect();
            let (d0, d1) = out[dy * w..(dy + 2) * w].split_at_mut(w);
            accumulate_column_pair(&rows, &ky[c..], d0, d1);
            dy += 2;
            continue;
        }
        fill(ring, &mut tame, y + c as isize);
        let row = |v: isize| &ring[slot(v) * w..(slot(v) + 1) * w];
        let pairs: Vec<(&[f32], &[f32])> = (1..=c as isize).map(|k| (row(y + k), row(y - k))).collect();
        let all_tame = tame.iter().all(|&t| t);
        accumulate_column(row(y), &pairs, &ky[c..], &mut out[dy * w..(dy + 1) * w], all_tame);
        dy += 1;
    }
}

/// Row filter of one row: a plain (non-symmetric) filter accumulated left to
/// right, the first tap a product and every further tap one FMA — the order
/// of OpenCV's AVX2 loop and its GCC-contracted scalar tail (§SIFT-3) — over the row
/// extended by BORDER_REFLECT_101. Interior pixels read the row in place;
/// only the r pixels at each end go through a small reflected copy, so no
/// row is copied whole. Each pixel's taps are
/// the same either way.
fn row_filter(row: &[f32], kx: &[f32], padded: &mut [f32], dst: &mut [f32]) {
    let (w, r) = (row.len(), kx.len() / 2);
    if w > 2 * r {
        accumulate_row(row, kx, &mut dst[r..w - r]);
        // Each end as one whole register block where the row allows, the
        // interior pixels it also covers recomputed from the same source
        // pixels in the same order: r pixels one by one were a chain of 2r+1
        // dependent FMAs each, a third of a KITTI row's time.
        let m = BLOCK.max(r).min(w - r);
        let edge = &mut padded[..m + 2 * r];
        // Pixels −r..m + r of the row: only the r before 0 are reflected
        // (w > 2r, so −j reflects to j), the rest copied as one slice.
        for (j, e) in edge[..r].iter_mut().enumerate() {
            *e = row[r - j];
        }
        edge[r..].copy_from_slice(&row[..m + r]);
        accumulate_row(edge, kx, &mut dst[..m]);
        // Pixels w − m − r..w + r: the r after w − 1 reflect to w − 2 − j.
        edge[..m + r].copy_from_slice(&row[w - m - r..]);
        for (j, e) in edge[m + r..].iter_mut().enumerate() {
            *e = row[w - 2 - j];
        }
        accumulate_row(edge, kx, &mut dst[w - m..]);
    } else {
        for (i, p) in padded.iter_mut().enumerate() {
            *p = row[reflect101(i as isize - r as isize, w)];
        }
        accumulate_row(padded, kx, dst);
    }
}

/// Whether [`accumulate_column_pair`] has a kernel here: AVX2 with FMA
/// without AVX-512 (whose one-row pass takes a row's 16 lanes per load).
fn column_pairs_available() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        crate::simd::avx2_fma() && !crate::simd::avx512f_fma()
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

/// Output rows y and y + 1 of the column pass, from `rows` = the 2c + 2 ring
/// rows y − c ..= y + c + 1 and `ky` = the kernel's centre and right half
/// (the AVX2 kernel reads each ring row once for both output rows).
fn accumulate_column_pair(rows: &[&[f32]], ky: &[f32], d0: &mut [f32], d1: &mut [f32]) {
    #[cfg(target_arch = "x86_64")]
    if crate::simd::avx2_fma() {
        // SAFETY: the CPU has AVX2 and FMA, the kernel's features.
        return unsafe { x86::column_pair_avx2(rows, ky, d0, d1) };
    }
    // Without that kernel (only if the SIMD cap was lowered since
    // `column_pairs_available`): each row on its own, the same taps.
    let c = ky.len() - 1;
    for (rows, dst) in [(&rows[..=2 * c], d0), (&rows[1..], d1)] {
        let pairs: Vec<(&[f32], &[f32])> = (1..=c).map(|k| (rows[c + k], rows[c - k])).collect();
        accumulate_column(rows[c], &pairs, ky, dst, false);
    }
}

/// One row of the row pass (`padded` holds the r pixels before and after
/// `dst`'s), with the fastest kernel this machine has.
fn accumulate_row(padded: &[f32], kx: &[f32], dst: &mut [f32]) {
    #[cfg(target_arch = "x86_64")]
    {
        if crate::simd::avx512f_fma() {
            // SAFETY: the CPU has AVX-512 F, AVX2 and FMA, the kernel's features.
            return unsafe { x86::row_avx512(padded, kx, dst) };
        }
        if crate::simd::avx2_fma() {
            // SAFETY: the CPU has AVX2 and FMA, the kernel's features.
            return unsafe { x86::row_avx2(padded, kx, dst) };
        }
    }
    #[cfg(all(target_arch = "wasm32", feature = "relaxed-simd"))]
    if wasm::fused() {
        return wasm::row_fused(padded, kx, dst);
    }
    #[cfg(target_arch = "wasm32")]
    return if wasm::exact_kernel(kx) && wasm::sixteenths(&padded[..dst.len() + kx.len() - 1]) {
        wasm::row_exact(padded, kx, dst)
    } else if wasm::tame_kernel(kx) && wasm::tame(&padded[..dst.len() + kx.len() - 1]) {
        wasm::row_tame(padded, kx, dst)
    } else {
        wasm::row(padded, kx, dst)
    };
    #[allow(unreachable_code)]
    accumulate_row_generic::<BLOCK>(padded, kx, dst, super::num::fma)
}

/// One row of the column pass with the fastest kernel this machine has.
/// `tame`: every value of the rows is tame (see `wasm::tame`), which lets
/// the wasm column pass take its fast path; native passes ignore it.
fn accumulate_column(centre: &[f32], pairs: &[(&[f32], &[f32])], ky: &[f32], dst: &mut [f32], tame: bool) {
    let _ = tame;
    #[cfg(target_arch = "x86_64")]
    {
        if crate::simd::avx512f_fma() {
            // SAFETY: the CPU has AVX-512 F, AVX2 and FMA, the kernel's features.
            return unsafe { x86::column_avx512(centre, pairs, ky, dst) };
        }
        if crate::simd::avx2_fma() {
            // SAFETY: the CPU has AVX2 and FMA, the kernel's features.
            return unsafe { x86::column_avx2(centre, pairs, ky, dst) };
        }
    }
    #[cfg(all(target_arch = "wasm32", feature = "relaxed-simd"))]
    if wasm::fused() {
        return wasm::column_fused(centre, pairs, ky, dst);
    }
    #[cfg(target_arch = "wasm32")]
    return if tame { wasm::column_tame(centre, pairs, ky, dst) } else { wasm::column(centre, pairs, ky, dst) };
    #[allow(unreachable_code)]
    accumulate_column_generic(centre, pairs, ky, dst, super::num::fma)
}

#[cfg(test)]
mod tests {
    use super::generic::{blocks, two_block_sizes};
    use super::*;

    fn hex(k: &[f32]) -> Vec<u32> {
        k[..k.len() / 2 + 1].iter().map(|v| v.to_bits()).collect()
    }

    #[test]
    fn blocks_cover_the_row_with_one_overlapping_last_block() {
        let run = |w, b| {
            let (starts, rest) = blocks(w, b);
            (starts.collect::<Vec<_>>(), rest)
        };
        assert_eq!(run(10, 4), (vec![0, 4, 6], 10));
        assert_eq!(run(8, 4), (vec![0, 4], 8));
        assert_eq!(run(4, 4), (vec![0], 4));
        assert_eq!(run(3, 4), (vec![], 0));
        assert_eq!(run(2482, 64), ((0..38).map(|i| i * 64).chain([2418]).collect(), 2482));
    }

    #[test]
    fn narrow_rows_take_small_blocks() {
        let run = |w, b| {
            let (big, small, rest) = two_block_sizes(w, b);
            (big.collect::<Vec<_>>(), small.collect::<Vec<_>>(), rest)
        };
        assert_eq!(run(100, 64), (vec![0, 36], vec![], 100));
        assert_eq!(run(40, 64), (vec![], vec![0, 16, 24], 40));
        assert_eq!(run(10, 64), (vec![], vec![], 0));
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
    fn blur_preserves_constant_image_and_mass() {
        let mut p = Plane::new(9, 7);
        p.data.iter_mut().for_each(|v| *v = 100.0);
        let b = gaussian_blur(&p, 1.6);
        for v in &b.data {
            assert!((v - 100.0).abs() < 1e-3, "{v}");
        }
    }
}
