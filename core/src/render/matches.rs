//! `cv2.drawMatchesKnn(img1, kp1, img2, kp2, matches, None, flags=2)` as the
//! lab's `view_feature` calls it (OpenCV 4.8 `features2d/src/draw.cpp`):
//! both gray frames side by side converted to colour, and for every match a
//! random colour from `cv::theRNG()`, a LINE_AA circle of radius 3 around
//! each end point (drawn inside that frame's region, so it is clipped at the
//! seam) and a LINE_AA line from the query keypoint to the train keypoint,
//! all with 4 fractional bits. flags=2 (`NOT_DRAW_SINGLE_POINTS`) means
//! unmatched keypoints are not drawn.

use super::draw::{circle, line};
use crate::error::{Error, Result};
use crate::image::GrayImage;
use crate::matching::DMatch;
use crate::rng::CvRng;
use crate::sift::KeyPoint;
use image::{Rgb, RgbImage};

/// `Scalar(rng(256), rng(256), rng(256))` as an RGB colour. GCC evaluates
/// the three constructor arguments right to left, so the first number drawn
/// is the third (red, in OpenCV's BGR) component.
fn match_color(rng: &mut CvRng) -> Rgb<u8> {
    let r = rng.uniform(256) as u8;
    let g = rng.uniform(256) as u8;
    let b = rng.uniform(256) as u8;
    Rgb([r, g, b])
}

/// OpenCV's `draw_shift_bits`: keypoints are drawn with 4 fractional bits.
const DRAW_SHIFT: u32 = 4;

/// `cvRound(v * draw_multiplier)` in float, as draw.cpp computes it.
fn fixed(v: f32) -> i64 {
    (v * 16.0).round_ties_even() as i64
}

/// Runs `f` on the `w` x `h` region at (`x0`, 0) as if it were its own image
/// (OpenCV draws keypoint circles on a ROI, so they clip at the region's
/// border). Circles well inside the region are drawn in place; only the
/// rare ones near a border go through a copy.
fn circle_in_region(img: &mut RgbImage, x0: u32, w: u32, h: u32, center: (i64, i64), c: Rgb<u8>) {
    let radius = 3 << DRAW_SHIFT;
    // Footprint: radius 3 plus the 3-pixel LINE_AA kernel and the 2-pixel
    // LineAA clip margin; 8 pixels is safely outside all of it.
    let margin = 8 << DRAW_SHIFT;
    let inside = center.0 >= margin
        && center.1 >= margin
        && center.0 < ((w as i64) << DRAW_SHIFT) - margin
        && center.1 < ((h as i64) << DRAW_SHIFT) - margin;
    if inside {
        let shifted = (center.0 + ((x0 as i64) << DRAW_SHIFT), center.1);
        circle(img, shifted, radius, c, 1, true, DRAW_SHIFT);
    } else {
        let mut sub = image::imageops::crop_imm(img, x0, 0, w, h).to_image();
        circle(&mut sub, center, radius, c, 1, true, DRAW_SHIFT);
        image::imageops::replace(img, &sub, x0 as i64, 0);
    }
}

/// The keypoint a match names, or the error OpenCV would throw for an index
/// past the end of that image's keypoints.
fn keypoint<'a>(kps: &'a [KeyPoint], idx: usize, side: &str, image: &str) -> Result<&'a KeyPoint> {
    kps.get(idx).ok_or_else(|| {
        Error::InvalidArgument(format!("match {side} index {idx} but the {image} image has {} keypoints", kps.len()))
    })
}

/// `cv2.drawMatchesKnn(img1, kp1, img2, kp2, matches, None, flags=2)` with
/// the random colours drawn from `rng` (pass [`CvRng::the_rng`] for the
/// lab's colours). A match naming a keypoint that does not exist is an
/// error (OpenCV would throw).
pub fn draw_matches_knn(
    img1: &GrayImage,
    kp1: &[KeyPoint],
    img2: &GrayImage,
    kp2: &[KeyPoint],
    matches: &[Vec<DMatch>],
    rng: &mut CvRng,
) -> Result<RgbImage> {
    let (w1, h1) = (img1.width() as u32, img1.height() as u32);
    let (w2, h2) = (img2.width() as u32, img2.height() as u32);
    let (w, h) = (w1 + w2, h1.max(h2));
    let mut out = RgbImage::new(w, h);
    image::imageops::replace(&mut out, &super::gray_to_rgb(img1), 0, 0);
    image::imageops::replace(&mut out, &super::gray_to_rgb(img2), w1 as i64, 0);
    for m in matches.iter().flatten() {
        let a = keypoint(kp1, m.query_idx, "query", "first")?;
        let b = keypoint(kp2, m.train_idx, "train", "second")?;
        let c = match_color(rng);
        circle_in_region(&mut out, 0, w1, h1, (fixed(a.x), fixed(a.y)), c);
        circle_in_region(&mut out, w1, w2, h2, (fixed(b.x), fixed(b.y)), c);
        // draw.cpp: dpt2.x = min(pt2.x + img1.cols, outImg.cols - 1), in float.
        let bx = (b.x + w1 as f32).min((w - 1) as f32);
        line(&mut out, (fixed(a.x), fixed(a.y)), (fixed(bx), fixed(b.y)), c, 1, true, DRAW_SHIFT);
    }
    Ok(out)
}

