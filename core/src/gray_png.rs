//! The lab's frames — 8-bit gray, non-interlaced PNGs — decoded directly:
//! the zlib stream inflated by `fdeflate` (the inflater the `png` crate uses)
//! straight into one buffer, and the rows unfiltered here. KITTI's encoder
//! filters most rows with Paeth, whose predictor needs the pixel just
//! decoded to its left: one row is one chain of dependent steps. Two Paeth
//! rows are undone side by side (row r at column x with row r + 1 at x − 1,
//! whose inputs row r has by then), so the two chains overlap. Every other
//! PNG goes through the `image` crate ([`decode_gray8`] returns `None`).

use crate::error::{Error, Result};

const SIGNATURE: [u8; 8] = [0x89, b'P', b'N', b'G', 0x0d, 0x0a, 0x1a, 0x0a];

/// The pixels of an 8-bit gray, non-interlaced PNG as (width, height,
/// row-major bytes); `None` for any other PNG (or not a PNG), which the
/// caller decodes the general way. A broken file of this kind is an error
/// saying what is wrong.
pub fn decode_gray8(bytes: &[u8], max_pixels: u64) -> Option<Result<(usize, usize, Vec<u8>)>> {
    let rest = bytes.strip_prefix(&SIGNATURE)?;
    let mut chunks = Chunks { rest };
    let (kind, ihdr) = chunks.next()?.ok()?;
    if kind != *b"IHDR" || ihdr.len() != 13 {
        return None;
    }
    let w = u32::from_be_bytes([ihdr[0], ihdr[1], ihdr[2], ihdr[3]]);
    let h = u32::from_be_bytes([ihdr[4], ihdr[5], ihdr[6], ihdr[7]]);
    // Bit depth 8, colour type 0 (gray), deflate, adaptive filtering, no
    // interlacing: anything else is the general decoder's.
    if ihdr[8..13] != [8, 0, 0, 0, 0] || w == 0 || h == 0 {
        return None;
    }
    if w as u64 * h as u64 > max_pixels {
        return Some(Err(Error::TooLarge { width: w, height: h, limit: max_pixels }));
    }
    Some(inflate_and_unfilter(chunks, w as usize, h as usize))
}

/// The (width, height) of a PNG's IHDR, if `bytes` start like a PNG with
/// one; read without checking anything else, for the pixel limit.
pub(crate) fn ihdr_size(bytes: &[u8]) -> Option<(u32, u32)> {
    let rest = bytes.strip_prefix(&SIGNATURE)?;
    if rest.len() < 16 || &rest[4..8] != b"IHDR" {
        return None;
    }
    let w = u32::from_be_bytes([rest[8], rest[9], rest[10], rest[11]]);
    let h = u32::from_be_bytes([rest[12], rest[13], rest[14], rest[15]]);
    Some((w, h))
}

fn corrupt(what: &str) -> Error {
    Error::Decode(format!("the image is corrupt or truncated ({what}); re-export or re-download it"))
}

/// The chunks after the signature: (type, data), the CRC checked.
struct Chunks<'a> {
    rest: &'a [u8],
}

