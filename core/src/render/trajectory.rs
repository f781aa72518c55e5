//! The lab's trajectory window (`VisualOdometry.showDrive`): a 600x600 black
//! canvas, one radius-1 circle per frame for the estimate (red) and the ground
//! truth (green) at `(int(x)+290, int(z)+90)`, and a black band (10,20)-(600,60)
//! with `"Coordinates: x=%2fm y=%2fm z=%2fm"` of the current estimate.
//! `view_trajectory` writes the window's final state as `trajectory.png`.

use super::draw::{circle8, fill_rect};
use super::font::draw_text;
use image::{Rgb, RgbImage};

/// The lab's `(0, 0, 255)` BGR: the estimate.
pub const ESTIMATE: Rgb<u8> = Rgb([255, 0, 0]);
/// The lab's `(0, 255, 0)`: the ground truth.
pub const TRUTH: Rgb<u8> = Rgb([0, 255, 0]);
const WHITE: Rgb<u8> = Rgb([255, 255, 255]);
const BLACK: Rgb<u8> = Rgb([0, 0, 0]);

/// Canvas and mapping. The default is the lab's: 600x600, x and z in metres
/// truncated to pixels (`int(x)+290, int(z)+90`). `scale` multiplies the
/// metres before truncation, so a short trajectory can be enlarged.
#[derive(Clone, Debug, PartialEq)]
pub struct Style {
    pub width: u32,
    pub height: u32,
    /// Pixel of the world origin: the lab's (290, 90).
    pub origin: (i64, i64),
    /// Pixels per metre (the lab: 1).
    pub scale: f64,
    /// Text scale of the 5x7 font (the lab's Hershey PLAIN at 1 is ~10 px tall).
    pub text_scale: u32,
}

impl Default for Style {
    fn default() -> Self {
        Style { width: 600, height: 600, origin: (290, 90), scale: 1.0, text_scale: 1 }
    }
}

impl Style {
    /// Python's `int(v * scale) + origin`: truncation toward zero. NaN has
    /// no pixel (the lab would raise; we skip the point).
    pub fn to_pixel(&self, p: &[f64; 3]) -> Option<(i64, i64)> {
        let (x, z) = (p[0] * self.scale, p[2] * self.scale);
        if !x.is_finite() || !z.is_finite() {
            return None;
        }
        // `as i64` saturates, so huge values land far off the canvas and are clipped.
        Some(((x.trunc() as i64).saturating_add(self.origin.0), (z.trunc() as i64).saturating_add(self.origin.1)))
    }
}

/// Python's `"%2f" % v`: at least 2 wide, 6 decimals, `nan`/`inf` spelled as Python does.
pub fn py_fixed6(v: f64) -> String {
    if v.is_nan() {
        "nan".into()
    } else if v.is_infinite() {
        if v > 0.0 {
            "inf".into()
        } else {
            "-inf".into()
        }
    } else {
        format!("{v:.6}")
    }
}

/// The lab's caption for the current position.
pub fn coordinates_text(p: &[f64; 3]) -> String {
    format!("Coordinates: x={}m y={}m z={}m", py_fixed6(p[0]), py_fixed6(p[1]), py_fixed6(p[2]))
}

/// Adds frame `i`'s two points the way the lab's loop does: estimate first,
/// truth drawn over it.
pub fn plot_step(img: &mut RgbImage, truth: Option<&[f64; 3]>, estimate: Option<&[f64; 3]>, style: &Style) {
    if let Some(p) = estimate.and_then(|p| style.to_pixel(p)) {
        circle8(img, p, 1, ESTIMATE, false);
    }
    if let Some(p) = truth.and_then(|p| style.to_pixel(p)) {
        circle8(img, p, 1, TRUTH, false);
    }
}

/// Blanks the caption band and writes the coordinates of `current`
/// (`cv2.rectangle((10,20),(600,60),black,-1)` then `putText` at (20,40)).
pub fn caption(img: &mut RgbImage, current: &[f64; 3], style: &Style) {
    fill_rect(img, (10, 20), (600, 60), BLACK);
    draw_text(img, &coordinates_text(current), 20, 40, style.text_scale, WHITE);
}

/// The whole window after the last frame: for every frame `i`, the estimate
/// `estimate[i]` in red then the truth `truth[i]` in green; the caption shows
/// the last estimate (or the origin when there is none). The slices may have
/// different lengths; each is drawn as far as it goes.
///
/// To reproduce the lab's window exactly, pass what `showDrive` plotted: its
/// truth is (0, 0, 0) for frames 0 and 1 (`trueX..` are only set by the
/// scale lookup from frame 2) and its estimate at frame 1 is already the
/// unscaled unit translation.
pub fn draw(truth: &[[f64; 3]], estimate: &[[f64; 3]], style: &Style) -> RgbImage {
    let mut img = RgbImage::new(style.width.max(1), style.height.max(1));
    for i in 0..truth.len().max(estimate.len()) {
        plot_step(&mut img, truth.get(i), estimate.get(i), style);
    }
    caption(&mut img, estimate.last().unwrap_or(&[0.0; 3]), style);
    img
}

#[cfg(test)]
mod tests {
    use super::*;

    fn px(img: &RgbImage, x: u32, y: u32) -> [u8; 3] {
        img.get_pixel(x, y).0
    }

