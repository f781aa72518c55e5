//! The pixel limit in the browser (docs/fuzzing.md, "Limits"): an image
//! over `MAX_PIXELS` is refused from its header, before any pixel buffer
//! exists, and (opt-in, slow) the largest accepted image is decoded and run
//! through SIFT while the WebAssembly memory it reaches is reported.
//!
//! `cargo test --release --target wasm32-unknown-unknown -p siftlab-core --no-default-features --test wasm_limits`
//! runs the refusal; with `SIFTLAB_MEASURE_MAX=1` in the environment at
//! build time it also runs the 16-megapixel measurement (about a minute).

#![cfg(target_arch = "wasm32")]

use siftlab_core::image::MAX_PIXELS;
use siftlab_core::sift::{detect_and_compute, SiftParams};
use siftlab_core::{Error, GrayImage};
use wasm_bindgen_test::*;

wasm_bindgen_test_configure!(run_in_browser);

/// WebAssembly linear memory in MiB. It only grows, so after a run it is
/// that run's peak (plus what the test harness held before).
fn memory_mib() -> f64 {
    core::arch::wasm32::memory_size(0) as f64 * 65536.0 / 1048576.0
}

fn png_header(w: u32, h: u32, colour: u8) -> Vec<u8> {
    let mut ihdr = Vec::new();
    ihdr.extend_from_slice(&w.to_be_bytes());
    ihdr.extend_from_slice(&h.to_be_bytes());
    ihdr.extend_from_slice(&[8, colour, 0, 0, 0]);
    let mut out = vec![0x89, b'P', b'N', b'G', 0x0d, 0x0a, 0x1a, 0x0a];
    out.extend_from_slice(&13u32.to_be_bytes());
    out.extend_from_slice(b"IHDR");
    out.extend_from_slice(&ihdr);
    let mut h = crc32fast::Hasher::new();
    h.update(b"IHDR");
    h.update(&ihdr);
    out.extend_from_slice(&h.finalize().to_be_bytes());
    // An empty IDAT and IEND: the png crate reads up to the first IDAT
    // before it reports the dimensions (a bare header is "truncated").
    for kind in [b"IDAT", b"IEND"] {
        out.extend_from_slice(&0u32.to_be_bytes());
        out.extend_from_slice(kind);
        out.extend_from_slice(&crc32fast::hash(kind).to_be_bytes());
    }
    out
}

#[wasm_bindgen_test]
fn over_the_limit_is_refused_from_the_header() {
    let before = memory_mib();
    // 4-gigapixel and just-over headers, both gray (fast path) and RGB.
    for (w, h, colour) in
        [(65535, 65535, 0), (4001, 4000, 0), (16_000_001, 1, 0), (4001, 4000, 2), (1 << 30, 1 << 30, 6)]
    {
        let e = GrayImage::decode(&png_header(w, h, colour)).unwrap_err();
        assert!(matches!(e, Error::TooLarge { .. }), "{w}x{h}: {e}");
        assert!(e.to_string().contains("above the limit of 16000000 pixels"), "{e}");
    }
    // Refused without growing memory by anything near an image.
    assert!(memory_mib() - before < 8.0, "{before} -> {} MiB", memory_mib());
}

#[wasm_bindgen_test]
fn the_largest_image_fits() {
    if option_env!("SIFTLAB_MEASURE_MAX").is_none() {
        return;
    }
    use image::codecs::png::{CompressionType, FilterType, PngEncoder};
    use image::ImageEncoder;
    let side = (MAX_PIXELS as f64).sqrt() as u32;
    assert_eq!(side as u64 * side as u64, MAX_PIXELS);
    // The texture of tests/fuzz/run.sh's measurement image: pseudo-random
    // rows, each a shifted copy of one line (many extrema, many ties).
    let mut s = 5u32;
    let line: Vec<u8> = (0..side + 4096)
        .map(|_| {
            s ^= s << 13;
            s ^= s >> 17;
            s ^= s << 5;
            (s >> 24) as u8
        })
        .collect();
    let mut px = Vec::with_capacity((side * side) as usize);
    for y in 0..side as usize {
        let off = (y * 37) % 4096;
        px.extend_from_slice(&line[off..off + side as usize]);
    }
    let mut png = Vec::new();
    PngEncoder::new_with_quality(&mut png, CompressionType::Fast, FilterType::NoFilter)
        .write_image(&px, side, side, image::ExtendedColorType::L8)
        .unwrap();
    drop(px);
    let before = memory_mib();
    let img = GrayImage::decode(&png).unwrap();
    drop(png);
    let after_decode = memory_mib();
    let f = detect_and_compute(&img, &SiftParams::default());
    let after = memory_mib();
    web_sys_log(&format!(
        "MAX_PIXELS {side}x{side}: {} keypoints; wasm memory {before:.0} MiB before decode, {after_decode:.0} after, {after:.0} MiB after SIFT",
        f.keypoints.len()
    ));
}

fn web_sys_log(s: &str) {
    wasm_bindgen_test::console_log!("{s}");
}
