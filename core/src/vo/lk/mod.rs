//! `cv2.calcOpticalFlowPyrLK(prev, next, pts, None, winSize=(21,21),
//! criteria=(EPS|COUNT, 30, 0.01))` as OpenCV 4.8 computes it
//! (docs/fidelity.md §VO-2): the integer pyramid (pyrDown), the unscaled Scharr
//! derivatives, and the fixed-point Lucas-Kanade iteration with the f32
//! accumulation orders of OpenCV's 128-bit SIMD loops. All of this is baseline
//! code in OpenCV (no FMA), so every f32 operation below rounds separately.

use crate::image::GrayImage;

/// Window side (21×21); the lab never changes it.
pub const WIN: usize = 21;
/// Border around every padded level: OpenCV pads by the window size.
const PAD: usize = WIN;
/// `(winSize - 1) * 0.5f`.
const HALF_WIN: f32 = 10.0;
const W_BITS: i32 = 14;
/// Row length of a window buffer: 21 columns padded to three 8-lane blocks.
const WS: usize = 24;
/// Slack after every padded plane so 8-lane loads at the last window column
/// stay inside the buffer.
const SLACK: usize = 32;
/// A 21×21 window (columns 21..23 are scratch, never summed).
type Win = [[i32; WS]; WIN];
/// `FLT_SCALE = 1.f / (1 << 20)`.
const FLT_SCALE: f32 = 1.0 / (1u32 << 20) as f32;

/// The tracker's parameters as `calcOpticalFlowPyrLK` effectively uses them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LkParams {
    /// Requested pyramid depth (may be lowered by the size rule).
    pub max_level: usize,
    /// Iteration cap (`criteria.maxCount`, clamped to [0, 100]).
    pub max_count: usize,
    /// `criteria.epsilon` before squaring (clamped to [0, 10]).
    pub epsilon: f64,
    /// `minEigThreshold`.
    pub min_eig_threshold: f64,
}

impl Default for LkParams {
    /// The lab's call: maxLevel 3, 30 iterations / 0.01, minEigThreshold 1e-4.
    fn default() -> Self {
        LkParams { max_level: 3, max_count: 30, epsilon: 0.01, min_eig_threshold: 1e-4 }
    }
}

/// Output of [`calc_optical_flow_pyr_lk`], one entry per input point.
#[derive(Clone, Debug, PartialEq)]
pub struct LkResult {
    pub next_pts: Vec<[f32; 2]>,
    pub status: Vec<bool>,
    /// Mean absolute difference (8-bit units) for status-1 points; for a
    /// status-0 point OpenCV leaves uninitialized memory, here it is 0.
    pub err: Vec<f32>,
}

/// `borderInterpolate(p, len, BORDER_REFLECT_101)`, repeated for borders wider
/// than the image.
#[inline]
fn reflect101(mut p: isize, len: usize) -> usize {
    let n = len as isize;
    if n == 1 {
        return 0;
    }
    while p < 0 || p >= n {
        p = if p < 0 { -p } else { 2 * n - 2 - p };
    }
    p as usize
}

/// `cv::pyrDown` on 8-bit data, exact integer arithmetic: the 5×5 binomial
/// kernel (sum 256) over reflect-101 of the source level, `+128 >> 8`.
pub fn pyr_down(src: &[u8], w: usize, h: usize) -> (Vec<u8>, usize, usize) {
    #[cfg(target_arch = "x86_64")]
    if crate::simd::avx2() && w >= 40 {
        // SAFETY: the CPU has AVX2, the feature the function is compiled for.
        return unsafe { x86::pyr_down_avx2(src, w, h) };
    }
    pyr_down_portable(src, w, h)
}

/// Every sum below fits 16 bits: a horizontal sum is at most 16·255 = 4080
/// and a vertical one 16·4080 + 128 = 65,408.
fn pyr_down_portable(src: &[u8], w: usize, h: usize) -> (Vec<u8>, usize, usize) {
    let dw = w.div_ceil(2);
    let mut hrow = vec![0u16; dw * h];
    for y in 0..h {
        pyr_down_row_edges(&src[y * w..(y + 1) * w], &mut hrow[y * dw..(y + 1) * dw], 0..dw);
    }
    pyr_down_columns(&hrow, dw, h)
}

/// Horizontal sums of the output columns `xs` of one row, reflect-101.
#[inline(always)]
fn pyr_down_row_edges(row: &[u8], out: &mut [u16], xs: std::ops::Range<usize>) {
    let w = row.len();
    for x in xs {
        let c = 2 * x as isize;
        let at = |d: isize| row[reflect101(c + d, w)] as u16;
        out[x] = at(-2) + 4 * at(-1) + 6 * at(0) + 4 * at(1) + at(2);
    }
}

/// The vertical pass over the horizontal sums, reflect-101 rows.
#[inline(always)]
fn pyr_down_columns(hrow: &[u16], dw: usize, h: usize) -> (Vec<u8>, usize, usize) {
    let mut dst = vec![0u8; dw * h.div_ceil(2)];
    for (y, out) in dst.chunks_exact_mut(dw).enumerate() {
        let r = 2 * y as isize;
        let [r0, r1, r2, r3, r4] = [-2, -1, 0, 1, 2].map(|d| &hrow[reflect101(r + d, h) * dw..][..dw]);
        for (x, o) in out.iter_mut().enumerate() {
            let s = r0[x] + 4 * r1[x] + 6 * r2[x] + 4 * r3[x] + r4[x];
            *o = ((s + 128) >> 8) as u8;
        }
    }
    (dst, dw, h.div_ceil(2))
}

