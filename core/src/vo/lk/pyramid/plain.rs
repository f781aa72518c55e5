//! The pyramid's plain parts, shared by the portable code and the AVX2
//! kernels beside it: the padded level, the derivative planes and their
//! portable computation, and `pyrDown`'s edge columns and vertical pass.

use super::super::WIN;
use crate::border::reflect101;

/// Border around every padded level: OpenCV pads by the window size.
pub(crate) const PAD: usize = WIN;
/// Slack after every padded plane so 8-lane loads at the last window column
/// stay inside the buffer.
pub(crate) const SLACK: usize = 32;

/// Horizontal sums of the output columns `xs` of one row, reflect-101.
#[inline(always)]
pub(super) fn pyr_down_row_edges(row: &[u8], out: &mut [u16], xs: std::ops::Range<usize>) {
    let w = row.len();
    for x in xs {
        let c = 2 * x as isize;
        let at = |d: isize| row[reflect101(c + d, w)] as u16;
        out[x] = at(-2) + 4 * at(-1) + 6 * at(0) + 4 * at(1) + at(2);
    }
}

/// The vertical pass over the horizontal sums, reflect-101 rows.
#[inline(always)]
pub(super) fn pyr_down_columns(hrow: &[u16], dw: usize, h: usize) -> (Vec<u8>, usize, usize) {
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

/// One pyramid level stored with a PAD-pixel reflect-101 border, as
/// `buildOpticalFlowPyramid` keeps it.
#[derive(Clone, Debug)]
pub struct Level {
    pub w: usize,
    pub h: usize,
    /// Unpadded pixels (row-major w×h).
    pub pixels: Vec<u8>,
    pub(crate) stride: usize,
    pub(crate) padded: Vec<u8>,
}

impl Level {
    pub(crate) fn new(pixels: Vec<u8>, w: usize, h: usize) -> Self {
        let stride = w + 2 * PAD;
        let ph = h + 2 * PAD;
        let mut padded = vec![0u8; stride * ph + SLACK];
        // Only the PAD columns on each side are reflected; the row itself
        // is one slice copy, not a gather per pixel.
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
    pub(crate) fn offset(&self, x: i32, y: i32) -> usize {
        ((y + PAD as i32) as usize) * self.stride + (x + PAD as i32) as usize
    }
}

/// Scharr derivatives of one level (`calcSharrDeriv`, §VO-2.3): no scaling,
/// reflect-101 inside the level, then a PAD-pixel border of zeros
/// (BORDER_CONSTANT).
#[derive(Clone, Debug)]
pub struct Deriv {
    pub(crate) stride: usize,
    pub(crate) ix: Vec<i16>,
    pub(crate) iy: Vec<i16>,
}

impl Deriv {
    /// In 16-bit lanes (compiled for AVX2 where the CPU has it, sixteen
    /// columns at a time): every sum is within ±16·255 = ±4080.
    #[inline(always)]
    pub(super) fn compute(level: &Level) -> Self {
        let (w, h) = (level.w, level.h);
        let img = &level.pixels;
        let stride = w + 2 * PAD;
        let len = stride * (h + 2 * PAD) + SLACK;
        // Written front to back, each element once: the zero border, then
        // per row its pixels and the border around them, so no plane is
        // zeroed first.
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
    pub(crate) fn offset(&self, x: i32, y: i32) -> usize {
        ((y + PAD as i32) as usize) * self.stride + (x + PAD as i32) as usize
    }
}
