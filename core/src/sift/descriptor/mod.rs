//! The 128-value descriptor, `calcSIFTDescriptor` (docs/fidelity.md §SIFT-11): a 4×4 grid of
//! 8-bin orientation histograms with trilinear interpolation, clipped at
//! 0.2 and scaled to integers 0..255.
//!
//! This file is the algorithm in OpenCV's order and the dispatch: the window's
//! samples, the trilinear histogram (OpenCV's SIMD body and its scalar tail),
//! the fold and the normalisation. The vector kernels for the sample rows and
//! the SIMD body live beside it, in `vector.rs` (one form for AVX-512, AVX2
//! and SIMD128), with the same operations per lane.

use super::image::Plane;
use super::keypoint::KeyPoint;
use super::num::{floor, fma, gradient_samples, rne, FLT_EPSILON};
use super::params::SiftParams;

mod layout;
mod vector;

use layout::{cell_offsets, Rows, Samples, BINS_PER_DEG, D, HIST_LEN, N};

// §SIFT-1: window factor 3, clip at 0.2, scale 512 (the 4×4 cells of 8 bins: `layout`).
const SCL_FCTR: f32 = 3.0;
const MAG_THR: f32 = 0.2;
const INT_DESCR_FCTR: f32 = 512.0;

/// Computes the descriptor of one keypoint (already rescaled, octave packed
/// as OpenCV reports it) from the Gaussian pyramid.
pub fn descriptor(gauss: &[Plane], kp: &KeyPoint, p: &SiftParams) -> [u8; 128] {
    // unpackOctave
    let mut oct = kp.octave & 255;
    if oct >= 128 {
        oct -= 256;
    }
    let layer = ((kp.octave >> 8) & 255) as usize;
    let scale = if oct >= 0 { 1.0 / (1u32 << oct) as f32 } else { (1u32 << -oct) as f32 };
    let (ptx, pty) = (kp.x * scale, kp.y * scale);
    let scl = (kp.size * scale) * 0.5;
    let level = (oct + 1) as usize * (p.n_octave_layers + 3) + layer;
    let Some(img) = gauss.get(level) else {
        return [0; 128];
    };
    let mut ori = 360.0 - kp.angle;
    if (ori - 360.0).abs() < FLT_EPSILON {
        ori = 0.0;
    }
    let lanes = p.opencv_lanes;
    crate::with_hw_fma!([u8; 128], calc_descriptor(img, ptx, pty, ori, scl, lanes))
}

#[inline(always)]
fn calc_descriptor(img: &Plane, ptx: f32, pty: f32, ori: f32, scl: f32, lanes: usize) -> [u8; 128] {
    let (px, py) = (rne(ptx) as i64, rne(pty) as i64);
    let angle_rad = ori * f32::from_bits(0x3C8EFA35); // (float)(CV_PI/180)
    let (mut cos_t, mut sin_t) = (angle_rad.cos(), angle_rad.sin());
    let exp_scale = -1.0 / ((D * D) as f32 * 0.5);
    let hist_width = SCL_FCTR * scl;
    let (rows, cols) = (img.height as i64, img.width as i64);
    let mut radius = rne(((hist_width * std::f32::consts::SQRT_2) * (D + 1) as f32) * 0.5) as i64;
    let diag = ((cols * cols + rows * rows) as f64).sqrt() as i64;
    radius = radius.min(diag);
    cos_t /= hist_width;
    sin_t /= hist_width;

    let samples = collect_samples(img, px, py, radius, cos_t, sin_t, exp_scale);
    let len = samples.dx.len();
    let simd_len = len - len % lanes;
    let (oris, mags, wts) = gradient_samples(&samples.dx, &samples.dy, &samples.w);
    let mut hist = [0f32; HIST_LEN];
    let inputs = Rows { rbin: &samples.rbin, cbin: &samples.cbin, ori: &oris, mag: &mags, wt: &wts };
    let done = accumulate_simd_body(&inputs, simd_len, ori, &mut hist);
    for k in done..len {
        let (idx, rc, obin) = bins(&inputs, k, ori);
        if k < simd_len {
            // The SIMD body rounds every product and difference separately.
            for (off, rc) in cell_offsets().into_iter().zip(rc) {
                let rco1 = rc * obin;
                let rco0 = rc - rco1;
                hist[idx + off] += rco0;
                hist[idx + off + 1] += rco1;
            }
        } else {
            // The scalar tail (§SIFT-11, §SIFT-13), contracted by GCC: `rc - rc*obin` is one FMA
            // and `hist += rc*obin` another.
            for (off, rc) in cell_offsets().into_iter().zip(rc) {
                hist[idx + off] += fma(-rc, obin, rc);
                hist[idx + off + 1] = fma(rc, obin, hist[idx + off + 1]);
            }
        }
    }

    // Fold the cyclic orientation bins and drop the spatial border.
    let mut raw = [0f32; D * D * N];
    for i in 0..D {
        for j in 0..D {
            let b = ((i + 1) * (D + 2) + (j + 1)) * (N + 2);
            hist[b] += hist[b + N];
            hist[b + 1] += hist[b + N + 1];
            for k in 0..N {
                raw[(i * D + j) * N + k] = hist[b + k];
            }
        }
    }
    normalize(&mut raw, lanes)
}

