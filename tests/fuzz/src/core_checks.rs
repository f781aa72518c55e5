//! The oracles of the core's fuzz targets. One file, included by the
//! cargo-fuzz targets (`tests/fuzz/fuzz_targets/*.rs`, nightly) and by the stable
//! replay test `core/tests/fuzz_regressions.rs`, so a committed finding is
//! replayed through exactly the checks that found it. A check panics only on
//! a bug: a panic inside the core, a wrong answer, or a refusal without a
//! message. docs/fuzzing.md says what each target compares.
#![allow(dead_code)]

use siftlab_core::dataset::{self, Dataset};
use siftlab_core::image::{bgr_to_gray, MAX_PIXELS};
use siftlab_core::matching::{self, knn_match, DMatch, Strategy};
use siftlab_core::sift::{detect_and_compute, Features, KeyPoint, SiftParams};
use siftlab_core::{Error, GrayImage};

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

/// Any failure must say something a student can act on.
fn check_message(e: &Error) {
    let m = e.to_string();
    assert!(m.len() >= 20, "an error without a useful message: {m:?}");
    if let Error::TooLarge { width, height, limit } = e {
        assert_eq!(*limit, MAX_PIXELS);
        assert!(*width as u64 * *height as u64 > MAX_PIXELS, "TooLarge for {width}x{height}");
    }
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

/// The largest image the SIFT target runs on: SIFT doubles it first, so
/// 4096 pixels keep one execution around a millisecond or two; the thin
/// shapes (up to 512 x 8) still reach the border and octave-count cases.
pub const SIFT_MAX_PIXELS: usize = 4096;
pub const SIFT_MAX_SIDE: usize = 512;

/// Image bytes (or raw pixels) → decode → SIFT, checking the output is
/// well formed.
pub fn sift(data: &[u8]) {
    let Some((&mode, rest)) = data.split_first() else { return };
    let img = if mode & 1 == 0 {
        match GrayImage::decode(rest) {
            Ok(img) => img,
            Err(e) => return check_message(&e),
        }
    } else {
        if rest.len() < 2 {
            return;
        }
        let w = 1 + (rest[0] as usize | ((mode as usize >> 4) << 8)) % SIFT_MAX_SIDE;
        let h = 1 + rest[1] as usize % SIFT_MAX_SIDE;
        if w * h > SIFT_MAX_PIXELS {
            return;
        }
        let px = &rest[2..];
        let data = (0..w * h).map(|i| if px.is_empty() { 0 } else { px[i % px.len()] }).collect();
        GrayImage::new(w, h, data).unwrap()
    };
    let (w, h) = (img.width(), img.height());
    if w * h > SIFT_MAX_PIXELS || w.max(h) > SIFT_MAX_SIDE {
        return;
    }
    let params = SiftParams { opencv_lanes: if mode & 2 == 0 { 8 } else { 16 }, ..SiftParams::default() };
    // On the calling thread: thread start-up would dominate at this size,
    // and LeakSanitizer reports glibc's per-thread TLS destructor record
    // (32 bytes from __cxa_thread_atexit_impl) as a leak in every spawned
    // thread. The threaded stages compute the same bits (golden tests).
    let f = siftlab_core::internals::serial(|| detect_and_compute(&img, &params));
    check_features(&f, w, h, &params);
}

fn check_features(f: &Features, w: usize, h: usize, p: &SiftParams) {
    assert_eq!(f.keypoints.len(), f.descriptors.len());
    // No cap on the count: retainBest keeps every keypoint tied with the
    // nfeatures-th response (a repeated texture gives thousands).
    let _ = p;
    for k in &f.keypoints {
        assert!(k.x.is_finite() && k.y.is_finite(), "{k:?}");
        assert!(k.x >= -1.0 && k.y >= -1.0 && k.x <= w as f32 && k.y <= h as f32, "{k:?} outside {w}x{h}");
        assert!(k.size.is_finite() && k.size > 0.0, "{k:?}");
        assert!(k.angle.is_finite() && (0.0..=360.0).contains(&k.angle), "{k:?}");
        assert!(k.response.is_finite(), "{k:?}");
    }
}

/// A reader of fuzz bytes that never fails (zeros past the end).
pub struct Bytes<'a>(pub &'a [u8]);

