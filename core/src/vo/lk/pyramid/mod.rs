//! The pyramids `calcOpticalFlowPyrLK` builds (docs/fidelity.md §VO-2.2,
//! §VO-2.3): `buildOpticalFlowPyramid`'s levels by exact integer `pyrDown`,
//! each stored with a reflect-101 border as OpenCV pads it, and the previous
//! image's unscaled Scharr derivatives per level, bordered with zeros. The
//! AVX2 versions (`x86`) compute the same integers.

use super::WIN;
use crate::border::reflect101;
use crate::image::GrayImage;

#[cfg(target_arch = "x86_64")]
mod x86;

/// Border around every padded level: OpenCV pads by the window size.
const PAD: usize = WIN;
/// Slack after every padded plane so 8-lane loads at the last window column
/// stay inside the buffer.
const SLACK: usize = 32;

/// `cv::pyrDown` on 8-bit data, exact integer arithmetic: the 5×5 binomial
/// kernel (sum 256) over reflect-101 of the source level, `+128 >> 8`
/// (§VO-2.2; truncating instead moved 92 % of the tracked points).
pub fn pyr_down(src: &[u8], w: usize, h: usize) -> (Vec<u8>, usize, usize) {
    #[cfg(target_arch = "x86_64")]
    if crate::simd::avx2() && w >= 40 {
        // SAFETY: the CPU has AVX2, the one feature the function enables.
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

/// One pyramid level stored with a PAD-pixel reflect-101 border, as
/// `buildOpticalFlowPyramid` keeps it.
#[derive(Clone, Debug)]
pub struct Level {
    pub w: usize,
    pub h: usize,
    /// Unpadded pixels (row-major w×h).
    pub pixels: Vec<u8>,
    pub(super) stride: usize,
    pub(super) padded: Vec<u8>,
}

impl Level {
    pub(super) fn new(pixels: Vec<u8>, w: usize, h: usize) -> Self {
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
    pub(super) fn offset(&self, x: i32, y: i32) -> usize {
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

/// An image pyramid as the tracker uses it; build it once per frame and pass
/// it as `next` for one call and as `prev` for the following one.
#[derive(Clone, Debug)]
pub struct Pyramid {
    pub(super) levels: Vec<Level>,
}

impl Pyramid {
    /// `buildOpticalFlowPyramid(img, (21, 21), max_level)`.
    pub fn new(img: &GrayImage, max_level: usize) -> Pyramid {
        Pyramid { levels: build_pyramid(img, max_level) }
    }
}

/// Scharr derivatives of one level (`calcSharrDeriv`, §VO-2.3): no scaling,
/// reflect-101 inside the level, then a PAD-pixel border of zeros
/// (BORDER_CONSTANT).
#[derive(Clone, Debug)]
pub struct Deriv {
    pub(super) stride: usize,
    pub(super) ix: Vec<i16>,
    pub(super) iy: Vec<i16>,
}

impl Deriv {
    pub fn new(level: &Level) -> Self {
        #[cfg(target_arch = "x86_64")]
        if crate::simd::avx2() {
            // SAFETY: the CPU has AVX2, the one feature the function enables.
            return unsafe { x86::deriv_avx2(level) };
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
    pub(super) fn offset(&self, x: i32, y: i32) -> usize {
        ((y + PAD as i32) as usize) * self.stride + (x + PAD as i32) as usize
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
}
