//! The gray image every stage works on, and decoding as `cv2.imread(path, 0)`.

use crate::error::{Error, Result};

/// Largest image siftlab accepts: 16 megapixels. SIFT doubles the image, so a
/// 16 MP input already needs ~64 MP float buffers per pyramid level.
pub const MAX_PIXELS: u64 = 16_000_000;

/// An 8-bit single-channel image, row-major, no padding.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct GrayImage {
    width: usize,
    height: usize,
    data: Vec<u8>,
}

impl GrayImage {
    /// Wraps `data` (row-major, `width * height` bytes).
    pub fn new(width: usize, height: usize, data: Vec<u8>) -> Result<Self> {
        if width.checked_mul(height) != Some(data.len()) {
            return Err(Error::InvalidArgument(format!(
                "image buffer has {} bytes but {width}x{height} needs {}",
                data.len(),
                width.saturating_mul(height)
            )));
        }
        Ok(GrayImage { width, height, data })
    }

    pub fn width(&self) -> usize {
        self.width
    }

    pub fn height(&self) -> usize {
        self.height
    }

    pub fn data(&self) -> &[u8] {
        &self.data
    }

    #[inline]
    pub fn get(&self, x: usize, y: usize) -> u8 {
        self.data[y * self.width + x]
    }

    /// Decodes PNG or JPEG bytes to gray as `cv2.imread(path, cv2.IMREAD_GRAYSCALE)`
    /// does for the lab's frames: 8-bit gray is taken as is, colour goes through
    /// OpenCV's fixed-point BGR2GRAY, 16-bit samples keep their high byte.
    pub fn decode(bytes: &[u8]) -> Result<Self> {
        // Every KITTI frame: 8-bit gray, decoded without the general path.
        if let Some(decoded) = crate::gray_png::decode_gray8(bytes, MAX_PIXELS) {
            let (width, height, data) = decoded?;
            return Ok(GrayImage { width, height, data });
        }
        let format = image::guess_format(bytes).map_err(|_| {
            Error::Decode(
                "not an image: the file is neither PNG nor JPEG (use a PNG or JPEG frame, \
                 e.g. gray/00/image_0/000000.png)"
                    .into(),
            )
        })?;
        if !matches!(format, image::ImageFormat::Png | image::ImageFormat::Jpeg) {
            return Err(Error::Decode(format!("unsupported image format {format:?}: use a PNG or JPEG frame")));
        }
        // The limit from the PNG header itself: for a huge header the png
        // crate fails first with its own "Memory limit exceeded", which
        // says nothing about the size (found by core/tests/wasm_limits.rs).
        if let Some((w, h)) = crate::gray_png::ihdr_size(bytes) {
            if w as u64 * h as u64 > MAX_PIXELS {
                return Err(Error::TooLarge { width: w, height: h, limit: MAX_PIXELS });
            }
        }
        let reader = image::ImageReader::with_format(std::io::Cursor::new(bytes), format);
        let mut decoder = reader;
        let mut limits = image::Limits::default();
        limits.max_alloc = Some(MAX_PIXELS * 8);
        decoder.limits(limits);
        let (w, h) = {
            let r = image::ImageReader::with_format(std::io::Cursor::new(bytes), format);
            r.into_dimensions().map_err(|e| Error::Decode(format!("cannot read the image header: {e}")))?
        };
        if w as u64 * h as u64 > MAX_PIXELS {
            return Err(Error::TooLarge { width: w, height: h, limit: MAX_PIXELS });
        }
        let img = decoder.decode().map_err(|e| {
            Error::Decode(format!("the image is corrupt or truncated ({e}); re-export or re-download it"))
        })?;
        // A gray PNG (every KITTI frame) is already the pixels: no copy.
        if let image::DynamicImage::ImageLuma8(g) = img {
            return Ok(GrayImage { width: w as usize, height: h as usize, data: g.into_raw() });
        }
        Ok(Self::from_dynamic(&img))
    }

    /// Converts any decoded image the way OpenCV's imread(..., 0) ends up:
    /// gray stays gray, colour uses [`bgr_to_gray`].
    pub fn from_dynamic(img: &image::DynamicImage) -> Self {
        use image::DynamicImage as D;
        let (w, h) = (img.width() as usize, img.height() as usize);
        let data = match img {
            D::ImageLuma8(g) => g.as_raw().clone(),
            D::ImageLumaA8(g) => g.as_raw().chunks_exact(2).map(|p| p[0]).collect(),
            D::ImageLuma16(g) => g.as_raw().iter().map(|&v| (v >> 8) as u8).collect(),
            D::ImageLumaA16(g) => g.as_raw().chunks_exact(2).map(|p| (p[0] >> 8) as u8).collect(),
            // 16-bit colour keeps the high byte too (OpenCV strips 16-bit
            // samples before converting); `to_rgb8` would round instead and
            // differ by one on about half the pixels (found by fuzzing,
            // tests/fuzz/regressions/png_diff).
            D::ImageRgb16(g) => g
                .as_raw()
                .chunks_exact(3)
                .map(|p| bgr_to_gray((p[2] >> 8) as u8, (p[1] >> 8) as u8, (p[0] >> 8) as u8))
                .collect(),
            D::ImageRgba16(g) => g
                .as_raw()
                .chunks_exact(4)
                .map(|p| bgr_to_gray((p[2] >> 8) as u8, (p[1] >> 8) as u8, (p[0] >> 8) as u8))
                .collect(),
            other => {
                let rgb = other.to_rgb8();
                rgb.as_raw().chunks_exact(3).map(|p| bgr_to_gray(p[2], p[1], p[0])).collect()
            }
        };
        GrayImage { width: w, height: h, data }
    }
}

/// OpenCV's `cvtColor(BGR2GRAY)` for 8-bit: the 0.114/0.587/0.299 weights in
/// 14-bit fixed point (1868, 9617, 4899), rounded by adding 2^13 before the shift.
#[inline]
pub fn bgr_to_gray(b: u8, g: u8, r: u8) -> u8 {
    ((b as u32 * 1868 + g as u32 * 9617 + r as u32 * 4899 + (1 << 13)) >> 14) as u8
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bgr2gray_matches_opencv_fixed_point() {
        // cv2.cvtColor(np.uint8([[[b,g,r]]]), cv2.COLOR_BGR2GRAY) values.
        assert_eq!(bgr_to_gray(255, 255, 255), 255);
        assert_eq!(bgr_to_gray(0, 0, 255), 76);
        assert_eq!(bgr_to_gray(0, 255, 0), 150);
        assert_eq!(bgr_to_gray(255, 0, 0), 29);
    }

    #[test]
    fn rejects_non_images() {
        let err = GrayImage::decode(b"hello, not a png").unwrap_err();
        assert!(err.to_string().contains("not an image"), "{err}");
    }

    #[test]
    fn rejects_truncated_png() {
        let img = image::GrayImage::from_fn(64, 64, |x, y| image::Luma([(x * 4 + y) as u8]));
        let mut buf = Vec::new();
        image::DynamicImage::ImageLuma8(img)
            .write_to(&mut std::io::Cursor::new(&mut buf), image::ImageFormat::Png)
            .unwrap();
        let ok = GrayImage::decode(&buf).unwrap();
        assert_eq!((ok.width(), ok.height(), ok.get(3, 2)), (64, 64, 14));
        let err = GrayImage::decode(&buf[..buf.len() / 2]).unwrap_err();
        assert!(err.to_string().contains("corrupt or truncated"), "{err}");
    }
}
