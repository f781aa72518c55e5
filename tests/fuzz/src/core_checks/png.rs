//! The `png_diff` target: siftlab's decoder against the `image` crate's, on
//! inputs as found, with their checksums fixed, or built as valid PNGs.

use super::check_message;
use siftlab_core::image::{bgr_to_gray, MAX_PIXELS};
use siftlab_core::GrayImage;

const SIGNATURE: [u8; 8] = [0x89, b'P', b'N', b'G', 0x0d, 0x0a, 0x1a, 0x0a];

fn png_chunk(out: &mut Vec<u8>, kind: &[u8; 4], data: &[u8]) {
    out.extend_from_slice(&(data.len() as u32).to_be_bytes());
    out.extend_from_slice(kind);
    out.extend_from_slice(data);
    let mut h = crc32fast::Hasher::new();
    h.update(kind);
    h.update(data);
    out.extend_from_slice(&h.finalize().to_be_bytes());
}

/// Rewrites every chunk checksum of a PNG-looking input, so mutations reach
/// the header and data checks instead of stopping at the CRC.
fn fix_crcs(bytes: &[u8]) -> Vec<u8> {
    let mut out = bytes.to_vec();
    if !out.starts_with(&SIGNATURE) {
        return out;
    }
    let mut at = 8;
    while at + 12 <= out.len() {
        let len = u32::from_be_bytes([out[at], out[at + 1], out[at + 2], out[at + 3]]) as usize;
        let end = match (at + 8).checked_add(len) {
            Some(e) if e + 4 <= out.len() => e,
            _ => break,
        };
        let crc = crc32fast::hash(&out[at + 4..end]);
        out[end..end + 4].copy_from_slice(&crc.to_be_bytes());
        at = end + 4;
    }
    out
}

/// A PNG built from fuzzed fields with a valid zlib stream: the rows'
/// filter bytes and samples are the input's, so the unfiltering and every
/// colour type and depth are reached, not only the chunk parser.
fn build_png(d: &[u8]) -> Vec<u8> {
    let b = |i: usize| d.get(i).copied().unwrap_or(0);
    let w = 1 + b(0) as u32 % 40;
    let h = 1 + b(1) as u32 % 40;
    // (bit depth, colour type); 8-bit gray (the lab's frames) most often.
    const KINDS: [(u8, u8); 12] =
        [(8, 0), (8, 0), (8, 0), (8, 0), (16, 0), (1, 0), (2, 0), (4, 0), (8, 2), (8, 4), (8, 6), (16, 2)];
    let (depth, colour) = KINDS[b(2) as usize % KINDS.len()];
    let flags = b(3);
    let interlace = u8::from(flags & 0x80 != 0 && flags & 0x40 != 0);
    let channels = match colour {
        0 => 1,
        2 => 3,
        4 => 2,
        _ => 4,
    };
    let row_bytes = (w as usize * channels * depth as usize).div_ceil(8);
    let body = &d[d.len().min(5)..];
    let mut raw = Vec::with_capacity((row_bytes + 1) * h as usize);
    let mut k = 0usize;
    let mut next = || {
        let v = if body.is_empty() { 0 } else { body[k % body.len()] };
        k += 1;
        v
    };
    for _ in 0..(row_bytes + 1) * h as usize {
        raw.push(next());
    }
    // Valid filter bytes unless flag 0x01 keeps the fuzzed ones (0..=255).
    if flags & 0x01 == 0 && interlace == 0 {
        for y in 0..h as usize {
            raw[y * (row_bytes + 1)] %= 5;
        }
    }
    // Flag 0x02: too little data; 0x04: too much.
    if flags & 0x02 != 0 {
        raw.truncate(raw.len() - 1 - b(4) as usize % raw.len());
    }
    if flags & 0x04 != 0 {
        raw.extend(std::iter::repeat_n(b(4), 1 + b(4) as usize % 7));
    }
    let z = fdeflate::compress_to_vec(&raw);
    let mut out = SIGNATURE.to_vec();
    let mut ihdr = Vec::new();
    ihdr.extend_from_slice(&w.to_be_bytes());
    ihdr.extend_from_slice(&h.to_be_bytes());
    ihdr.extend_from_slice(&[depth, colour, 0, 0, interlace]);
    png_chunk(&mut out, b"IHDR", &ihdr);
    if flags & 0x08 != 0 {
        png_chunk(&mut out, b"tEXt", b"Comment\0fuzz");
    }
    // The zlib stream over 1 to 4 IDAT chunks, possibly empty ones.
    let parts = 1 + (b(4) as usize >> 4) % 4;
    let step = z.len().div_ceil(parts).max(1);
    for c in z.chunks(step) {
        png_chunk(&mut out, b"IDAT", c);
    }
    if z.is_empty() {
        png_chunk(&mut out, b"IDAT", &[]);
    }
    if flags & 0x10 == 0 {
        png_chunk(&mut out, b"IEND", &[]);
    }
    if flags & 0x20 != 0 {
        out.extend_from_slice(b"trailing bytes");
    }
    out
}