impl Bytes<'_> {
    pub fn u8(&mut self) -> u8 {
        let (&v, rest) = self.0.split_first().unwrap_or((&0, &[]));
        self.0 = rest;
        v
    }
    pub fn u64(&mut self) -> u64 {
        (0..8).fold(0, |a, _| (a << 8) | self.u8() as u64)
    }
    pub fn f64(&mut self) -> f64 {
        // Half the time one of the values that break comparisons.
        match self.u8() % 12 {
            0 => f64::NAN,
            1 => f64::INFINITY,
            2 => f64::NEG_INFINITY,
            3 => -0.0,
            4 => -(self.u8() as f64),
            5 => f64::MAX,
            6 => f64::MIN_POSITIVE / 4.0,
            7 => self.u8() as f64 / 255.0,
            8 => self.u8() as f64 * 16.0,
            _ => f64::from_bits(self.u64()),
        }
    }
}

/// `sqrt` of the exact integer sum of squared differences: the L2 distance
/// as OpenCV's `BFMatcher` returns it (every sum < 2^24, so exact in f32).
fn naive_distance(a: &[u8; 128], b: &[u8; 128]) -> f32 {
    let s: u32 = a.iter().zip(b).map(|(&x, &y)| (x as i32 - y as i32).pow(2) as u32).sum();
    (s as f32).sqrt()
}

/// Every train row of `q`, by distance then train index (knnMatch's order).
fn naive_ranked(qi: usize, q: &[u8; 128], train: &[[u8; 128]]) -> Vec<DMatch> {
    let mut v: Vec<DMatch> = train
        .iter()
        .enumerate()
        .map(|(j, t)| DMatch { query_idx: qi, train_idx: j, distance: naive_distance(q, t) })
        .collect();
    v.sort_by(|a, b| a.distance.partial_cmp(&b.distance).unwrap().then(a.train_idx.cmp(&b.train_idx)));
    v
}

/// The lab's three functions written out plainly, on the ranked row.
fn naive_select(s: &Strategy, ranked: &[DMatch]) -> Option<Vec<DMatch>> {
    Some(match *s {
        Strategy::Dt(t) => ranked.iter().copied().filter(|m| (m.distance as f64) < t).collect(),
        Strategy::Nn(t) => {
            ranked.iter().take(1).copied().filter(|m| t.is_none_or(|t| (m.distance as f64) < t)).collect()
        }
        Strategy::Nndr(t) => {
            if ranked.len() < 2 {
                return None;
            }
            if (ranked[0].distance as f64) < t * ranked[1].distance as f64 {
                vec![ranked[0]]
            } else {
                vec![]
            }
        }
    })
}

fn descriptors(r: &mut Bytes, n: usize) -> Vec<[u8; 128]> {
    // Few distinct values (ties) or free bytes.
    let palette = r.u8();
    (0..n)
        .map(|_| {
            let mut d = [0u8; 128];
            let kind = r.u8();
            for v in d.iter_mut() {
                *v = match kind % 3 {
                    0 => [0, 1, 255][r.u8() as usize % 3],
                    1 => palette,
                    _ => r.u8(),
                };
            }
            d
        })
        .collect()
}

fn features(descriptors: Vec<[u8; 128]>) -> Features {
    let keypoints = (0..descriptors.len())
        .map(|i| KeyPoint { x: i as f32, y: 0.5, size: 2.0, angle: 0.0, response: 1.0, octave: 0 })
        .collect();
    Features { keypoints, descriptors }
}