/// Histogram index of sample k's (r0, c0, o0) bin, the four cell weights
/// (00, 01, 10, 11) and the fractional orientation bin.
#[inline(always)]
fn bins(s: &Rows, k: usize, ori: f32) -> (usize, [f32; 4], f32) {
    let (mut rbin, mut cbin) = (s.rbin[k], s.cbin[k]);
    let mut obin = (s.ori[k] - ori) * BINS_PER_DEG;
    let mag = s.mag[k] * s.wt[k];
    let r0 = floor(rbin);
    let c0 = floor(cbin);
    let mut o0 = floor(obin);
    rbin -= r0 as f32;
    cbin -= c0 as f32;
    obin -= o0 as f32;
    if o0 < 0 {
        o0 += N as i32;
    }
    if o0 >= N as i32 {
        o0 -= N as i32;
    }
    let v_r1 = mag * rbin;
    let v_r0 = mag - v_r1;
    let v_rc11 = v_r1 * cbin;
    let v_rc10 = v_r1 - v_rc11;
    let v_rc01 = v_r0 * cbin;
    let v_rc00 = v_r0 - v_rc01;
    let idx = (((r0 + 1) * (D as i32 + 2) + c0 + 1) * (N as i32 + 2) + o0) as usize;
    (idx, [v_rc00, v_rc01, v_rc10, v_rc11], obin)
}

/// OpenCV visits the whole (2r+1)² square and keeps the samples whose
/// rotated bin coordinates fall in the grid and whose pixel has all four
/// neighbours. Here the rows and columns that cannot pass are skipped
/// up front ([`sample_columns`], the image border); the float test still
/// decides every sample visited, so the samples and their order are OpenCV's.
#[inline(always)]
fn collect_samples(img: &Plane, px: i64, py: i64, radius: i64, cos_t: f32, sin_t: f32, exp_scale: f32) -> Samples {
    let (rows, cols) = (img.height as i64, img.width as i64);
    let cap = ((2 * radius + 1) * (2 * radius + 1)) as usize;
    let mut s = Samples {
        dx: Vec::with_capacity(cap),
        dy: Vec::with_capacity(cap),
        w: Vec::with_capacity(cap),
        rbin: Vec::with_capacity(cap),
        cbin: Vec::with_capacity(cap),
    };
    for i in -radius..=radius {
        let r = py + i;
        if r <= 0 || r >= rows - 1 {
            continue;
        }
        let Some((j0, j1)) = sample_columns(i, radius, cos_t, sin_t) else { continue };
        let (j0, j1) = (j0.max(1 - px), j1.min(cols - 2 - px));
        if j0 > j1 {
            continue;
        }
        let fi = i as f32;
        let (a, b) = (-(fi * sin_t), fi * cos_t);
        let r = r as usize;
        let (row, up, down) = (img.row(r), img.row(r - 1), img.row(r + 1));
        let c0 = (px + j0) as usize;
        let n = (j1 - j0 + 1) as usize;
        let done = super::lanes::run(&mut vector::SampleRow {
            s: &mut s,
            rows: [row, up, down],
            c0,
            n,
            j0: j0 as f32,
            rot: [cos_t, sin_t, a, b],
            exp_scale,
        });
        for t in done..n {
            let fj = (j0 + t as i64) as f32;
            let c_rot = fma(fj, cos_t, a);
            let r_rot = fma(fj, sin_t, b);
            let rbin = (r_rot + D as f32 / 2.0) - 0.5;
            let cbin = (c_rot + D as f32 / 2.0) - 0.5;
            if rbin > -1.0 && rbin < D as f32 && cbin > -1.0 && cbin < D as f32 {
                let c = c0 + t;
                s.dx.push(row[c + 1] - row[c - 1]);
                s.dy.push(up[c] - down[c]);
                s.rbin.push(rbin);
                s.cbin.push(cbin);
                s.w.push(fma(c_rot, c_rot, r_rot * r_rot) * exp_scale);
            }
        }
    }
    s
}