#[cfg(target_arch = "x86_64")]
mod x86 {
    use std::arch::x86_64::*;

    /// [`super::pyr_down`] with AVX2: each row's interior columns sixteen at
    /// a time (the even and odd source pixels of 32 bytes are the low and
    /// high bytes of its sixteen 16-bit lanes), the vertical pass compiled
    /// for AVX2. The same integers as the portable pass. Needs w ≥ 40.
    #[target_feature(enable = "avx2")]
    pub unsafe fn pyr_down_avx2(src: &[u8], w: usize, h: usize) -> (Vec<u8>, usize, usize) {
        let dw = w.div_ceil(2);
        // Columns 1..=last read source pixels 2x − 2 ..= 2x + 2 inside the row.
        let last = (w - 3) / 2;
        let mut hrow = vec![0u16; dw * h];
        let lo = _mm256_set1_epi16(0xff);
        for y in 0..h {
            let row = &src[y * w..(y + 1) * w];
            let out = &mut hrow[y * dw..(y + 1) * dw];
            super::pyr_down_row_edges(row, out, 0..1);
            super::pyr_down_row_edges(row, out, last + 1..dw);
            // Blocks of 16 columns from 1; the last block ends at `last`
            // and overlaps the one before (recomputing the same sums).
            let mut x = 1;
            loop {
                let x0 = x.min(last + 1 - 16);
                // Source pixels 2x0 − 2 ..= 2x0 + 32, all inside the row:
                // lane i of `a` holds pixels 2(x0 + i) − 2 and − 1, of `b`
                // 2(x0 + i) and + 1, the high byte of `c` 2(x0 + i) + 2.
                let p = row.as_ptr().add(2 * x0 - 2);
                let a = _mm256_loadu_si256(p as *const __m256i);
                let b = _mm256_loadu_si256(p.add(2) as *const __m256i);
                let c = _mm256_loadu_si256(p.add(3) as *const __m256i);
                let (em, om) = (_mm256_and_si256(a, lo), _mm256_srli_epi16::<8>(a));
                let (e0, o0) = (_mm256_and_si256(b, lo), _mm256_srli_epi16::<8>(b));
                let ep = _mm256_srli_epi16::<8>(c);
                let fours = _mm256_slli_epi16::<2>(_mm256_add_epi16(om, o0));
                let six = _mm256_add_epi16(_mm256_slli_epi16::<2>(e0), _mm256_slli_epi16::<1>(e0));
                let s = _mm256_add_epi16(_mm256_add_epi16(em, ep), _mm256_add_epi16(fours, six));
                _mm256_storeu_si256(out.as_mut_ptr().add(x0) as *mut __m256i, s);
                if x0 + 16 > last {
                    break;
                }
                x += 16;
            }
        }
        super::pyr_down_columns(&hrow, dw, h)
    }
}

/// One pyramid level stored with a PAD-pixel reflect-101 border, as
/// `buildOpticalFlowPyramid` keeps it.
#[derive(Clone, Debug)]
pub struct Level {
    pub w: usize,
    pub h: usize,
    /// Unpadded pixels (row-major w×h).
    pub pixels: Vec<u8>,
    stride: usize,
    padded: Vec<u8>,
}

impl Level {
    fn new(pixels: Vec<u8>, w: usize, h: usize) -> Self {
        let stride = w + 2 * PAD;
        let ph = h + 2 * PAD;
        let mut padded = vec![0u8; stride * ph + SLACK];
        // Only the PAD columns on each side are reflected; the row itself
        // is one slice copy (a gather per pixel was 0.5 % of a VO run).
        let (left, right): (Vec<usize>, Vec<usize>) =
            (0..PAD).map(|j| (reflect101(j as isize - PAD as isize, w), reflect101((w + j) as isize, w))).unzip();
        for py in 0..ph {
            let sy = reflect101(py as isize - PAD as isize, h);
            let src = &pixels[sy * w..(sy + 1) * w];
            let dst = &mut padded[py * stride..(py + 1) * stride];
            let (l, rest) = dst.split_at_mut(PAD);
            let (mid, r) = rest.split_at_mut(w);
            mid.copy_from_slice(src);
            for (d, &sx) in l.iter_mut().zip(&left) {
                *d = src[sx];
            }
            for (d, &sx) in r.iter_mut().zip(&right) {
                *d = src[sx];
            }
        }
        Level { w, h, pixels, stride, padded }
    }

    /// Offset of pixel (x, y) (level coordinates, may be negative down to
    /// −PAD) in the padded buffer.
    #[inline]
    fn offset(&self, x: i32, y: i32) -> usize {
        ((y + PAD as i32) as usize) * self.stride + (x + PAD as i32) as usize
    }
}

/// `buildOpticalFlowPyramid(img, winSize=21, maxLevel, withDerivatives=false)`:
/// stops early when the next level would be ≤ 21 pixels in either direction.
pub fn build_pyramid(img: &GrayImage, max_level: usize) -> Vec<Level> {
    let (mut w, mut h) = (img.width(), img.height());
    let mut levels = vec![Level::new(img.data().to_vec(), w, h)];
    for _ in 0..max_level {
        let (nw, nh) = (w.div_ceil(2), h.div_ceil(2));
        if nw <= WIN || nh <= WIN {
            break;
        }
        let prev = levels.last().map(|l| &l.pixels[..]).unwrap_or(&[]);
        let (d, dw, dh) = pyr_down(prev, w, h);
        levels.push(Level::new(d, dw, dh));
        w = dw;
        h = dh;
    }
    levels
}