/// The matcher and the three strategies on arbitrary descriptors, counts
/// and thresholds, against the naive version above.
pub fn matching(data: &[u8]) {
    let mut r = Bytes(data);
    let (np, nc) = (r.u8() as usize % 24, r.u8() as usize % 40);
    let algo = ["dt", "nn", "nndr", "knn", "", "NN"][r.u8() as usize % 6];
    let threshold = if r.u8() % 4 == 0 { None } else { Some(r.f64()) };
    let direct = r.u8();
    let k = r.u8() as usize % 6;
    let feature = r.u8() as usize % 48;
    let prev = features(descriptors(&mut r, np));
    let cur = features(descriptors(&mut r, nc));

    // The CLI's and the app's way in: the checked constructor. Whatever it
    // accepts is finite and >= 0 (nndr <= 1); refusals are explained.
    let parsed = Strategy::parse(algo, threshold);
    match &parsed {
        Ok(s) => {
            if let Some(t) = s.threshold() {
                assert!(t.is_finite() && t >= 0.0, "{s:?} accepted");
                assert!(!matches!(s, Strategy::Nndr(_)) || t <= 1.0, "{s:?} accepted");
            }
        }
        Err(e) => check_message(e),
    }
    // The variants are public: the rules must also hold (and not panic) on
    // thresholds the parser refuses.
    let t = threshold.unwrap_or(f64::NAN);
    let s = match (parsed, direct & 3) {
        (Ok(s), 0) => s,
        (_, 1) => Strategy::Dt(t),
        (_, 2) => Strategy::Nn(threshold),
        (_, 3) => Strategy::Nndr(t),
        (Err(_), _) | (_, 4..) => Strategy::Nn(None),
    };

    let all = matching::match_all(&s, &prev, &cur);
    let mut want_all = Vec::new();
    for (i, q) in prev.descriptors.iter().enumerate() {
        want_all.push(naive_select(&s, &naive_ranked(i, q, &cur.descriptors)));
    }
    match &all {
        Ok(rows) => {
            assert_eq!(rows.len(), np);
            for (i, (got, want)) in rows.iter().zip(&want_all).enumerate() {
                assert_eq!(Some(got), want.as_ref(), "{s:?} query {i}");
            }
        }
        Err(e) => {
            check_message(e);
            assert!(want_all.iter().any(Option::is_none), "{s:?}: match_all refused: {e}");
        }
    }
    match matching::match_feature(&s, &prev, &cur, feature) {
        Ok(got) => {
            assert!(feature < np);
            assert_eq!(Some(got.clone()), want_all[feature], "{s:?} feature {feature}");
            let info = matching::matching_info(&prev.keypoints, &cur.keypoints, &got);
            let _ = info.to_string();
        }
        Err(e) => {
            check_message(&e);
            assert!(feature >= np || want_all[feature].is_none(), "{s:?}: refused: {e}");
        }
    }
    if let Ok(ex) = matching::explain(&s, &prev, &cur, feature) {
        let _ = ex.rule();
    }
    // knnMatch for any k.
    let knn = knn_match(&prev.descriptors, &cur.descriptors, k);
    assert_eq!(knn.len(), np);
    for (i, row) in knn.iter().enumerate() {
        let mut want = naive_ranked(i, &prev.descriptors[i], &cur.descriptors);
        want.truncate(k);
        assert_eq!(row, &want, "knn k={k} query {i}");
    }
}

/// `math.dist` of two points, scaled like CPython's `vector_norm` so that
/// neither huge nor tiny coordinates overflow: within 1 ulp of the truth.
fn naive_dist(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    let d: Vec<f64> = (0..3).map(|k| (a[k] - b[k]).abs()).collect();
    let m = d.iter().copied().fold(0.0, f64::max);
    if m == 0.0 || !m.is_finite() {
        return m;
    }
    d.iter().map(|x| (x / m) * (x / m)).sum::<f64>().sqrt() * m
}