impl<'a> Iterator for Chunks<'a> {
    type Item = Result<([u8; 4], &'a [u8])>;

    fn next(&mut self) -> Option<Self::Item> {
        if self.rest.is_empty() {
            return None;
        }
        let Some((head, body)) = self.rest.split_first_chunk::<8>() else {
            self.rest = &[];
            return Some(Err(corrupt("a chunk header is cut off")));
        };
        let len = u32::from_be_bytes([head[0], head[1], head[2], head[3]]) as usize;
        let kind = [head[4], head[5], head[6], head[7]];
        if body.len() < len + 4 {
            self.rest = &[];
            return Some(Err(corrupt("a chunk is cut off")));
        }
        let (data, after) = body.split_at(len);
        let crc = u32::from_be_bytes([after[0], after[1], after[2], after[3]]);
        self.rest = &after[4..];
        let mut hasher = crc32fast::Hasher::new();
        hasher.update(&kind);
        hasher.update(data);
        if hasher.finalize() != crc {
            self.rest = &[];
            return Some(Err(corrupt("a chunk's checksum does not match")));
        }
        Some(Ok((kind, data)))
    }
}

fn inflate_and_unfilter(chunks: Chunks, w: usize, h: usize) -> Result<(usize, usize, Vec<u8>)> {
    // The filtered rows, each a filter byte and w pixels.
    let stride = w + 1;
    let mut filtered = vec![0u8; stride * h];
    let mut idats = Vec::new();
    for chunk in chunks {
        let (kind, data) = chunk?;
        match &kind {
            b"IDAT" => idats.push(data),
            b"IEND" => break,
            _ => {}
        }
    }
    let mut inflater = fdeflate::Decompressor::new();
    let mut produced = 0;
    for (i, &data) in idats.iter().enumerate() {
        let last = i + 1 == idats.len();
        let mut input = data;
        while !inflater.is_done() && (last || !input.is_empty()) {
            let (used, made) = inflater
                .read(input, &mut filtered, produced, last)
                .map_err(|e| corrupt(&format!("its pixel data does not inflate: {e:?}")))?;
            input = &input[used..];
            produced += made;
            if used == 0 && made == 0 {
                // Stuck: the buffer (exactly the image) is full, or the
                // data stopped mid-stream.
                let what = if produced == filtered.len() {
                    "its pixel data is longer than the image"
                } else {
                    "its pixel data ends early"
                };
                return Err(corrupt(what));
            }
        }
    }
    if !inflater.is_done() || produced != filtered.len() {
        return Err(corrupt("its pixel data ends early"));
    }
    let mut pixels = vec![0u8; w * h];
    unfilter(&filtered, w, h, &mut pixels)?;
    Ok((w, h, pixels))
}

const NONE: u8 = 0;
const SUB: u8 = 1;
const UP: u8 = 2;
const AVERAGE: u8 = 3;
const PAETH: u8 = 4;

/// Undoes the row filters of `filtered` (h rows of a filter byte and w
/// pixels) into `out` (h rows of w pixels).
fn unfilter(filtered: &[u8], w: usize, h: usize, out: &mut [u8]) -> Result<()> {
    let stride = w + 1;
    let zeros = vec![0u8; w];
    let mut y = 0;
    while y < h {
        let (done, rest) = out.split_at_mut(y * w);
        let prev: &[u8] = if y == 0 { &zeros } else { &done[(y - 1) * w..] };
        let f0 = &filtered[y * stride..(y + 1) * stride];
        if f0[0] == PAETH && y + 1 < h && filtered[(y + 1) * stride] == PAETH {
            let f1 = &filtered[(y + 1) * stride + 1..(y + 2) * stride];
            let (row0, rest) = rest.split_at_mut(w);
            paeth_pair(prev, &f0[1..], row0, f1, &mut rest[..w]);
            y += 2;
            continue;
        }
        unfilter_row(f0[0], prev, &f0[1..], &mut rest[..w])?;
        y += 1;
    }
    Ok(())
}

/// The PNG Paeth predictor of left `a`, above `b`, above-left `c`, in the
/// branch-free form of stb_image (public domain): with t = 3c − a − b, the
/// spec's choice is max(a, b) when t ≤ min(a, b), min(a, b) when
/// t ≥ max(a, b), else c. Fewer steps depend on `a` (the pixel just
/// decoded) than in the spec's three distances, and no branch mispredicts
/// on camera noise; `paeth_is_the_spec_predictor` checks all 2^24 inputs.
#[inline(always)]
fn paeth(a: u8, b: u8, c: u8) -> u8 {
    let (a, b, c) = (a as i16, b as i16, c as i16);
    let t = 3 * c - (a + b);
    let (lo, hi) = (a.min(b), a.max(b));
    let not_hi = if hi <= t { lo } else { c };
    (if t <= lo { hi } else { not_hi }) as u8
}

fn unfilter_row(kind: u8, prev: &[u8], raw: &[u8], out: &mut [u8]) -> Result<()> {
    let w = out.len();
    let (prev, raw) = (&prev[..w], &raw[..w]);
    match kind {
        NONE => out.copy_from_slice(raw),
        SUB => {
            let mut a = 0u8;
            for (o, &r) in out.iter_mut().zip(raw) {
                a = r.wrapping_add(a);
                *o = a;
            }
        }
        UP => {
            for ((o, &r), &b) in out.iter_mut().zip(raw).zip(prev) {
                *o = r.wrapping_add(b);
            }
        }
        AVERAGE => {
            let mut a = 0u8;
            for ((o, &r), &b) in out.iter_mut().zip(raw).zip(prev) {
                a = r.wrapping_add(((a as u16 + b as u16) / 2) as u8);
                *o = a;
            }
        }
        PAETH => {
            let (mut a, mut c) = (0u8, 0u8);
            for ((o, &r), &b) in out.iter_mut().zip(raw).zip(prev) {
                a = r.wrapping_add(paeth(a, b, c));
                c = b;
                *o = a;
            }
        }
        _ => return Err(corrupt(&format!("unknown row filter {kind}"))),
    }
    Ok(())
}

/// Two consecutive Paeth rows: `out0` from `prev`, `out1` from `out0`, with
/// row 1 one column behind row 0 so both chains advance in each step.
fn paeth_pair(prev: &[u8], raw0: &[u8], out0: &mut [u8], raw1: &[u8], out1: &mut [u8]) {
    let w = out0.len();
    let (prev, raw0, raw1, out1) = (&prev[..w], &raw0[..w], &raw1[..w], &mut out1[..w]);
    // Column 0 of row 0: no left or above-left neighbour.
    let mut a0 = raw0[0].wrapping_add(paeth(0, prev[0], 0));
    out0[0] = a0;
    let (mut a1, mut c1) = (0u8, 0u8);
    for x in 1..w {
        // Row 0, column x.
        a0 = raw0[x].wrapping_add(paeth(a0, prev[x], prev[x - 1]));
        out0[x] = a0;
        // Row 1, column x − 1: above is row 0's x − 1, above-left its x − 2.
        let b1 = out0[x - 1];
        a1 = raw1[x - 1].wrapping_add(paeth(a1, b1, c1));
        out1[x - 1] = a1;
        c1 = b1;
    }
    out1[w - 1] = raw1[w - 1].wrapping_add(paeth(a1, out0[w - 1], c1));
}

#[cfg(test)]
mod tests {
    use super::*;
    use image::codecs::png::{CompressionType, FilterType, PngEncoder};
    use image::ImageEncoder;