/// A conservative range of j for row i outside which no sample can land
/// in the 4x4 grid (|c_rot|, |r_rot| < 2.5): the exact float test still
/// decides every sample inside it, so results are unchanged, but about half
/// of the (2r+1)^2 square is never visited.
#[inline(always)]
fn sample_columns(i: i64, radius: i64, cos_t: f32, sin_t: f32) -> Option<(i64, i64)> {
    let (mut lo, mut hi) = (-radius as f64, radius as f64);
    let fi = i as f64;
    for (slope, offset) in [(cos_t as f64, -fi * sin_t as f64), (sin_t as f64, fi * cos_t as f64)] {
        if slope.abs() > 1e-9 {
            let (a, b) = ((-2.6 - offset) / slope, (2.6 - offset) / slope);
            lo = lo.max(a.min(b).floor() - 1.0);
            hi = hi.min(a.max(b).ceil() + 1.0);
        } else if offset.abs() > 2.6 {
            return None;
        }
    }
    if lo > hi {
        None
    } else {
        Some((lo as i64, hi as i64))
    }
}

/// Accumulates the samples `0..simd_len` (OpenCV's SIMD body, §SIFT-11) with vector
/// arithmetic where the CPU allows; returns how many it did.
#[inline(always)]
fn accumulate_simd_body(s: &Rows, simd_len: usize, ori: f32, hist: &mut [f32; HIST_LEN]) -> usize {
    super::lanes::run(&mut vector::Accumulate { s, len: simd_len, ori, hist })
}