/// The poses parser, the ground-truth scale and the frame checks; one input
/// in 16 also lays out a dataset folder for `Dataset::open`.
pub fn poses(data: &[u8]) {
    let Some((&mode, rest)) = data.split_first() else { return };
    let text = String::from_utf8_lossy(rest);
    let parsed = dataset::parse_poses(&text);
    let lines: Vec<&str> = text.lines().filter(|l| !l.trim().is_empty()).collect();
    let poses = match parsed {
        Ok(p) => {
            assert_eq!(p.len(), lines.len());
            for (row, line) in p.iter().zip(&lines) {
                let want: Vec<f64> = line.split_whitespace().map(|f| f.parse().unwrap()).collect();
                assert_eq!(row.as_slice(), want.as_slice());
                assert!(row.iter().all(|v| v.is_finite()));
            }
            for i in 0..=p.len() {
                match dataset::gt_scale(&p, i) {
                    Ok(s) => {
                        assert!(i >= 1 && i < p.len());
                        let (a, b) = (dataset::position(&p[i - 1]), dataset::position(&p[i]));
                        let want = naive_dist(&a, &b);
                        // A finite scale for finite positions, as math.dist gives.
                        assert!(s.is_finite() || !want.is_finite(), "scale {s} for {a:?} -> {b:?}");
                        if want.is_finite() && want > 0.0 {
                            assert!((s - want).abs() <= want * 1e-15, "scale {s} vs {want} for {a:?} -> {b:?}");
                        }
                    }
                    Err(e) => {
                        check_message(&e);
                        assert!(i == 0 || i >= p.len());
                    }
                }
            }
            p
        }
        Err(e) => {
            check_message(&e);
            assert!(e.to_string().contains("poses/00.txt"), "{e}");
            Vec::new()
        }
    };
    // A dataset as the app assembles one from a picked folder.
    let frame_count = (mode >> 4) as usize;
    let ds = Dataset::from_parts("picked".into(), frame_count, Some(poses.clone()));
    // The same bytes as a calib.txt: a camera that validates, or a message.
    match dataset::parse_calib(&text, "calib.txt") {
        Ok(cam) => assert!(cam.validate().is_ok() && text.contains("P0:")),
        Err(e) => check_message(&e),
    }
    for n in 0..=18 {
        match ds.check_frames(n) {
            Ok(()) => assert!(n <= frame_count && n <= poses.len()),
            Err(e) => {
                check_message(&e);
                assert!(n > frame_count || n > poses.len());
            }
        }
    }
    // The file-system part is slow (a folder per run): one mode value in 16.
    if mode & 15 == 15 {
        open_layout(mode, rest);
    }
}

/// A dataset folder laid out from fuzz bits (the lab's layout or KITTI's,
/// frames folder, poses file, calib.txt, frames that are images or not),
/// opened and read.
fn open_layout(mode: u8, rest: &[u8]) {
    let bits = rest.first().copied().unwrap_or(0) ^ mode;
    let dir = std::env::temp_dir().join(format!("siftlab-fuzz-ds-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let layout = if bits & 8 != 0 { dataset::Layout::Kitti } else { dataset::Layout::Lab };
    let seq = dataset::SequenceLayout::new(layout, "00").unwrap();
    if bits & 1 != 0 {
        std::fs::create_dir_all(dir.join(seq.frame_dir())).unwrap();
        for i in 0..(bits >> 5) as usize {
            let bytes: &[u8] = if bits & 2 != 0 { TINY_PNG } else { &rest[..rest.len().min(64)] };
            std::fs::write(dir.join(seq.frame_path(i)), bytes).unwrap();
        }
        if bits & 16 != 0 {
            std::fs::write(dir.join(seq.calib_file()), rest).unwrap();
        }
    }
    if bits & 4 != 0 {
        std::fs::create_dir_all(dir.join("poses")).unwrap();
        std::fs::write(dir.join(dataset::POSES_FILE), rest).unwrap();
    }
    match Dataset::open(&dir) {
        Ok(ds) => {
            assert_eq!(ds.sequence(), &seq);
            for i in 0..ds.frame_count() {
                if let Err(e) = ds.load_frame(i) {
                    check_message(&e);
                }
            }
            let _ = ds.check_frames(ds.frame_count() + 1).unwrap_err();
        }
        Err(e) => check_message(&e),
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// A 2x2 8-bit gray PNG.
const TINY_PNG: &[u8] = &[
    0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a, 0x00, 0x00, 0x00, 0x0d, 0x49, 0x48, 0x44, 0x52, 0x00, 0x00, 0x00,
    0x02, 0x00, 0x00, 0x00, 0x02, 0x08, 0x00, 0x00, 0x00, 0x00, 0x57, 0xdd, 0x52, 0xf8, 0x00, 0x00, 0x00, 0x0c, 0x49,
    0x44, 0x41, 0x54, 0x78, 0x9c, 0x63, 0x60, 0x00, 0x02, 0x16, 0x00, 0x00, 0x0a, 0x00, 0x05, 0xe2, 0xa9, 0xcd, 0xb7,
    0x00, 0x00, 0x00, 0x00, 0x49, 0x45, 0x4e, 0x44, 0xae, 0x42, 0x60, 0x82,
];
