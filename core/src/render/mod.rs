//! The images the lab's commands draw, reproduced with the `image` crate only:
//! `cv2.drawMatchesKnn(..., flags=2)` for `view_feature` ([`matches`](mod@matches)), the
//! `view_info` composite ([`info`]) and the `view_trajectory` window
//! ([`trajectory`]); and `match_all`'s whole-frame pictures, side by side
//! ([`whole_frame`](mod@whole_frame)) or as flow over the current frame
//! ([`flow`](mod@flow)). Everything here is plain Rust and runs on wasm too.
//!
//! The primitives in [`draw`] follow OpenCV 4.8's `imgproc/drawing.cpp`
//! integer arithmetic, with the line type each lab call uses:
//! `drawMatchesKnn` draws its keypoint circles (radius 3) and match lines
//! with **LINE_AA** and 4 fractional bits (`draw_shift_bits`), colours from
//! `cv::theRNG()`; the lab's `view_info` circles (radius 10, thickness 2) and
//! the trajectory dots (radius 1) are `cv2.circle`'s default **LINE_8**.
//! `view_feature` and `view_info` PNGs equal OpenCV's pixel for pixel
//! (`testdata/compare_visual.py`). Only text differs: a built-in 5x7 bitmap
//! font ([`font`]) replaces OpenCV's Hershey strokes.

// Every unsafe operation sits in its own `unsafe` block with the reason it
// holds, also inside `unsafe fn`s (render has none today).

// The marker's picture of a wrong value (PrairieLearn's images).
pub mod difference;
pub(crate) mod draw;
pub(crate) mod flow;
pub(crate) mod font;
pub mod info;
pub mod matches;
// The colours, dashes and markers of every figure for people (the CLI's
// plots and matches.png, the app): one palette, public for the app.
pub mod palette;
// The VO figures (axes, SVG, raster) the CLI and the app share: an API of its own.
pub mod plot;
pub mod trajectory;
pub(crate) mod whole_frame;

use crate::error::{Error, Result};
pub use flow::draw as flow_frame;
pub use image::RgbImage;
pub use info::draw as view_info;
pub use matches::draw_feature as view_feature;
pub use trajectory::{coordinates_text, draw as trajectory_window, Style as TrajectoryStyle};
pub use whole_frame::draw as whole_frame;

/// Encodes an RGB image as PNG bytes (what `cv2.imwrite` would write, minus
/// the BGR order OpenCV keeps in memory). Works on wasm: no file system.
pub fn encode_png(img: &RgbImage) -> Result<Vec<u8>> {
    let mut out = Vec::new();
    let enc = image::codecs::png::PngEncoder::new(&mut out);
    image::ImageEncoder::write_image(enc, img.as_raw(), img.width(), img.height(), image::ExtendedColorType::Rgb8)
        .map_err(|e| Error::Decode(format!("cannot encode the PNG: {e}")))?;
    Ok(out)
}

/// Encodes an RGB image as JPEG bytes at `quality` (1 to 100): the
/// marker's pictures of photographs, a tenth of their PNG's size.
pub fn encode_jpeg(img: &RgbImage, quality: u8) -> Result<Vec<u8>> {
    let mut out = Vec::new();
    let enc = image::codecs::jpeg::JpegEncoder::new_with_quality(&mut out, quality.clamp(1, 100));
    image::ImageEncoder::write_image(enc, img.as_raw(), img.width(), img.height(), image::ExtendedColorType::Rgb8)
        .map_err(|e| Error::Decode(format!("cannot encode the JPEG: {e}")))?;
    Ok(out)
}

/// A gray frame as the RGB image `cv2.cvtColor(gray, COLOR_GRAY2BGR)` gives.
pub fn gray_to_rgb(img: &crate::image::GrayImage) -> RgbImage {
    let (w, h) = (img.width() as u32, img.height() as u32);
    let mut raw = Vec::with_capacity(img.data().len() * 3);
    for &v in img.data() {
        raw.extend_from_slice(&[v, v, v]);
    }
    // The buffer has exactly w*h*3 bytes, so from_raw cannot fail; fall back
    // to a black image rather than panic.
    RgbImage::from_raw(w, h, raw).unwrap_or_else(|| RgbImage::new(w, h))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn png_round_trip_keeps_pixels() {
        let mut img = RgbImage::new(7, 3);
        img.put_pixel(6, 2, image::Rgb([1, 2, 3]));
        let bytes = encode_png(&img).unwrap();
        assert_eq!(&bytes[1..4], b"PNG");
        let back = image::load_from_memory(&bytes).unwrap().to_rgb8();
        assert_eq!(back.dimensions(), (7, 3));
        assert_eq!(back.get_pixel(6, 2).0, [1, 2, 3]);
        assert_eq!(back.get_pixel(0, 0).0, [0, 0, 0]);
    }

    #[test]
    fn gray_to_rgb_replicates_channels() {
        let g = crate::image::GrayImage::new(2, 1, vec![10, 200]).unwrap();
        let c = gray_to_rgb(&g);
        assert_eq!(c.dimensions(), (2, 1));
        assert_eq!(c.get_pixel(1, 0).0, [200, 200, 200]);
    }
}