/// Clip at 0.2 of the norm, renormalise to 512 and round (§SIFT-11): OpenCV's
/// accumulator layout for the first norm depends on its SIMD width (§SIFT-13).
#[inline(always)]
fn normalize(raw: &mut [f32; 128], lanes: usize) -> [u8; 128] {
    let nrm2 = if lanes == 16 {
        let mut acc = [0f32; 16];
        for t in 0..8 {
            for l in 0..16 {
                acc[l] = fma(raw[l + 16 * t], raw[l + 16 * t], acc[l]);
            }
        }
        let mut h = [0f32; 8];
        for i in 0..8 {
            h[i] = acc[i] + acc[i + 8];
        }
        let q = [h[0] + h[4], h[1] + h[5], h[2] + h[6], h[3] + h[7]];
        (q[0] + q[1]) + (q[2] + q[3])
    } else {
        let mut acc = [0f32; 8];
        for t in 0..16 {
            for l in 0..8 {
                acc[l] = fma(raw[l + 8 * t], raw[l + 8 * t], acc[l]);
            }
        }
        ((acc[0] + acc[1]) + (acc[2] + acc[3])) + ((acc[4] + acc[5]) + (acc[6] + acc[7]))
    };
    let thr = nrm2.sqrt() * MAG_THR;
    let mut n2 = 0f32;
    for v in raw.iter_mut() {
        *v = v.min(thr);
        // A separate multiply and add (docs/fidelity.md §SIFT-11, second norm):
        // OpenCV's source reads as an FMA, but GCC does not contract this
        // loop in either build. Measured against the wheel with IPP off on
        // 100 synthetic KITTI frames: the FMA form put 8 of 150,041 rows off
        // by one on an AVX-512 CPU and 7 on an AVX2 CPU; this form none on
        // either (a test below holds one of the 7).
        n2 += *v * *v;
    }
    let s = INT_DESCR_FCTR / n2.sqrt().max(FLT_EPSILON);
    let mut out = [0u8; 128];
    for (o, &v) in out.iter_mut().zip(raw.iter()) {
        *o = (rne(v * s) as f32).clamp(0.0, 255.0) as u8;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::normalize;

    /// Keypoint 990 of frame 27 of a synthetic KITTI-like sequence (the renderer
    /// that made it was retired once the real frames were bundled),
    /// the histogram our descriptor builds for it and the row OpenCV 4.8.0.76
    /// (`OPENCV_IPP=disabled`, an AVX2 CPU: 8 lanes) returns. Normalising with
    /// an FMA in the second norm (as OpenCV's source reads) gives 45 at
    /// element 32; OpenCV gives 46.
    const RAW_BITS: [u32; 128] = [
        0x421d434a, 0x415e6fff, 0x408b6087, 0x41135d28, 0x423fd148, 0x412cabf8, 0x408a4f5b, 0x3fe6a268, 0x43aae13c,
        0x422d3bb6, 0x4040d82f, 0x403cae56, 0x40bf16bc, 0x3e95f8c1, 0x411d20b2, 0x4253cc55, 0x42404308, 0x40d22a81,
        0x41981215, 0x408e1437, 0x3f8db948, 0x3f00bd1e, 0x42c1fef6, 0x42260657, 0x3f13766b, 0x403c9de4, 0x423d43c1,
        0x3fb60977, 0x3cd7ea17, 0x3fc5b4a1, 0x42d202e3, 0x4111787c, 0x42641442, 0x40a0ecf9, 0x3f6f3a53, 0x419c7e4c,
        0x42f2b876, 0x40e947c0, 0x3fbe07cf, 0x409f57ff, 0x44162dd1, 0x41e1462a, 0x3f2faa3b, 0x403f929b, 0x41c91f7b,
        0x40e66ff8, 0x40875dff, 0x4291af3c, 0x42a6b3a1, 0x40e5aa27, 0x4226643b, 0x420d05c2, 0x42c37bb0, 0x422c88e8,
        0x41467bab, 0x41f00171, 0x3e544a99, 0x403ee62f, 0x430f122c, 0x41942156, 0x410666ff, 0x411e1375, 0x41c33d6d,
        0x4003cc4f, 0x4233a692, 0x3f1a354f, 0x3f180321, 0x414648a6, 0x42772aea, 0x4282735c, 0x4241a578, 0x4148a84b,
        0x440cfcab, 0x429526c4, 0x40515b66, 0x40534641, 0x41559431, 0x415d15fb, 0x4147ce2b, 0x422f3079, 0x42bc1a48,
        0x42086495, 0x4163e7e8, 0x425e1469, 0x42d22e32, 0x425efff6, 0x411b4e86, 0x40999712, 0x3d98f5c0, 0x3f0232c7,
        0x421cbb08, 0x42610b86, 0x41720660, 0x41e12474, 0x422c70d6, 0x3f542926, 0x40a84272, 0x3d2cc87c, 0x3f3d6a3a,
        0x3fa27342, 0x40c16518, 0x430c9263, 0x43069a9e, 0x414b31f6, 0x4348991a, 0x4124bc8a, 0x3f86084d, 0x3f988122,
        0x406e8d62, 0x4228e4b0, 0x423ff76c, 0x4308aa07, 0x42592e46, 0x40d15669, 0x40cf9f38, 0x421411ef, 0x427fb611,
        0x426107c6, 0x40c0221a, 0x41d8a8b6, 0x3f0334b5, 0x3f4e458b, 0x41a6b82f, 0x42166a4f, 0x41d0456c, 0x4285dc0d,
        0x412058e0, 0x3f81ffee,
    ];
    const OPENCV_ROW: [u8; 128] = [
        31, 11, 3, 7, 38, 9, 3, 1, 166, 35, 2, 2, 5, 0, 8, 42, 38, 5, 15, 4, 1, 0, 77, 33, 0, 2, 38, 1, 0, 1, 84, 7,
        46, 4, 1, 16, 97, 6, 1, 4, 166, 22, 1, 2, 20, 6, 3, 58, 67, 6, 33, 28, 78, 34, 10, 24, 0, 2, 114, 15, 7, 8, 19,
        2, 36, 0, 0, 10, 49, 52, 39, 10, 166, 60, 3, 3, 11, 11, 10, 35, 75, 27, 11, 44, 84, 44, 8, 4, 0, 0, 31, 45, 12,
        22, 34, 1, 4, 0, 1, 1, 5, 112, 107, 10, 160, 8, 1, 1, 3, 34, 38, 109, 43, 5, 5, 30, 51, 45, 5, 22, 0, 1, 17,
        30, 21, 53, 8, 1,
    ];

    #[test]
    fn the_second_norm_is_a_multiply_then_an_add_as_opencv_computes_it() {
        let mut raw = RAW_BITS.map(f32::from_bits);
        assert_eq!(normalize(&mut raw, 8), OPENCV_ROW);
    }
}
