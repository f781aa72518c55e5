//! `createInitialImage` with doubleImageSize = true (spec §2).

use super::blur::gaussian_blur;
use super::image::Plane;
use crate::image::GrayImage;

/// The pyramid base: the gray image as float, upsampled ×2 bilinearly, then
/// blurred from the assumed camera blur 0.5 (doubled: 1.0) up to σ = 1.6.
pub fn initial_image(img: &GrayImage, sigma: f64) -> Plane {
    let s = sigma as f32;
    // Evaluated in f32 without FMA, as sift.dispatch.cpp is compiled for the
    // SSE3 baseline: 1.6f*1.6f rounds to 2.5600002f.
    let sig_diff = (s * s - 0.5f32 * 0.5f32 * 4.0f32).max(0.01f32).sqrt();
    let up = upsample2x(img);
    gaussian_blur(&up, sig_diff as f64)
}

/// INTER_LINEAR ×2 with the pixel-centre convention. Source coordinate of
/// destination t is (t + 0.5)/2 − 0.5, so weights are (0.25, 0.75) with edge
/// replication. All values are multiples of 1/16 below 256, so this is exact
/// whatever implementation OpenCV dispatches to (IPP included).
fn upsample2x(img: &GrayImage) -> Plane {
    let (w, h) = (img.width(), img.height());
    let (w2, h2) = (2 * w, 2 * h);
    let taps = |t: usize, n: usize| -> (usize, usize, f32) {
        // (left, right, weight of right)
        let m = t / 2;
        if t % 2 == 0 {
            if m == 0 { (0, 0, 0.0) } else { (m - 1, m, 0.75) }
        } else if m + 1 >= n {
            (n - 1, n - 1, 0.0)
        } else {
            (m, m + 1, 0.25)
        }
    };
    // Horizontal pass: destination pixels 2m and 2m+1 both lie between
    // source pixels m−1, m and m+1, so a row is one pass over source
    // triples (vectorised; any order gives the same exact sums).
    let mut tmp = Plane::for_overwrite(w2, h);
    super::par::for_each_chunk(&mut tmp.data, w2, |y0, rows| {
        for (dy, row) in rows.chunks_exact_mut(w2).enumerate() {
            upsample_row(&img.data()[(y0 + dy) * w..(y0 + dy + 1) * w], row);
        }
    });
    let mut out = Plane::for_overwrite(w2, h2);
    super::par::for_each_chunk(&mut out.data, w2, |y0, rows| {
        for (dy, row) in rows.chunks_exact_mut(w2).enumerate() {
            let (a, b, f) = taps(y0 + dy, h);
            for ((d, &ta), &tb) in row.iter_mut().zip(tmp.row(a)).zip(tmp.row(b)) {
                *d = ta * (1.0 - f) + tb * f;
            }
        }
    });
    out
}

/// One row of the horizontal pass: `out[2m] = ¼·src[m−1] + ¾·src[m]`,
/// `out[2m+1] = ¾·src[m] + ¼·src[m+1]`, the ends replicated.
fn upsample_row(src: &[u8], out: &mut [f32]) {
    #[inline(always)]
    fn body(src: &[u8], out: &mut [f32]) {
        let w = src.len();
        if w == 0 {
            return;
        }
        out[0] = src[0] as f32;
        out[2 * w - 1] = src[w - 1] as f32;
        for (pair, s) in out[1..2 * w - 1].chunks_exact_mut(2).zip(src.windows(2)) {
            let (a, b) = (s[0] as f32, s[1] as f32);
            pair[0] = a * 0.75 + b * 0.25;
            pair[1] = a * 0.25 + b * 0.75;
        }
    }
    #[cfg(target_arch = "x86_64")]
    {
        #[target_feature(enable = "avx2")]
        unsafe fn avx2(src: &[u8], out: &mut [f32]) {
            body(src, out)
        }
        if crate::simd::avx2() {
            // SAFETY: the CPU has AVX2, the only feature `avx2` enables.
            return unsafe { avx2(src, out) };
        }
    }
    body(src, out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn upsample_weights_and_edges() {
        let img = GrayImage::new(3, 1, vec![0, 16, 32]).unwrap();
        let up = upsample2x(&img);
        assert_eq!(up.width, 6);
        assert_eq!(up.row(0), &[0.0, 4.0, 12.0, 20.0, 28.0, 32.0]);
        assert_eq!(up.row(1), up.row(0));
    }

    /// The row pass against INTER_LINEAR's taps written out per pixel, for
    /// every width from 1 (both ends replicated) to 40.
    #[test]
    fn upsample_row_is_inter_linear() {
        let mut s = 0x2545_f491u32;
        for w in 1..=40usize {
            let src: Vec<u8> = (0..w).map(|_| { s ^= s << 13; s ^= s >> 17; s ^= s << 5; s as u8 }).collect();
            let mut out = vec![f32::NAN; 2 * w];
            upsample_row(&src, &mut out);
            for (t, &got) in out.iter().enumerate() {
                let m = t / 2;
                let (a, b, f) = if t % 2 == 0 {
                    if m == 0 { (0, 0, 0.0) } else { (m - 1, m, 0.75) }
                } else if m + 1 >= w {
                    (w - 1, w - 1, 0.0)
                } else {
                    (m, m + 1, 0.25)
                };
                let want = src[a] as f32 * (1.0 - f) + src[b] as f32 * f;
                assert_eq!(got.to_bits(), want.to_bits(), "w {w}, t {t}");
            }
        }
    }

    #[test]
    fn sig_diff_is_opencvs() {
        let s = 1.6f32;
        let sig_diff = (s * s - 1.0f32).max(0.01f32).sqrt();
        assert_eq!(sig_diff.to_bits(), 0x3F9FDF39);
    }
}
