//! What the tests share: OpenCV's SIFT goldens of the bundled frames as the
//! app's frames, the `get_info` goldens as draws, and a lab loaded with them.

use leptos::prelude::*;
use siftlab_app::model::frame::FrameData;
use siftlab_app::model::lab::{Lab, Source};
use siftlab_app::protocol::sift::SiftResult;
use siftlab_core::sift::{Features, KeyPoint};
use std::sync::Arc;

/// The frames the goldens cover: 0–5 and the lab manual's pairs.
fn golden_bytes(id: usize) -> &'static [u8] {
    match id {
        0 => include_bytes!("../../../tests/fixtures/golden-avx2/ipp/000000.sift"),
        1 => include_bytes!("../../../tests/fixtures/golden-avx2/ipp/000001.sift"),
        2 => include_bytes!("../../../tests/fixtures/golden-avx2/ipp/000002.sift"),
        3 => include_bytes!("../../../tests/fixtures/golden-avx2/ipp/000003.sift"),
        4 => include_bytes!("../../../tests/fixtures/golden-avx2/ipp/000004.sift"),
        5 => include_bytes!("../../../tests/fixtures/golden-avx2/ipp/000005.sift"),
        119 => include_bytes!("../../../tests/fixtures/golden-avx2/ipp/000119.sift"),
        120 => include_bytes!("../../../tests/fixtures/golden-avx2/ipp/000120.sift"),
        149 => include_bytes!("../../../tests/fixtures/golden-avx2/ipp/000149.sift"),
        150 => include_bytes!("../../../tests/fixtures/golden-avx2/ipp/000150.sift"),
        _ => panic!("no golden for frame {id}"),
    }
}
const GET_INFO: &str = include_str!("../../../tests/fixtures/golden-avx2/get_info.jsonl");

/// The frame ids of the bundled demo (`www/demo/MyKITTI`).
fn demo_ids() -> Vec<u32> {
    (0..=150).collect()
}

/// Reads a `SIFTGLD1` file (format in tests/fixtures/README.md).
pub(crate) fn golden(i: usize) -> (usize, usize, Features) {
    let b = golden_bytes(i);
    assert_eq!(&b[..8], b"SIFTGLD1");
    let u = |o: usize| u32::from_le_bytes(b[o..o + 4].try_into().unwrap());
    let (w, h, n) = (u(8) as usize, u(12) as usize, u(16) as usize);
    let f = |o: usize| f32::from_le_bytes(b[o..o + 4].try_into().unwrap());
    let mut keypoints = Vec::with_capacity(n);
    for k in 0..n {
        let o = 20 + 24 * k;
        keypoints.push(KeyPoint {
            x: f(o),
            y: f(o + 4),
            size: f(o + 8),
            angle: f(o + 12),
            response: f(o + 16),
            octave: i32::from_le_bytes(b[o + 20..o + 24].try_into().unwrap()),
        });
    }
    let d0 = 20 + 24 * n;
    let descriptors = (0..n).map(|k| b[d0 + 128 * k..d0 + 128 * (k + 1)].try_into().unwrap()).collect();
    (w, h, Features { keypoints, descriptors })
}

pub(crate) fn frame(i: usize) -> Arc<FrameData> {
    let (w, h, features) = golden(i);
    Arc::new(FrameData {
        label: format!("gray/00/image_0/{i:06}.png"),
        sift: SiftResult {
            width: w,
            height: h,
            // The frame view only needs some pixels; a gradient is enough here.
            gray: (0..w * h).map(|p| (p % 251) as u8).collect(),
            features,
            decode_ms: 0.0,
            sift_ms: 0.0,
            engine: String::new(),
            memory: 0,
        },
        bytes: Arc::new(Vec::new()),
        lanes: 8,
    })
}

/// One `get_info` golden: (FRAME_ID, feature, algo, threshold text, ret value).
pub(crate) struct Draw {
    pub(crate) frame: usize,
    pub(crate) feature: usize,
    pub(crate) algo: String,
    pub(crate) threshold: String,
    pub(crate) ret: String,
}

fn field<'a>(line: &'a str, key: &str) -> &'a str {
    let start = line.find(&format!("\"{key}\": ")).unwrap() + key.len() + 4;
    let rest = &line[start..];
    let end = rest.find([',', '}']).unwrap();
    rest[..end].trim().trim_matches('"')
}

pub(crate) fn draws() -> Vec<Draw> {
    GET_INFO
        .lines()
        .filter(|l| !l.trim().is_empty())
        .map(|l| {
            let ret_start = l.find("ret value: ").unwrap() + "ret value: ".len();
            let ret_len = l[ret_start..].find("\\n").unwrap();
            let t = field(l, "threshold");
            Draw {
                frame: field(l, "dataset_frame").parse().unwrap(),
                feature: field(l, "feature").parse().unwrap(),
                algo: field(l, "algo").to_string(),
                // The lab's argparse reads -t as a float; the golden stores its repr.
                threshold: if t == "null" { String::new() } else { t.to_string() },
                ret: l[ret_start..ret_start + ret_len].to_string(),
            }
        })
        .collect()
}

pub(crate) fn loaded_lab(cur: usize) -> Lab {
    let lab = Lab::new();
    lab.prev.set(Some(frame(cur - 1)));
    lab.cur.set(Some(frame(cur)));
    lab.source.set(Source::Demo(demo_ids()));
    lab.frame_id.set(cur as u32);
    lab
}