/// Scharr derivatives of one level (`calcSharrDeriv`): no scaling, reflect-101
/// inside the level, then a PAD-pixel border of zeros (BORDER_CONSTANT).
#[derive(Clone, Debug)]
pub struct Deriv {
    stride: usize,
    ix: Vec<i16>,
    iy: Vec<i16>,
}

impl Deriv {
    pub fn new(level: &Level) -> Self {
        #[cfg(target_arch = "x86_64")]
        if crate::simd::avx2() {
            #[target_feature(enable = "avx2")]
            unsafe fn avx2(level: &Level) -> Deriv {
                Deriv::compute(level)
            }
            // SAFETY: the CPU has AVX2, the feature `avx2` is compiled for.
            return unsafe { avx2(level) };
        }
        Deriv::compute(level)
    }

    /// In 16-bit lanes (compiled for AVX2 where the CPU has it, sixteen
    /// columns at a time): every sum is within ±16·255 = ±4080.
    #[inline(always)]
    fn compute(level: &Level) -> Self {
        let (w, h) = (level.w, level.h);
        let img = &level.pixels;
        let stride = w + 2 * PAD;
        let len = stride * (h + 2 * PAD) + SLACK;
        // Written front to back, each element once: the zero border, then
        // per row its pixels and the border around them (zeroing both whole
        // planes first was half this function's time).
        let (mut ix, mut iy) = (Vec::with_capacity(len), Vec::with_capacity(len));
        let (mut rx, mut ry) = (vec![0i16; w], vec![0i16; w]);
        let mut s = vec![0i16; w];
        let mut d = vec![0i16; w];
        for p in [&mut ix, &mut iy] {
            p.resize(PAD * stride + PAD, 0);
        }
        for y in 0..h {
            let up = &img[reflect101(y as isize - 1, h) * w..][..w];
            let mid = &img[y * w..][..w];
            let dn = &img[reflect101(y as isize + 1, h) * w..][..w];
            for ((((s, d), &u), &m), &n) in s.iter_mut().zip(d.iter_mut()).zip(up).zip(mid).zip(dn) {
                *s = 3 * u as i16 + 10 * m as i16 + 3 * n as i16;
                *d = n as i16 - u as i16;
            }
            // Interior without index arithmetic (vectorizes), the two edge
            // columns with reflect-101.
            if w > 2 {
                for (((rx, ry), s), d) in
                    rx[1..w - 1].iter_mut().zip(&mut ry[1..w - 1]).zip(s.windows(3)).zip(d.windows(3))
                {
                    *rx = s[2] - s[0];
                    *ry = 3 * d[0] + 10 * d[1] + 3 * d[2];
                }
            }
            for x in [0, w - 1] {
                let l = reflect101(x as isize - 1, w);
                let r = reflect101(x as isize + 1, w);
                rx[x] = s[r] - s[l];
                ry[x] = 3 * d[l] + 10 * d[x] + 3 * d[r];
            }
            // This row, the right border, the next row's left border (or,
            // after the last row, the bottom border and the slack).
            for (p, r) in [(&mut ix, &rx), (&mut iy, &ry)] {
                p.extend_from_slice(r);
                p.resize(p.len() + 2 * PAD, 0);
            }
        }
        for p in [&mut ix, &mut iy] {
            p.resize(len, 0);
        }
        Deriv { stride, ix, iy }
    }

    #[inline]
    fn offset(&self, x: i32, y: i32) -> usize {
        ((y + PAD as i32) as usize) * self.stride + (x + PAD as i32) as usize
    }
}

/// The four 14-bit bilinear weights OpenCV derives from the fractional part
/// (each product an f32 operation in source order, rounded half-even).
#[inline(always)]
fn weights(a: f32, b: f32) -> [i32; 4] {
    let one = (1i32 << W_BITS) as f32;
    let w00 = ((1.0 - a) * (1.0 - b) * one).round_ties_even() as i32;
    let w01 = (a * (1.0 - b) * one).round_ties_even() as i32;
    let w10 = ((1.0 - a) * b * one).round_ties_even() as i32;
    [w00, w01, w10, (1 << W_BITS) - w00 - w01 - w10]
}

/// Interpolates a 21×21 window of a padded u8 level at top-left `(ix, iy)`
/// into values ×32 (`CV_DESCALE(..., W_BITS - 5)`).
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

#[inline]
fn out_of_bounds(ix: i32, iy: i32, w: usize, h: usize) -> bool {
    ix < -(WIN as i32) || ix >= w as i32 || iy < -(WIN as i32) || iy >= h as i32
}

/// The window kernels of one point and level. [`Scalar`] is the reference
/// (and what wasm without SIMD runs); `avx2::Avx2` and `simd128::Simd128` keep
/// 16-bit windows in the column layout of `wide` and get the same bits.
trait Kernels {
    /// The template and gradient windows of one point at one level.
    type Patch;
    fn new_patch() -> Box<Self::Patch>;
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

struct Scalar;

impl Kernels for Scalar {
    type Patch = Scratch;