    #[test]
    fn lab_mapping_and_colours() {
        let truth = [[0.0, 0.0, 0.0], [1.9, 0.0, 100.7]];
        let est = [[0.0, 0.0, 0.0], [-5.7, -1.0, 83.9]];
        let img = draw(&truth, &est, &Style::default());
        assert_eq!(img.dimensions(), (600, 600));
        // Frame 0: both at (290, 90); truth drawn last so the cross is green.
        assert_eq!(px(&img, 291, 90), [0, 255, 0]);
        assert_eq!(px(&img, 290, 91), [0, 255, 0]);
        assert_eq!(px(&img, 290, 90), [0, 0, 0], "radius-1 circle has no centre");
        // Truth (1.9, 100.7) -> int -> (1, 100) -> (291, 190).
        assert_eq!(px(&img, 292, 190), [0, 255, 0]);
        assert_eq!(px(&img, 291, 189), [0, 255, 0]);
        // Estimate (-5.7, 83.9) -> int truncates toward zero -> (-5, 83) -> (285, 173).
        assert_eq!(px(&img, 284, 173), [255, 0, 0]);
        assert_eq!(px(&img, 286, 173), [255, 0, 0]);
        assert_eq!(px(&img, 285, 174), [255, 0, 0]);
        assert_eq!(px(&img, 285, 173), [0, 0, 0]);
    }

    #[test]
    fn caption_text_and_band() {
        assert_eq!(
            coordinates_text(&[-0.03253505574129042, -0.0229585009250804, 1.858783796014574]),
            "Coordinates: x=-0.032535m y=-0.022959m z=1.858784m"
        );
        assert_eq!(coordinates_text(&[f64::NAN, f64::INFINITY, 0.0]), "Coordinates: x=nanm y=infm z=0.000000m");
        // A point inside the band is erased by the caption, like the lab's rectangle.
        let img = draw(&[[-200.0, 0.0, -60.0]], &[[1.0, 2.0, 3.0]], &Style::default());
        assert_eq!(px(&img, 91, 30), [0, 0, 0]);
        // Text pixels: white, only inside the band, starting at x=20, rows 33..=39.
        let white: Vec<(u32, u32)> =
            img.enumerate_pixels().filter(|(_, _, p)| p.0 == [255, 255, 255]).map(|(x, y, _)| (x, y)).collect();
        assert!(white.len() > 200, "{}", white.len());
        assert!(white.iter().all(|&(x, y)| (20..600).contains(&x) && (33..40).contains(&y)));
        // 'C' (0x0E top row) at x=20..25: its top row lights columns 1..3.
        assert_eq!(px(&img, 21, 33), [255, 255, 255]);
        assert_eq!(px(&img, 20, 33), [0, 0, 0]);
    }

    #[test]
    fn scale_enlarges_and_far_or_nan_points_are_skipped() {
        let style = Style { scale: 4.0, ..Style::default() };
        let img = draw(&[[1.0, 0.0, 25.0], [f64::NAN, 0.0, 0.0], [1e300, 0.0, -1e300]], &[], &style);
        // (4, 100) + (290, 90) = (294, 190).
        assert_eq!(px(&img, 295, 190), [0, 255, 0]);
        assert_eq!(img.enumerate_pixels().filter(|(_, _, p)| p.0 == [0, 255, 0]).count(), 4);
        // Caption with no estimate shows the origin.
        assert_eq!(coordinates_text(&[0.0; 3]), "Coordinates: x=0.000000m y=0.000000m z=0.000000m");
    }
}

#[cfg(test)]
mod lab_reference {
    use super::*;

    /// Fixture truth and gen_refs.py traj()'s made-up estimate.
    fn paths() -> (Vec<[f64; 3]>, Vec<[f64; 3]>) {
        let text =
            std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../tests/fixtures/synthetic/poses/00.txt"))
                .unwrap();
        let truth: Vec<[f64; 3]> = text
            .lines()
            .map(|l| {
                let v: Vec<f64> = l.split_whitespace().map(|s| s.parse().unwrap()).collect();
                [v[3], v[7], v[11]]
            })
            .collect();
        let est = truth.iter().enumerate().map(|(i, p)| [p[0] * 0.9 - i as f64 * 0.05, p[1], p[2] * 0.97]).collect();
        (truth, est)
    }

    #[test]
    fn window_equals_the_labs_outside_the_caption() {
        let (truth, est) = paths();
        let img = draw(&truth, &est, &Style::default());
        let want = image::open(concat!(env!("CARGO_MANIFEST_DIR"), "/src/render/testdata/trajectory_lab.png"))
            .unwrap()
            .to_rgb8();
        assert_eq!(img.dimensions(), want.dimensions());
        let mut dots = 0;
        for (x, y, p) in img.enumerate_pixels() {
            if (20..=60).contains(&y) && x >= 10 {
                continue; // caption band: Hershey text there, 5x7 bitmap here
            }
            assert_eq!(p.0, want.get_pixel(x, y).0, "pixel ({x}, {y})");
            dots += (p.0 != [0, 0, 0]) as usize;
        }
        assert!(dots > 300, "{dots} coloured pixels: both paths drawn");
        // The caption: same band, same text width class, white pixels only inside it.
        let white =
            |im: &RgbImage| im.enumerate_pixels().filter(|(_, y, p)| (20..=60).contains(y) && p.0 == [255; 3]).count();
        assert!(white(&img) > 150 && white(&want) > 150);
    }
}
