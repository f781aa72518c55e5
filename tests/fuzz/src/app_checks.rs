//! The oracles of the app's fuzz target: the URL state, the worker message
//! checks, the pasted-answer reader, the frame-range texts and the exercise
//! draws, all natively (the functions take plain Rust values). Included by
//! `tests/fuzz/fuzz_targets/app_state.rs` and by the stable replay test
//! `app/tests/fuzz_regressions.rs`.
#![allow(dead_code)]

use siftlab_app::model::urlstate::UrlState;
use siftlab_app::model::{exercise, frameset, pylit};
use siftlab_app::protocol::codec::{features_from_parts, points_field, u32_field, vec3_field, KP_FLOATS};
use siftlab_app::protocol::sift::SiftParts;

fn take<'a>(d: &mut &'a [u8], n: usize) -> &'a [u8] {
    let (a, b) = d.split_at(n.min(d.len()));
    *d = b;
    a
}

fn byte(d: &mut &[u8]) -> u8 {
    take(d, 1).first().copied().unwrap_or(0)
}

fn f64_of(d: &mut &[u8]) -> f64 {
    let b = take(d, 8);
    let mut a = [0u8; 8];
    a[..b.len()].copy_from_slice(b);
    f64::from_le_bytes(a)
}

pub fn app_state(data: &[u8]) {
    let Some((&mode, mut d)) = data.split_first() else { return };
    match mode % 5 {
        0 => url(d),
        1 => message(&mut d),
        2 => answer(d),
        3 => frames(&mut d),
        _ => exercises(&mut d),
    }
}

/// A query's decoded pairs (`&` and `=` split here as URLSearchParams
/// would after decoding) → state → pairs → state: a link the app writes
/// reads back as the same view.
fn url(d: &[u8]) {
    let q = String::from_utf8_lossy(d);
    let pairs: Vec<(String, String)> = q
        .split('&')
        .map(|kv| match kv.split_once('=') {
            Some((k, v)) => (k.to_string(), v.to_string()),
            None => (kv.to_string(), String::new()),
        })
        .collect();
    let st = UrlState::from_pairs(pairs);
    let again = UrlState::from_pairs(st.to_pairs());
    assert_eq!(again, st);
}

/// The checks of a `done` message and its small fields.
fn message(d: &mut &[u8]) {
    let v = f64_of(d);
    match u32_field("id", Some(v)) {
        Ok(n) => assert_eq!(n as f64, v),
        Err(m) => assert!(m.contains("id"), "{m}"),
    }
    let n = byte(d) as usize % 24;
    let flat: Vec<f32> = take(d, n * 4).chunks_exact(4).map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect();
    if let Ok(p) = points_field("points", &flat) {
        assert_eq!(p.len() * 2, flat.len());
    }
    let three: Vec<f64> = flat.iter().map(|&v| v as f64).collect();
    assert_eq!(vec3_field("position", &three).is_ok(), three.len() == 3);
    // Sizes: free u32s (65536 x 65536 is what wraps on wasm32), buffers small.
    let mut dim = || {
        let b = take(d, 4);
        let mut a = [0u8; 4];
        a[..b.len()].copy_from_slice(b);
        u32::from_le_bytes(a)
    };
    let (width, height) = (dim(), dim());
    let (gl, kl, ol, dl) = (byte(d) as usize, byte(d) as usize % 16, byte(d) as usize % 4, byte(d) as usize % 4);
    let desc = vec![9; dl * 128 + usize::from(dl == 3)];
    let features = match features_from_parts(&vec![1.5; kl], &vec![3; ol], &desc) {
        Ok(f) => {
            assert_eq!(f.keypoints.len(), ol);
            assert_eq!(f.descriptors.len(), ol);
            assert_eq!(kl, ol * KP_FLOATS);
            f
        }
        Err(m) => {
            assert!(!m.is_empty());
            Default::default()
        }
    };
    match (SiftParts { width, height, gray: vec![7; gl], features }).check() {
        // An empty gray buffer is a reply without the image, whatever the size.
        Ok(r) => {
            assert!(r.gray.is_empty() || r.gray.len() as u64 == width as u64 * height as u64);
            assert_eq!((r.width, r.height), (width as usize, height as usize));
        }
        Err(m) => assert!(!m.is_empty()),
    }
}

/// A pasted answer: read or refused with a position, never a panic (deep
/// nesting included).
fn answer(d: &[u8]) {
    let text = String::from_utf8_lossy(d);
    if let Err(m) = pylit::parse(&text) {
        assert!(!m.is_empty());
    }
}

/// The FRAME_ID box and the frame-set texts.
fn frames(d: &mut &[u8]) {
    let run = u32::from_le_bytes([byte(d), byte(d), byte(d), byte(d)]);
    let n = byte(d) as usize % 16;
    let ids: Vec<u32> =
        (0..n).map(|_| u32::from_le_bytes([byte(d), byte(d), byte(d), byte(d)]) >> (byte(d) % 33).min(31)).collect();
    let text = String::from_utf8_lossy(d);
    let _ = frameset::vo_range_label(&text, run);
    match frameset::vo_frame_count(&text, run) {
        Ok(count) => {
            let last: u32 = text.trim().parse().unwrap();
            assert!(last >= 1 && last < run && count == last + 1);
        }
        Err(m) => assert!(!m.is_empty()),
    }
    let _ = frameset::describe_ids(&ids);
    if let Ok(f) = text.trim().parse::<u32>() {
        let _ = frameset::vo_range_text(f);
        let _ = frameset::has_pair(&ids, f);
        let _ = frameset::missing_pair_message("the folder", &ids, f);
    }
    if let Some(f) = frameset::first_pair(&ids) {
        assert!(frameset::has_pair(&ids, f));
    }
    let r = frameset::run_from_zero(&ids);
    assert!((0..r).all(|i| ids.contains(&i)));
}

/// A link's exercise seed and question number, on any frame set.
fn exercises(d: &mut &[u8]) {
    let seed = f64_of(d).to_bits();
    let q = u32::from_le_bytes([byte(d), byte(d), byte(d), byte(d)]);
    let n = byte(d) as usize % 12;
    let frames: Vec<u32> =
        (0..n).map(|_| u32::from_le_bytes([byte(d), byte(d), byte(d), byte(d)]) >> (byte(d) % 32)).collect();
    if let Some(qn) = exercise::question(seed, q, &frames) {
        assert!(frames.contains(&qn.frame_id) && frames.contains(&(qn.frame_id - 1)));
        assert!((0.0..1.0).contains(&qn.feature_pos));
        for kps in [0, 1, 2, 1500] {
            assert!(qn.feature(kps) < kps.max(1));
            let _ = qn.command(kps);
        }
    }
}