/// The lab's `visualiseFeature`: `drawMatchesKnn` of the previous and the
/// current frame with only the selected feature's matches
/// (`matches[feature_id:feature_id+1]`), colours from a fresh `theRNG()`.
pub fn draw_feature(
    prev_image: &GrayImage,
    prev: &[KeyPoint],
    cur_image: &GrayImage,
    cur: &[KeyPoint],
    feature_matches: &[DMatch],
) -> Result<RgbImage> {
    draw_matches_knn(prev_image, prev, cur_image, cur, &[feature_matches.to_vec()], &mut CvRng::the_rng())
}

#[cfg(test)]
mod tests {
    use super::*;

    pub(crate) fn kp(x: f32, y: f32) -> KeyPoint {
        KeyPoint { x, y, size: 5.0, angle: -1.0, response: 0.0, octave: 0 }
    }

    pub(crate) fn dm(q: usize, t: usize) -> DMatch {
        DMatch { query_idx: q, train_idx: t, distance: 0.0 }
    }

    /// The gen_refs.py frames: two 80x60 gradients.
    fn frames() -> (GrayImage, GrayImage) {
        let mut a = Vec::new();
        let mut b = Vec::new();
        for y in 0..60usize {
            for x in 0..80usize {
                a.push(((x * 3 + y * 2) % 256) as u8);
                b.push(((x * 2 + y * 5 + 40) % 256) as u8);
            }
        }
        (GrayImage::new(80, 60, a).unwrap(), GrayImage::new(80, 60, b).unwrap())
    }

    fn reference(name: &str) -> RgbImage {
        let path = format!("{}/src/render/testdata/{name}", env!("CARGO_MANIFEST_DIR"));
        image::open(&path).unwrap_or_else(|e| panic!("{path}: {e}")).to_rgb8()
    }

    pub(crate) fn diff(a: &RgbImage, b: &RgbImage) -> Vec<(u32, u32, [u8; 3], [u8; 3])> {
        assert_eq!(a.dimensions(), b.dimensions());
        a.enumerate_pixels()
            .filter(|(x, y, p)| p.0 != b.get_pixel(*x, *y).0)
            .map(|(x, y, p)| (x, y, p.0, b.get_pixel(x, y).0))
            .collect()
    }

    #[test]
    fn the_rng_sequence_is_opencvs() {
        // cv::RNG(0xffffffff): state*4164903690 + carry, low 32 bits.
        let mut r = CvRng::the_rng();
        let first = r.next_u32();
        let expect = (0xffff_ffffu64 * 4164903690) as u32;
        assert_eq!(first, expect);
        let mut r2 = CvRng::new(0xffff_ffff);
        assert_eq!(r2.uniform(256), expect % 256);
    }

    #[test]
    fn draw_matches_knn_equals_opencv_pixel_for_pixel() {
        // gen_refs.py knn(): three matches for query 0, one each for 1 and 3,
        // keypoints on and near the borders and the seam.
        let (a, b) = frames();
        let kp1 = [kp(20.3, 30.7), kp(1.2, 2.6), kp(77.9, 58.6)];
        let kp2 = [kp(60.6, 10.4), kp(0.4, 57.5), kp(33.25, 29.75)];
        let m = vec![vec![dm(0, 2), dm(0, 0), dm(0, 1)], vec![dm(1, 1)], vec![], vec![dm(2, 0)]];
        let out = draw_matches_knn(&a, &kp1, &b, &kp2, &m, &mut CvRng::the_rng()).unwrap();
        let want = reference("knn.png");
        let d = diff(&out, &want);
        assert!(d.is_empty(), "{} pixels differ, first: {:?}", d.len(), &d[..d.len().min(8)]);
    }

    #[test]
    fn bad_match_index_is_an_error() {
        let (a, b) = frames();
        let err = draw_matches_knn(&a, &[kp(1.0, 1.0)], &b, &[], &[vec![dm(0, 0)]], &mut CvRng::the_rng()).unwrap_err();
        assert!(err.to_string().contains("train index 0"), "{err}");
    }
}