/// The picture `cv2.imread(path, 0)` gives, as siftlab documents it
/// (`GrayImage::decode`), computed here from the `image` crate's decoding
/// on its own: 8-bit gray as is, 16-bit samples by their high byte, alpha
/// dropped, colour through BGR2GRAY's fixed point. `None` when the `image`
/// crate refuses the bytes.
fn reference_gray(bytes: &[u8]) -> Option<(usize, usize, Vec<u8>)> {
    use image::DynamicImage as D;
    let img = image::load_from_memory(bytes).ok()?;
    let (w, h) = (img.width() as usize, img.height() as usize);
    let hi = |v: u16| (v >> 8) as u8;
    let px: Vec<u8> = match &img {
        D::ImageLuma8(g) => g.as_raw().clone(),
        D::ImageLuma16(g) => g.as_raw().iter().map(|&v| hi(v)).collect(),
        D::ImageLumaA8(g) => g.as_raw().chunks_exact(2).map(|p| p[0]).collect(),
        D::ImageLumaA16(g) => g.as_raw().chunks_exact(2).map(|p| hi(p[0])).collect(),
        D::ImageRgb8(g) => g.as_raw().chunks_exact(3).map(|p| bgr_to_gray(p[2], p[1], p[0])).collect(),
        D::ImageRgba8(g) => g.as_raw().chunks_exact(4).map(|p| bgr_to_gray(p[2], p[1], p[0])).collect(),
        D::ImageRgb16(g) => g.as_raw().chunks_exact(3).map(|p| bgr_to_gray(hi(p[2]), hi(p[1]), hi(p[0]))).collect(),
        D::ImageRgba16(g) => g.as_raw().chunks_exact(4).map(|p| bgr_to_gray(hi(p[2]), hi(p[1]), hi(p[0]))).collect(),
        // Float images come from neither PNG nor JPEG.
        _ => return None,
    };
    Some((w, h, px))
}

/// Differential: siftlab's decoder (the gray-PNG fast path, else the
/// `image` crate with the pixel limit) against the `image` crate alone.
pub fn png_diff(data: &[u8]) {
    let Some((&mode, rest)) = data.split_first() else { return };
    let bytes = match mode % 4 {
        0 => rest.to_vec(),
        1 => fix_crcs(rest),
        _ => build_png(rest),
    };
    compare_decoders(&bytes);
}

pub fn compare_decoders(bytes: &[u8]) {
    match GrayImage::decode(bytes) {
        Ok(img) => {
            assert!((img.width() * img.height()) as u64 <= MAX_PIXELS);
            assert_eq!(img.data().len(), img.width() * img.height());
            // siftlab gave a picture: the image crate's must be the same. If
            // the image crate refuses (a stricter reference, e.g. no IEND)
            // there is no second picture to differ from; what siftlab
            // accepted is at least self-consistent (checked above).
            if let Some((w, h, px)) = reference_gray(bytes) {
                assert_eq!((img.width(), img.height()), (w, h), "the two decoders disagree on the size");
                if let Some(i) = img.data().iter().zip(&px).position(|(a, b)| a != b) {
                    panic!(
                        "siftlab and the image crate decode different pixels: at ({}, {}) {} vs {} in a {w}x{h} image",
                        i % w,
                        i / w,
                        img.data()[i],
                        px[i]
                    );
                }
            }
        }
        Err(e) => check_message(&e),
    }
}