    fn new_patch() -> Box<Scratch> {
        Box::new(Scratch { tmpl: [[0; WS]; WIN], gx: [[0; WS]; WIN], gy: [[0; WS]; WIN], warped: [[0; WS]; WIN] })
    }

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

#[cfg(target_arch = "x86_64")]
mod avx2;
#[cfg(all(target_arch = "wasm32", target_feature = "simd128"))]
mod simd128;
#[cfg(any(target_arch = "x86_64", all(target_arch = "wasm32", target_feature = "simd128")))]
mod wide;

/// Window buffers reused across points (every element is written before
/// it is read).
struct Scratch {
    tmpl: Win,
    gx: Win,
    gy: Win,
    warped: Win,
}

/// One point at one level (LKTrackerInvoker::operator()), as a state that
/// advances one iteration at a time, so that [`run_job_body`] can keep two
/// points going side by side. `next` holds the stored estimate, updated in
/// place; `status`/`err` are only touched at level 0.
struct Track {
    /// Index of the point in the job's output slices.
    k: usize,
    a11: f32,
    a12: f32,
    a22: f32,
    dinv: f32,
    /// Window corner of the current estimate (`next − HALF_WIN`).
    n: [f32; 2],
    prev_delta: [f32; 2],
    /// Iterations done.
    j: usize,
}

/// What a level of one point needs from its job.
struct LevelCtx<'a> {
    prev: &'a Level,
    deriv: &'a Deriv,
    next: &'a Level,
    level: usize,
    max_level: usize,
    crit: (usize, f64),
    min_eig_threshold: f32,
}

impl Track {
    /// The guess, the template window and the structure tensor; `None` when
    /// the point is done at this level before any iteration.
    #[inline(always)]
    fn start<K: Kernels>(
        cx: &LevelCtx,
        k: usize,
        prev_pt: [f32; 2],
        next: &mut [f32; 2],
        status: &mut bool,
        err: &mut f32,
        patch: &mut K::Patch,
    ) -> Option<Track> {
        let level = cx.level;
        let scale = 1.0 / (1u32 << level) as f32;
        let p = [prev_pt[0] * scale, prev_pt[1] * scale];
        let guess = if level == cx.max_level { p } else { [next[0] * 2.0, next[1] * 2.0] };
        *next = guess;

        let q = [p[0] - HALF_WIN, p[1] - HALF_WIN];
        let (ix, iy) = (q[0].floor() as i32, q[1].floor() as i32);
        if out_of_bounds(ix, iy, cx.prev.w, cx.prev.h) {
            if level == 0 {
                *status = false;
                *err = 0.0;
            }
            return None;
        }
        let wts = weights(q[0] - ix as f32, q[1] - iy as f32);
        let (s11, s12, s22) = K::load_patch(cx.prev, cx.deriv, ix, iy, &wts, patch);
        let (a11, a12, a22) = (s11 * FLT_SCALE, s12 * FLT_SCALE, s22 * FLT_SCALE);
        let det = a11 * a22 - a12 * a12;
        let min_eig = (a22 + a11 - ((a11 - a22) * (a11 - a22) + 4.0 * a12 * a12).sqrt()) / (2 * WIN * WIN) as f32;
        if min_eig < cx.min_eig_threshold || det < f32::EPSILON {
            if level == 0 {
                *status = false;
            }
            return None;
        }
        if cx.crit.0 == 0 {
            Track::finish::<K>(cx, next, status, err, patch);
            return None;
        }
        Some(Track {
            k,
            a11,
            a12,
            a22,
            dinv: 1.0 / det,
            n: [guess[0] - HALF_WIN, guess[1] - HALF_WIN],
            prev_delta: [0.0; 2],
            j: 0,
        })
    }

    /// One iteration; false when the point is done at this level (then
    /// [`Track::finish`] has run).
    #[inline(always)]
    fn step<K: Kernels>(
        &mut self,
        cx: &LevelCtx,
        next: &mut [f32; 2],
        status: &mut bool,
        err: &mut f32,
        patch: &mut K::Patch,
    ) -> bool {
        let n = self.n;
        let (jx, jy) = (n[0].floor() as i32, n[1].floor() as i32);
        let go_on = if out_of_bounds(jx, jy, cx.next.w, cx.next.h) {
            if cx.level == 0 {
                *status = false;
            }
            false
        } else {
            let w = weights(n[0] - jx as f32, n[1] - jy as f32);
            let (b1, b2) = K::mismatch(cx.next, jx, jy, &w, patch);
            let (a11, a12, a22, dinv) = (self.a11, self.a12, self.a22, self.dinv);
            let delta = [(a12 * b2 - a22 * b1) * dinv, (a12 * b1 - a11 * b2) * dinv];
            self.n = [n[0] + delta[0], n[1] + delta[1]];
            *next = [self.n[0] + HALF_WIN, self.n[1] + HALF_WIN];
            let prev_delta = self.prev_delta;
            if (delta[0] as f64) * (delta[0] as f64) + (delta[1] as f64) * (delta[1] as f64) <= cx.crit.1 {
                false
            } else if self.j > 0
                && ((delta[0] + prev_delta[0]).abs() as f64) < 0.01
                && ((delta[1] + prev_delta[1]).abs() as f64) < 0.01
            {
                // The step reversed itself: retreat half of it and stop.
                *next = [next[0] - delta[0] * 0.5, next[1] - delta[1] * 0.5];
                false
            } else {
                self.prev_delta = delta;
                self.j += 1;
                self.j < cx.crit.0
            }
        };
        if !go_on {
            Track::finish::<K>(cx, next, status, err, patch);
        }
        go_on
    }

    /// The error of a point still tracked after level 0.
    #[inline(always)]
    fn finish<K: Kernels>(cx: &LevelCtx, next: &[f32; 2], status: &mut bool, err: &mut f32, patch: &mut K::Patch) {
        if *status && cx.level == 0 {
            let m = [next[0] - HALF_WIN, next[1] - HALF_WIN];
            let (jx, jy) = (m[0].floor() as i32, m[1].floor() as i32);
            if out_of_bounds(jx, jy, cx.next.w, cx.next.h) {
                *status = false;
                return;
            }
            let w = weights(m[0] - jx as f32, m[1] - jy as f32);
            let errval = K::abs_diff_sum(cx.next, jx, jy, &w, patch);
            *err = errval / (32 * WIN * WIN) as f32;
        }
    }
}

struct Job<'a> {
    prep: &'a Prepared<'a>,
    pts: &'a [[f32; 2]],
    range: std::ops::Range<usize>,
    max_level: usize,
    crit: (usize, f64),
    min_eig: f32,
    /// Forces the scalar kernels (tests compare both paths).
    scalar: bool,
}

