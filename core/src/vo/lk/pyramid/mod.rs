//! The pyramids `calcOpticalFlowPyrLK` builds (docs/fidelity.md §VO-2.2,
//! §VO-2.3): `buildOpticalFlowPyramid`'s levels by exact integer `pyrDown`,
//! each stored with a reflect-101 border as OpenCV pads it, and the previous
//! image's unscaled Scharr derivatives per level, bordered with zeros. The
//! AVX2 versions (`x86`) compute the same integers.

use super::WIN;
#[cfg(test)]
use crate::border::reflect101;
use crate::image::GrayImage;

mod plain;
#[cfg(target_arch = "x86_64")]
mod x86;

use plain::{pyr_down_columns, pyr_down_row_edges};
pub use plain::{Deriv, Level};

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

impl Deriv {
    pub fn new(level: &Level) -> Self {
        #[cfg(target_arch = "x86_64")]
        if crate::simd::avx2() {
            // SAFETY: the CPU has AVX2, the one feature the function enables.
            return unsafe { x86::deriv_avx2(level) };
        }
        Deriv::compute(level)
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
