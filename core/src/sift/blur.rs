//! GaussianBlur for f32 images exactly as OpenCV 4.8's generic FilterEngine
//! runs it for SIFT (docs/fidelity.md §SIFT-3): bit-exact kernel, row pass then symmetric
//! column pass, BORDER_REFLECT_101.

use super::image::Plane;
use super::num::rne64;
use crate::border::reflect101;

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
    // A single row or column gets a size-1 kernel on that axis (OpenCV's
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
    super::par::for_each_chunk(&mut out.data, w, |y0, chunk| blur_rows(src, &kx, &ky, y0, chunk));
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
/// of OpenCV's AVX2 loop and its GCC-contracted scalar tail — over the row
/// extended by BORDER_REFLECT_101. Interior pixels read the row in place;
/// only the r pixels at each end go through a small reflected copy (copying
/// every row first was 3 % of a VO frame's CPU time). Each pixel's taps are
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

/// Starts of blocks `x..x + b` covering `0..w`: one after another, the last
/// ending at `w` and overlapping the one before (each pixel's value depends
/// only on its own taps, so the overlap is recomputed identically, where a
/// lone pixel would cost a chain of dependent FMAs); and where the uncovered
/// rest starts: `w`, or 0 when `w < b`. (No closure: a closure here would be
/// compiled apart from its caller, without the caller's FMA feature.)
#[inline(always)]
fn blocks(w: usize, b: usize) -> (impl Iterator<Item = usize>, usize) {
    let whole = if w < b { 0 } else { w / b };
    let last = (w >= b && w % b != 0).then_some(w.wrapping_sub(b));
    ((0..whole).map(move |i| i * b).chain(last), if w < b { 0 } else { w })
}

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
fn accumulate_row_generic<const B: usize>(
    padded: &[f32],
    kx: &[f32],
    dst: &mut [f32],
    fma: impl Fn(f32, f32, f32) -> f32,
) {
    let w = dst.len();
    let (starts, mut x) = blocks(w, B);
    for x in starts {
        row_block::<B>(&padded[x..], kx, &mut dst[x..], &fma);
    }
    if x == 0 {
        let (starts, rest) = blocks(w, SMALL_BLOCK);
        for x in starts {
            row_block::<SMALL_BLOCK>(&padded[x..], kx, &mut dst[x..], &fma);
        }
        x = rest;
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
    let (starts, mut x) = blocks(w, BLOCK);
    for x in starts {
        column_block::<BLOCK>(x, centre, pairs, ky, dst, &fma);
    }
    if x == 0 {
        let (starts, rest) = blocks(w, SMALL_BLOCK);
        for x in starts {
            column_block::<SMALL_BLOCK>(x, centre, pairs, ky, dst, &fma);
        }
        x = rest;
    }
    for i in x..w {
        let mut a = centre[i] * ky[0];
        for (k, (up, down)) in pairs.iter().enumerate() {
            a = fma(up[i] + down[i], ky[k + 1], a);
        }
        dst[i] = a;
    }
}

/// Output rows y and y + 1 of the column pass at once, from `rows` = the
/// 2c + 2 ring rows y − c ..= y + c + 1 and `ky` = the kernel's centre and
/// right half. Row y + 1's taps reuse row y's loads shifted by one tap
/// (R[y+1+k] is R[y+(k+1)], R[y+1−k] is R[y−(k−1)]), so a tap costs two
/// loads per vector for both rows instead of two per row: the ring is read
/// from L2, and that read bounded the one-row pass. Each pixel still sees
/// OpenCV's operations in OpenCV's order: centre·k0, then fma(up + down, kk, acc)
/// for k = 1..=c.
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

fn accumulate_column_pair(rows: &[&[f32]], ky: &[f32], d0: &mut [f32], d1: &mut [f32]) {
    #[cfg(target_arch = "x86_64")]
    if crate::simd::avx2_fma() {
        // SAFETY: the CPU supports the features the function was compiled for.
        return unsafe { x86::column_pair_avx2(rows, ky, d0, d1) };
    }
    accumulate_column_pair_generic(rows, ky, d0, d1, super::num::fma)
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

    /// [`super::column_pair_block`] in intrinsics, three vectors a row (the
    /// generic form compiled to partial-vector shuffles for its carried
    /// arrays): acc, up and down of both rows take 12 registers.
    #[target_feature(enable = "avx2,fma")]
    pub unsafe fn column_pair_avx2(rows: &[&[f32]], ky: &[f32], d0: &mut [f32], d1: &mut [f32]) {
        let (c, w) = (ky.len() - 1, d0.len());
        assert!(rows.len() == 2 * c + 2 && d1.len() == w && rows.iter().all(|r| r.len() >= w));
        if w < 8 * PAIR_V || c > MAX_HALF {
            return super::accumulate_column_pair_generic(rows, ky, d0, d1, f32::mul_add);
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
        let centres = (rows[c].as_ptr(), rows[c + 1].as_ptr());
        let outs = (d0.as_mut_ptr(), d1.as_mut_ptr());
        for x in super::blocks(w, 8 * PAIR_V).0 {
            // The output rows are fresh memory: without asking for their
            // lines ahead, each block's stores waited on those lines being
            // read in (over a quarter of this function's time); with it, a
            // first-octave blur took about a tenth less.
            if x + PREFETCH_AHEAD + 16 < w {
                for o in [outs.0, outs.1] {
                    _mm_prefetch::<_MM_HINT_ET0>(o.add(x + PREFETCH_AHEAD) as *const i8);
                    _mm_prefetch::<_MM_HINT_ET0>(o.add(x + PREFETCH_AHEAD + 16) as *const i8);
                }
            }
            pair_block(centres, &ups[..c], &downs[..c], ky, x, outs);
        }
    }

    use std::arch::x86_64::{_mm_prefetch, _MM_HINT_ET0};

    /// AVX2 vectors a row in [`column_pair_avx2`]'s blocks.
    const PAIR_V: usize = 3;
    /// Largest kernel half-width the AVX2 pair pass takes (SIFT's largest is 12).
    const MAX_HALF: usize = 32;
    /// How far ahead of a block its output lines are asked for, in pixels
    /// (512 bytes, five blocks; 64 to 512 all helped, 128–256 most).
    const PREFETCH_AHEAD: usize = 128;

    /// Pixels x..x + 24 of output rows y and y + 1 (`outs`): `centres` are
    /// ring rows y and y + 1, `ups[k − 1]` and `downs[k − 1]` rows y + 1 + k
    /// and y − k. Inlined there, so compiled with its features; every row
    /// holds x + 24 pixels (checked by the caller).
    #[inline(always)]
    unsafe fn pair_block(
        centres: (*const f32, *const f32),
        ups: &[*const f32],
        downs: &[*const f32],
        ky: &[f32],
        x: usize,
        outs: (*mut f32, *mut f32),
    ) {
        use std::arch::x86_64::*;
        const V: usize = PAIR_V;
        let load = |r: *const f32| -> [__m256; V] { std::array::from_fn(|v| _mm256_loadu_ps(r.add(x + 8 * v))) };
        let k0 = _mm256_set1_ps(ky[0]);
        let (centre0, centre1) = (load(centres.0), load(centres.1));
        let mut acc0: [__m256; V] = std::array::from_fn(|v| _mm256_mul_ps(centre0[v], k0));
        let mut acc1: [__m256; V] = std::array::from_fn(|v| _mm256_mul_ps(centre1[v], k0));
        // up of row y at tap k, and down of row y + 1 at tap k.
        let (mut up0, mut down1) = (centre1, centre0);
        for k in 0..ups.len() {
            let kv = _mm256_set1_ps(*ky.get_unchecked(k + 1));
            let up1 = load(*ups.get_unchecked(k));
            let down0 = load(*downs.get_unchecked(k));
            for v in 0..V {
                acc0[v] = _mm256_fmadd_ps(_mm256_add_ps(up0[v], down0[v]), kv, acc0[v]);
                acc1[v] = _mm256_fmadd_ps(_mm256_add_ps(up1[v], down1[v]), kv, acc1[v]);
            }
            up0 = up1;
            down1 = down0;
        }
        for v in 0..V {
            _mm256_storeu_ps(outs.0.add(x + 8 * v), acc0[v]);
            _mm256_storeu_ps(outs.1.add(x + 8 * v), acc1[v]);
        }
    }

    #[target_feature(enable = "avx512f,avx2,fma")]
    pub unsafe fn column_avx512(centre: &[f32], pairs: &[(&[f32], &[f32])], ky: &[f32], dst: &mut [f32]) {
        super::accumulate_column_generic(centre, pairs, ky, dst, f32::mul_add)
    }
}

/// WebAssembly: four pixels per vector with the lane-wise exact FMA
/// emulation, four vectors per block; the rest of the row pixel by pixel.
#[cfg(target_arch = "wasm32")]
pub(crate) mod wasm {
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
            let v = i32x4_shuffle::<0, 1, 4, 5>(
                f32x4_demote_f64x2_zero(acc[2 * q]),
                f32x4_demote_f64x2_zero(acc[2 * q + 1]),
            );
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
                let mut acc: [v128; P] =
                    core::array::from_fn(|q| round_to_f32(f64x2_mul(load_f64(&wide, x + 2 * q), k0)));
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

    fn column_scalar(
        centre: &[f32],
        pairs: &[(&[f32], &[f32])],
        ky: &[f32],
        dst: &mut [f32],
        xs: core::ops::Range<usize>,
    ) {
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
}

fn accumulate_row(padded: &[f32], kx: &[f32], dst: &mut [f32]) {
    #[cfg(target_arch = "x86_64")]
    {
        // SAFETY (both calls): the CPU supports the features the function was compiled for.
        if crate::simd::avx512f_fma() {
            return unsafe { x86::row_avx512(padded, kx, dst) };
        }
        if crate::simd::avx2_fma() {
            return unsafe { x86::row_avx2(padded, kx, dst) };
        }
    }
    #[cfg(all(target_arch = "wasm32", feature = "relaxed-simd"))]
    if wasm::fused() {
        return wasm::row_fused(padded, kx, dst);
    }
    #[cfg(target_arch = "wasm32")]
    return if wasm::tame_kernel(kx) && wasm::tame(&padded[..dst.len() + kx.len() - 1]) {
        wasm::row_tame(padded, kx, dst)
    } else {
        wasm::row(padded, kx, dst)
    };
    #[allow(unreachable_code)]
    accumulate_row_generic::<BLOCK>(padded, kx, dst, super::num::fma)
}

/// `tame`: every value of the rows is tame (see `wasm::tame`), which lets
/// the wasm column pass take its fast path; native passes ignore it.
fn accumulate_column(centre: &[f32], pairs: &[(&[f32], &[f32])], ky: &[f32], dst: &mut [f32], tame: bool) {
    let _ = tame;
    #[cfg(target_arch = "x86_64")]
    {
        // SAFETY (both calls): the CPU supports the features the function was compiled for.
        if crate::simd::avx512f_fma() {
            return unsafe { x86::column_avx512(centre, pairs, ky, dst) };
        }
        if crate::simd::avx2_fma() {
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

/// The wasm fast path's fallback, in the browser (`cargo test --target
/// wasm32-unknown-unknown`): a block holding one sum that lands, rounded to
/// f64, exactly on an f32 halfway point it does not lie on, so rounding that
/// f64 to f32 goes the wrong way. Real images hit such a sum about once in a
/// million FMAs, too rarely for a random test to be sure of one.
#[cfg(all(test, target_arch = "wasm32"))]
mod wasm_tests {
    use super::super::num::fma_emulated;
    use super::wasm;
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
        let k = super::gaussian_kernel(1.5450077936447955);
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
        let zeros = vec![0f32; 16];
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

#[cfg(test)]
mod tests {
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