/// Every level of the job's points, two points at a time: a point's
/// iterations form one chain (each window is placed by the previous
/// iteration's result), and the end of an iteration — the sums' reduction,
/// the step, the next window's weights and address — is a short serial
/// stretch the vector units sit out. With a second point's iteration next
/// in program order, its window work fills that stretch. Each point still
/// runs exactly its own iterations, so no result changes.
#[inline(always)]
fn run_job_body<K: Kernels>(job: &Job, np: &mut [[f32; 2]], st: &mut [bool], er: &mut [f32]) {
    let prep = job.prep;
    let mut patches = [K::new_patch(), K::new_patch()];
    for level in (0..=job.max_level).rev() {
        let cx = LevelCtx {
            prev: &prep.prev[level],
            deriv: &prep.derivs[level],
            next: &prep.next[level],
            level,
            max_level: job.max_level,
            crit: job.crit,
            min_eig_threshold: job.min_eig,
        };
        let mut lanes: [Option<Track>; 2] = [None, None];
        let mut todo = 0..job.range.len();
        loop {
            let mut busy = false;
            for (lane, patch) in lanes.iter_mut().zip(patches.iter_mut()) {
                while lane.is_none() {
                    let Some(k) = todo.next() else { break };
                    let i = job.range.start + k;
                    *lane = Track::start::<K>(&cx, k, job.pts[i], &mut np[k], &mut st[k], &mut er[k], patch);
                }
                if let Some(t) = lane {
                    let k = t.k;
                    if !t.step::<K>(&cx, &mut np[k], &mut st[k], &mut er[k], patch) {
                        *lane = None;
                    }
                    busy = true;
                }
            }
            if !busy {
                break;
            }
        }
    }
}

/// The loop compiled for AVX2 around the AVX2 window kernels: only integer
/// ops and separately rounded f32 adds/multiplies are involved (Rust never
/// contracts to FMA), so this changes the speed, not a bit of the result.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn run_job_avx2(job: &Job, np: &mut [[f32; 2]], st: &mut [bool], er: &mut [f32]) {
    run_job_body::<avx2::Avx2>(job, np, st, er)
}

/// The same loop around the AVX-512 BW mismatch kernel.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512bw,avx512f,avx2")]
unsafe fn run_job_avx512(job: &Job, np: &mut [[f32; 2]], st: &mut [bool], er: &mut [f32]) {
    run_job_body::<avx2::Avx512>(job, np, st, er)
}

fn run_job(job: &Job, np: &mut [[f32; 2]], st: &mut [bool], er: &mut [f32]) {
    #[cfg(target_arch = "x86_64")]
    {
        if !job.scalar && crate::simd::avx512bw() {
            // SAFETY: the CPU supports AVX-512 F and BW (checked just above).
            unsafe { run_job_avx512(job, np, st, er) };
            return;
        }
        if !job.scalar && crate::simd::avx2() {
            // SAFETY: the CPU supports AVX2 (checked just above).
            unsafe { run_job_avx2(job, np, st, er) };
            return;
        }
    }
    #[cfg(all(target_arch = "wasm32", target_feature = "simd128"))]
    {
        if !job.scalar {
            return run_job_body::<simd128::Simd128>(job, np, st, er);
        }
    }
    run_job_body::<Scalar>(job, np, st, er)
}

/// Pyramids and derivatives of a frame pair, built once per call.
struct Prepared<'a> {
    prev: &'a [Level],
    next: &'a [Level],
    derivs: Vec<Deriv>,
}

/// An image pyramid as the tracker uses it; build it once per frame and pass
/// it as `next` for one call and as `prev` for the following one.
#[derive(Clone, Debug)]
pub struct Pyramid {
    levels: Vec<Level>,
}

impl Pyramid {
    /// `buildOpticalFlowPyramid(img, (21, 21), max_level)`.
    pub fn new(img: &GrayImage, max_level: usize) -> Pyramid {
        Pyramid { levels: build_pyramid(img, max_level) }
    }

    pub fn size(&self) -> (usize, usize) {
        (self.levels[0].w, self.levels[0].h)
    }
}

/// calcOpticalFlowPyrLK on prebuilt pyramids (the previous one may be deeper;
/// OpenCV limits the second pyramid to the first one's depth).
pub fn calc_optical_flow_pyr_lk_pyramids(
    prev: &Pyramid,
    next: &Pyramid,
    pts: &[[f32; 2]],
    params: &LkParams,
) -> LkResult {
    let depth = prev.levels.len().min(next.levels.len()).min(params.max_level + 1);
    let derivs = prev.levels[..depth].iter().map(Deriv::new).collect();
    let prep = Prepared { prev: &prev.levels[..depth], next: &next.levels[..depth], derivs };
    track_prepared(&prep, pts, params, false)
}

/// `cv2.calcOpticalFlowPyrLK(prev, next, pts, None, winSize=(21,21), ...)`.
/// Both images must have the same size.
pub fn calc_optical_flow_pyr_lk(prev: &GrayImage, next: &GrayImage, pts: &[[f32; 2]], params: &LkParams) -> LkResult {
    lk_from_images(prev, next, pts, params, false)
}

