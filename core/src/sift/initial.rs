//! `createInitialImage` with doubleImageSize = true (docs/fidelity.md §SIFT-2).

use super::blur::{gaussian_blur_rows, Rows};
use super::image::Plane;
use crate::image::GrayImage;

/// The pyramid base: the gray image as float, upsampled ×2 bilinearly, then
/// blurred from the assumed camera blur 0.5 (doubled: 1.0) up to σ = 1.6.
pub fn initial_image(img: &GrayImage, sigma: f64) -> Plane {
    let s = sigma as f32;
    // Evaluated in f32 without FMA, as sift.dispatch.cpp is compiled for the
    // SSE3 baseline: 1.6f*1.6f rounds to 2.5600002f.
    let sig_diff = (s * s - 0.5f32 * 0.5f32 * 4.0f32).max(0.01f32).sqrt();
    gaussian_blur_rows(&Upsampled::new(img), sig_diff as f64)
}

/// The ×2 upsampled image for the blur: the horizontal pass stored, each
/// output row's vertical blend made when the blur reads it, so the
/// upsampled plane is never stored: its rows live in the blur's row buffer.
struct Upsampled {
    /// The horizontal pass: 2w × h.
    tmp: Plane,
}

impl Upsampled {
    fn new(img: &GrayImage) -> Self {
        let (w, h) = (img.width(), img.height());
        let w2 = 2 * w;
        let mut tmp = Plane::for_overwrite(w2, h);
        crate::par::for_each_chunk(&mut tmp.data, w2, |y0, rows| {
            for (dy, row) in rows.chunks_exact_mut(w2).enumerate() {
                upsample_row(&img.data()[(y0 + dy) * w..(y0 + dy + 1) * w], row);
            }
        });
        Upsampled { tmp }
    }
}

impl Rows for Upsampled {
    fn width(&self) -> usize {
        self.tmp.width
    }
    fn height(&self) -> usize {
        2 * self.tmp.height
    }
    fn row<'a>(&'a self, y: usize, buf: &'a mut [f32]) -> &'a [f32] {
        let (a, b, f) = vertical_taps(y, self.tmp.height);
        blend_rows(self.tmp.row(a), self.tmp.row(b), f, buf);
        buf
    }
}

/// Source rows and the weight of the second for output row `t` of `n`
/// source rows: (left, right, weight of right).
fn vertical_taps(t: usize, n: usize) -> (usize, usize, f32) {
    let m = t / 2;
    if t.is_multiple_of(2) {
        if m == 0 {
            (0, 0, 0.0)
        } else {
            (m - 1, m, 0.75)
        }
    } else if m + 1 >= n {
        (n - 1, n - 1, 0.0)
    } else {
        (m, m + 1, 0.25)
    }
}

/// `d = ta·(1 − f) + tb·f` across a row (exact: multiples of 1/16 below 256).
fn blend_rows(ta: &[f32], tb: &[f32], f: f32, d: &mut [f32]) {
    #[inline(always)]
    fn body(ta: &[f32], tb: &[f32], f: f32, d: &mut [f32]) {
        for ((d, &a), &b) in d.iter_mut().zip(ta).zip(tb) {
            *d = a * (1.0 - f) + b * f;
        }
    }
    #[cfg(target_arch = "x86_64")]
    {
        #[target_feature(enable = "avx2")]
        fn avx2(ta: &[f32], tb: &[f32], f: f32, d: &mut [f32]) {
            body(ta, tb, f, d)
        }
        if crate::simd::avx2() {
            // SAFETY: the CPU has AVX2, the only feature `avx2` enables.
            return unsafe { avx2(ta, tb, f, d) };
        }
    }
    body(ta, tb, f, d)
}

/// INTER_LINEAR ×2 with the pixel-centre convention. Source coordinate of
/// destination t is (t + 0.5)/2 − 0.5, so weights are (0.25, 0.75) with edge
/// replication. All values are multiples of 1/16 below 256, so this is exact
/// whatever implementation OpenCV dispatches to (IPP included). The horizontal
/// pass ([`upsample_row`]) takes destination pixels 2m and 2m+1 from source
/// pixels m−1, m and m+1, a row as one pass over source triples; the
/// vertical pass is [`Upsampled`]'s rows.
#[cfg(test)]
fn upsample2x(img: &GrayImage) -> Plane {
    let up = Upsampled::new(img);
    let (w2, h2) = (up.width(), up.height());
    let mut out = Plane::for_overwrite(w2, h2);
    let mut buf = vec![0f32; w2];
    for (y, row) in out.data.chunks_exact_mut(w2).enumerate() {
        row.copy_from_slice(up.row(y, &mut buf));
    }
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
        fn avx2(src: &[u8], out: &mut [f32]) {
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
        let mut rng = crate::testutil::XorShift64::new(0x2545_f491);
        for w in 1..=40usize {
            let src: Vec<u8> = (0..w).map(|_| rng.byte()).collect();
            let mut out = vec![f32::NAN; 2 * w];
            upsample_row(&src, &mut out);
            for (t, &got) in out.iter().enumerate() {
                // The unrolled row against the tap rule the vertical pass uses.
                let (a, b, f) = vertical_taps(t, w);
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