    fn encode(w: u32, h: u32, px: &[u8], filter: FilterType) -> Vec<u8> {
        let mut out = Vec::new();
        PngEncoder::new_with_quality(&mut out, CompressionType::Fast, filter)
            .write_image(px, w, h, image::ExtendedColorType::L8)
            .unwrap();
        out
    }

    /// Noise with runs and ramps, so every predictor branch is taken.
    fn pattern(w: usize, h: usize, seed: u32) -> Vec<u8> {
        let mut s = seed.wrapping_mul(2654435761).max(1);
        (0..w * h)
            .map(|i| {
                s ^= s << 13;
                s ^= s >> 17;
                s ^= s << 5;
                match (i / w) % 3 {
                    0 => (s >> 24) as u8,
                    1 => ((i % w) * 7 + (s as usize >> 30)) as u8,
                    _ => ((i % w) / 5 * 40) as u8,
                }
            })
            .collect()
    }

    fn general(bytes: &[u8]) -> Vec<u8> {
        image::load_from_memory(bytes).unwrap().to_luma8().into_raw()
    }

    #[test]
    fn paeth_is_the_spec_predictor() {
        for a in 0..=255u8 {
            for b in 0..=255u8 {
                for c in 0..=255u8 {
                    let p = a as i16 + b as i16 - c as i16;
                    let (pa, pb, pc) = ((p - a as i16).abs(), (p - b as i16).abs(), (p - c as i16).abs());
                    let spec = if pa <= pb && pa <= pc {
                        a
                    } else if pb <= pc {
                        b
                    } else {
                        c
                    };
                    assert_eq!(paeth(a, b, c), spec, "a={a} b={b} c={c}");
                }
            }
        }
    }

    #[test]
    fn every_filter_and_size_matches_the_image_crate() {
        let filters = [
            FilterType::NoFilter,
            FilterType::Sub,
            FilterType::Up,
            FilterType::Avg,
            FilterType::Paeth,
            FilterType::Adaptive,
        ];
        for (w, h) in [(1, 1), (1, 7), (7, 1), (2, 2), (3, 5), (33, 17), (64, 9), (1241, 6)] {
            for (k, &filter) in filters.iter().enumerate() {
                let px = pattern(w, h, (w * 31 + h * 7 + k) as u32);
                let png = encode(w as u32, h as u32, &px, filter);
                let (gw, gh, got) = decode_gray8(&png, u64::MAX).expect("an 8-bit gray PNG").unwrap();
                assert_eq!((gw, gh), (w, h));
                assert_eq!(got, px, "{w}x{h} {filter:?}");
                assert_eq!(got, general(&png), "{w}x{h} {filter:?}");
            }
        }
    }

    #[test]
    fn the_fixture_frames_match_the_image_crate() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../www/demo/MyKITTI/gray/00/image_0");
        let mut n = 0;
        for entry in std::fs::read_dir(&dir).unwrap() {
            let bytes = std::fs::read(entry.unwrap().path()).unwrap();
            let (w, h, got) = decode_gray8(&bytes, u64::MAX).expect("KITTI frames are 8-bit gray").unwrap();
            assert_eq!((w, h), (1241, 376));
            assert_eq!(got, general(&bytes));
            n += 1;
        }
        assert!(n > 0);
    }

    #[test]
    fn other_pngs_and_non_pngs_go_the_general_way() {
        let rgb = {
            let mut out = Vec::new();
            PngEncoder::new(&mut out).write_image(&[1, 2, 3, 4, 5, 6], 2, 1, image::ExtendedColorType::Rgb8).unwrap();
            out
        };
        assert!(decode_gray8(&rgb, u64::MAX).is_none());
        assert!(decode_gray8(b"GIF89a", u64::MAX).is_none());
        assert!(decode_gray8(&[], u64::MAX).is_none());
    }

    #[test]
    fn broken_files_are_errors_not_panics() {
        let px = pattern(40, 30, 9);
        let png = encode(40, 30, &px, FilterType::Paeth);
        // Cut anywhere after the header, or one byte of the data flipped.
        for cut in [40, png.len() / 2, png.len() - 13, png.len() - 1] {
            if let Some(r) = decode_gray8(&png[..cut], u64::MAX) {
                assert!(r.is_err(), "cut at {cut}");
            }
        }
        let mut flipped = png.clone();
        let mid = png.len() / 2;
        flipped[mid] ^= 0x55;
        assert!(decode_gray8(&flipped, u64::MAX).unwrap().is_err());
        assert!(matches!(decode_gray8(&png, 100), Some(Err(Error::TooLarge { .. }))));
    }
}