/// The same call with the portable scalar kernels only (the reference the
/// vector kernels are tested against; what wasm without SIMD runs).
pub fn calc_optical_flow_pyr_lk_portable(
    prev: &GrayImage,
    next: &GrayImage,
    pts: &[[f32; 2]],
    params: &LkParams,
) -> LkResult {
    lk_from_images(prev, next, pts, params, true)
}

fn lk_from_images(prev: &GrayImage, next: &GrayImage, pts: &[[f32; 2]], params: &LkParams, portable: bool) -> LkResult {
    let prev_pyr = build_pyramid(prev, params.max_level);
    let max_level = prev_pyr.len() - 1;
    let next_pyr = build_pyramid(next, max_level);
    let derivs = prev_pyr.iter().map(Deriv::new).collect();
    let prep = Prepared { prev: &prev_pyr, next: &next_pyr, derivs };
    track_prepared(&prep, pts, params, portable)
}

fn track_prepared(prep: &Prepared, pts: &[[f32; 2]], params: &LkParams, scalar: bool) -> LkResult {
    let n = pts.len();
    // Visit the points in bands of rows, left to right within a band, not
    // in the caller's order (for SIFT keypoints that is response order,
    // spatially random): neighbouring windows then share cached rows of the
    // pyramids and derivative planes. Each point's result depends on its
    // own window only, so the order changes the speed, not a bit of them.
    let mut order: Vec<u32> = (0..n as u32).collect();
    order.sort_by_key(|&i| {
        let [x, y] = pts[i as usize];
        // Keys from the clamped coordinates: NaN or huge inputs sort anywhere.
        let band = (y.clamp(-1.0e6, 1.0e6) as i32) >> 5;
        (band, x.clamp(-1.0e6, 1.0e6) as i32)
    });
    let sorted: Vec<[f32; 2]> = order.iter().map(|&i| pts[i as usize]).collect();
    let out = track_ordered(prep, &sorted, params, scalar);
    let mut next_pts = vec![[0f32; 2]; n];
    let mut status = vec![true; n];
    let mut err = vec![0f32; n];
    for (k, &i) in order.iter().enumerate() {
        next_pts[i as usize] = out.next_pts[k];
        status[i as usize] = out.status[k];
        err[i as usize] = out.err[k];
    }
    LkResult { next_pts, status, err }
}

fn track_ordered(prep: &Prepared, pts: &[[f32; 2]], params: &LkParams, scalar: bool) -> LkResult {
    let max_level = prep.prev.len().min(prep.next.len()) - 1;
    let max_count = params.max_count.min(100);
    let eps = params.epsilon.clamp(0.0, 10.0);
    let crit = (max_count, eps * eps);
    let min_eig = params.min_eig_threshold as f32;
    let n = pts.len();
    let mut next_pts = vec![[0f32; 2]; n];
    let mut status = vec![true; n];
    let mut err = vec![0f32; n];

    // Points are independent (OpenCV runs them in parallel too, each result
    // written by one task), so splitting them over threads changes nothing.
    let run = |range: std::ops::Range<usize>, np: &mut [[f32; 2]], st: &mut [bool], er: &mut [f32]| {
        let job = Job { prep, pts, range, max_level, crit, min_eig, scalar };
        run_job(&job, np, st, er);
    };

    #[cfg(not(target_arch = "wasm32"))]
    {
        // Within `par::with_threads`' cap: the odometry tracks on one core
        // while the detection workers take the others.
        let threads = crate::sift::par::threads();
        if threads > 1 && n >= 64 {
            let chunk = n.div_ceil(threads);
            std::thread::scope(|s| {
                let mut start = 0;
                for ((np, st), er) in
                    next_pts.chunks_mut(chunk).zip(status.chunks_mut(chunk)).zip(err.chunks_mut(chunk))
                {
                    let range = start..start + np.len();
                    start += np.len();
                    let run = &run;
                    s.spawn(move || run(range, np, st, er));
                }
            });
            return LkResult { next_pts, status, err };
        }
    }
    run(0..n, &mut next_pts, &mut status, &mut err);
    LkResult { next_pts, status, err }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A smooth textured image: sums of sines, so sub-pixel shifts are
    /// well defined, sampled at (x + dx, y + dy).
    fn textured(w: usize, h: usize, dx: f64, dy: f64) -> GrayImage {
        let mut data = vec![0u8; w * h];
        for y in 0..h {
            for x in 0..w {
                let (u, v) = (x as f64 + dx, y as f64 + dy);
                let val = 128.0
                    + 35.0 * (u * 0.27 + v * 0.13).sin()
                    + 35.0 * (v * 0.21 - u * 0.17).sin()
                    + 30.0 * (u * 0.07 + v * 0.05).sin()
                    + 25.0 * (u * 0.04 - v * 0.08).cos();
                data[y * w + x] = val.round().clamp(0.0, 255.0) as u8;
            }
        }
        GrayImage::new(w, h, data).unwrap()
    }

    /// The pyrDown of the old per-pixel code: gathers through a column table.
    fn pyr_down_reference(src: &[u8], w: usize, h: usize) -> Vec<u8> {
        let (dw, dh) = (w.div_ceil(2), h.div_ceil(2));
        let at = |x: isize, y: isize| src[reflect101(y, h) * w + reflect101(x, w)] as u32;
        let k = [1, 4, 6, 4, 1];
        let mut dst = vec![0u8; dw * dh];
        for y in 0..dh {
            for x in 0..dw {
                let mut s = 0;
                for (i, ky) in k.iter().enumerate() {
                    let mut r = 0;
                    for (j, kx) in k.iter().enumerate() {
                        r += kx * at(2 * x as isize + j as isize - 2, 2 * y as isize + i as isize - 2);
                    }
                    s += ky * r;
                }
                dst[y * dw + x] = ((s + 128) >> 8) as u8;
            }
        }
        dst
    }

    /// w×h pixels of xorshift noise, two thirds of them 0 or 255, so the
    /// 16-bit sums of the fast paths reach their bounds.
    fn extreme_noise(w: usize, h: usize, seed: u64) -> Vec<u8> {
        let mut rng = crate::testutil::XorShift64::new(seed);
        (0..w * h)
            .map(|_| {
                let s = rng.next_u64();
                [0, 255, (s >> 8) as u8][(s % 3) as usize]
            })
            .collect()
    }

    #[test]
    fn pyr_down_fast_paths_match_the_definition() {
        for (w, h) in [(40, 3), (41, 4), (55, 9), (72, 21), (1241, 376), (621, 188), (311, 94), (7, 5), (1, 1), (2, 3)]
        {
            let src = extreme_noise(w, h, 0x9e37_79b9 ^ (w * h) as u64);
            let want = pyr_down_reference(&src, w, h);
            assert_eq!(pyr_down(&src, w, h).0, want, "{w}x{h}");
            assert_eq!(pyr_down_portable(&src, w, h).0, want, "{w}x{h} portable");
        }
    }

    #[test]
    fn pyr_down_matches_cv2() {
        // cv2.pyrDown(np.arange(35, dtype=np.uint8).reshape(5, 7) * 7)
        let src: Vec<u8> = (0..35u32).map(|v| (v * 7) as u8).collect();
        let (d, w, h) = pyr_down(&src, 7, 5);
        assert_eq!((w, h), (4, 3));
        assert_eq!(d, vec![42, 51, 65, 74, 103, 112, 126, 135, 165, 173, 187, 196]);
    }

    #[test]
    fn pyramid_sizes_follow_the_window_rule() {
        let img = GrayImage::new(1241, 376, vec![0; 1241 * 376]).unwrap();
        let pyr = build_pyramid(&img, 3);
        let sizes: Vec<_> = pyr.iter().map(|l| (l.w, l.h)).collect();
        assert_eq!(sizes, vec![(1241, 376), (621, 188), (311, 94), (156, 47)]);
        // 100x60 → 50x30 → next would be 25x15 (15 ≤ 21): maxLevel 1.
        let small = GrayImage::new(100, 60, vec![0; 6000]).unwrap();
        assert_eq!(build_pyramid(&small, 3).len(), 2);
    }

    #[test]
    fn scharr_fast_path_matches_the_portable_one() {
        for (w, h) in [(1241, 376), (156, 47), (3, 2), (2, 1)] {
            let lvl = Level::new(extreme_noise(w, h, 0x2468_ace1 ^ (w * h) as u64), w, h);
            let (fast, portable) = (Deriv::new(&lvl), Deriv::compute(&lvl));
            assert!(fast.ix == portable.ix && fast.iy == portable.iy, "{w}x{h}");
        }
    }

    #[test]
    fn scharr_is_unscaled_with_reflect101() {
        // A horizontal ramp I = 3x: Ix = (3+10+3)·(3(x+1) − 3(x−1)) = 96 inside,
        // 0 on the reflected columns; Iy = 0 everywhere.
        let (w, h) = (6usize, 4usize);
        let data: Vec<u8> = (0..w * h).map(|i| (3 * (i % w)) as u8).collect();
        let lvl = Level::new(data, w, h);
        let d = Deriv::new(&lvl);
        let at = |p: &Vec<i16>, x: i32, y: i32| p[d.offset(x, y)];
        assert_eq!(at(&d.ix, 2, 1), 96);
        assert_eq!(at(&d.ix, 0, 0), 0);
        assert_eq!(at(&d.ix, 5, 3), 0);
        assert_eq!(at(&d.iy, 3, 2), 0);
        // The zero border.
        assert_eq!(at(&d.ix, -1, 1), 0);
    }

    #[test]
    fn recovers_a_known_subpixel_shift() {
        let (w, h) = (320, 240);
        let (sx, sy) = (2.37, -1.61);
        let prev = textured(w, h, 0.0, 0.0);
        // next(x, y) = prev(x + sx, y + sy) → features move by (−sx, −sy).
        let next = textured(w, h, sx, sy);
        let mut pts = Vec::new();
        for gy in 0..6 {
            for gx in 0..8 {
                pts.push([40.0 + 32.0 * gx as f32 + 0.25, 40.0 + 30.0 * gy as f32 + 0.5]);
            }
        }
        let out = calc_optical_flow_pyr_lk(&prev, &next, &pts, &LkParams::default());
        let (mut worst, mut sum) = (0f64, 0f64);
        for (i, p) in pts.iter().enumerate() {
            assert!(out.status[i], "point {i} lost");
            let ex = (out.next_pts[i][0] - p[0]) as f64 + sx;
            let ey = (out.next_pts[i][1] - p[1]) as f64 + sy;
            worst = worst.max(ex.abs()).max(ey.abs());
            sum += ex.abs() + ey.abs();
            assert!(out.err[i] < 2.0, "err {}", out.err[i]);
        }
        // Measured: worst 0.0088 px, mean 0.0030 px (8-bit quantization).
        assert!(worst < 0.01, "worst shift error {worst}");
        let mean = sum / (2 * pts.len()) as f64;
        assert!(mean < 0.005, "mean error {mean}");
    }

    #[test]
    fn results_follow_the_callers_order_not_the_visiting_order() {
        // The tracker visits points in bands of rows; each result must land
        // at its own point's index, bit for bit what tracking it alone gives.
        let prev = textured(320, 240, 0.0, 0.0);
        let next = textured(320, 240, 1.3, -0.7);
        let mut pts = Vec::new();
        for k in 0..70u32 {
            // Scattered, bottom-right first, with one point outside the image.
            let x = 300.0 - ((k * 37) % 280) as f32 - 0.25 * (k % 4) as f32;
            let y = 220.0 - ((k * 53) % 200) as f32 - 0.5 * (k % 3) as f32;
            pts.push([x, y]);
        }
        pts[17] = [-30.0, 50.0];
        let together = calc_optical_flow_pyr_lk(&prev, &next, &pts, &LkParams::default());
        assert!(!together.status[17]);
        assert!(together.status.iter().filter(|&&s| s).count() > 60);
        for (i, p) in pts.iter().enumerate() {
            let alone = calc_optical_flow_pyr_lk(&prev, &next, &[*p], &LkParams::default());
            assert_eq!(together.next_pts[i].map(f32::to_bits), alone.next_pts[0].map(f32::to_bits), "point {i}");
            assert_eq!(together.status[i], alone.status[0], "point {i}");
            assert_eq!(together.err[i].to_bits(), alone.err[0].to_bits(), "point {i}");
        }
    }

    #[test]
    fn status_flags_points_outside_the_image() {
        let prev = textured(200, 120, 0.0, 0.0);
        let next = textured(200, 120, 1.0, 0.0);
        let pts = [[100.0, 60.0], [-40.0, 60.0], [100.0, 500.0], [250.0, 10.0]];
        let out = calc_optical_flow_pyr_lk(&prev, &next, &pts, &LkParams::default());
        assert_eq!(out.status, vec![true, false, false, false]);
        // A previous point out of bounds at level 0 gets err 0 explicitly.
        assert_eq!(out.err[1], 0.0);
        // A flat image has no gradient: the eigenvalue test fails.
        let flat = GrayImage::new(200, 120, vec![90; 24000]).unwrap();
        let out = calc_optical_flow_pyr_lk(&flat, &flat, &[[100.0, 60.0]], &LkParams::default());
        assert_eq!(out.status, vec![false]);
    }

    include!("../testdata/lk_golden.rs");

    /// The AVX2 tracker against the portable one on a KITTI-sized pair (the
    /// bundled KITTI frames 0 → 1), on a grid of 640 points covering
    /// borders, flat sky and texture: same positions, status and err, bit for
    /// bit (the kernel-level test covers the replay path on purpose).
    #[test]
    fn avx2_equals_portable_on_a_kitti_sized_pair() {
        let prev =
            GrayImage::decode(include_bytes!("../../../../www/demo/MyKITTI/gray/00/image_0/000000.png")).unwrap();
        let next =
            GrayImage::decode(include_bytes!("../../../../www/demo/MyKITTI/gray/00/image_0/000001.png")).unwrap();
        let mut pts = Vec::new();
        for gy in 0..16 {
            for gx in 0..40 {
                pts.push([-8.0 + 32.0 * gx as f32 + 0.37 * gy as f32, -6.0 + 24.5 * gy as f32 + 0.11 * gx as f32]);
            }
        }
        let fast = calc_optical_flow_pyr_lk(&prev, &next, &pts, &LkParams::default());
        let portable = calc_optical_flow_pyr_lk_portable(&prev, &next, &pts, &LkParams::default());
        let tracked = fast.status.iter().filter(|&&s| s).count();
        assert!(tracked > 400, "only {tracked} of {} tracked", pts.len());
        assert_eq!(fast.status, portable.status);
        for i in 0..pts.len() {
            let bits = |r: &LkResult| [r.next_pts[i][0].to_bits(), r.next_pts[i][1].to_bits()];
            assert_eq!(bits(&fast), bits(&portable), "point {i} {:?}", pts[i]);
            if fast.status[i] {
                assert_eq!(fast.err[i].to_bits(), portable.err[i].to_bits(), "err of point {i}");
            }
        }
    }

    #[test]
    fn bit_exact_against_opencv_on_a_synthetic_pair() {
        let prev = GrayImage::decode(include_bytes!("../testdata/lk_prev.png")).unwrap();
        let next = GrayImage::decode(include_bytes!("../testdata/lk_next.png")).unwrap();
        let pts: Vec<[f32; 2]> = LK_GOLDEN.iter().map(|g| g.0).collect();
        let out = calc_optical_flow_pyr_lk(&prev, &next, &pts, &LkParams::default());
        // The portable kernels (CPUs without AVX2, wasm without SIMD) give the same bits.
        assert_eq!(calc_optical_flow_pyr_lk_portable(&prev, &next, &pts, &LkParams::default()), out);
        let mut exact = 0;
        for (i, g) in LK_GOLDEN.iter().enumerate() {
            let got = [out.next_pts[i][0].to_bits(), out.next_pts[i][1].to_bits()];
            assert_eq!(out.status[i] as u8, g.2, "status of point {i}");
            assert_eq!(
                got,
                g.1,
                "point {i} {:?}: got {:?}, OpenCV {:?}",
                g.0,
                out.next_pts[i],
                [f32::from_bits(g.1[0]), f32::from_bits(g.1[1])]
            );
            if g.2 == 1 {
                assert_eq!(out.err[i].to_bits(), g.3, "err of point {i}");
            }
            exact += 1;
        }
        assert_eq!(exact, 68);
    }
}
