//! The host's knnMatch answers against OpenCV 4.8's.

use crate::{frame_file, repo_root};
use siftlab_core::json::{self, Json};
use siftlab_core::sift::{detect_and_compute, SiftParams};
use siftlab_core::GrayImage;
use siftlab_mark::{knn_answer, unbase64, Pair};
use std::fs;
use std::path::PathBuf;

/// The host's answers to knnMatch requests equal OpenCV 4.8's `knnMatch`
/// (tests/fixtures/mark/knn_*.json: chosen queries at k = 2, 5 and others,
/// with ties, and whole rows at k = nt), by value and by reference.
#[test]
fn knn_answers_equal_opencv() {
    let dir = repo_root().join("tests/fixtures/mark");
    let mut goldens: Vec<PathBuf> = fs::read_dir(&dir)
        .unwrap()
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            p.file_name().and_then(|n| n.to_str()).is_some_and(|n| n.starts_with("knn_") && n.ends_with(".json"))
        })
        .collect();
    goldens.sort();
    assert!(!goldens.is_empty(), "no knn_*.json golden in {}", dir.display());
    for path in goldens {
        let g = json::parse(&fs::read_to_string(&path).unwrap()).unwrap();
        let frames: Vec<i64> =
            g.get("frames").and_then(Json::as_arr).unwrap().iter().map(|f| f.as_i64().unwrap()).collect();
        let lanes = g.get("lanes").and_then(Json::as_i64).unwrap() as usize;
        let params = SiftParams { opencv_lanes: lanes, ..SiftParams::default() };
        let sift = |i: i64| {
            let bytes = fs::read(frame_file(&repo_root().join("www/demo/MyKITTI"), i as usize)).unwrap();
            detect_and_compute(&GrayImage::decode(&bytes).unwrap(), &params)
        };
        let pair = Pair { id: frames[1] as u32, prev: sift(frames[0]), cur: sift(frames[1]) };
        assert_eq!(pair.prev.descriptors.len() as i64, g.get("nq").and_then(Json::as_i64).unwrap());
        assert_eq!(pair.cur.descriptors.len() as i64, g.get("nt").and_then(Json::as_i64).unwrap());
        let id = pair.id;
        let pairs = [pair];
        let b64 = |row: &[u8; 128]| siftlab_mark::base64(row);
        // One query by value against the pair's train side.
        let answer = |q: usize, k: i64| -> Vec<(i64, f32)> {
            let req = format!(
                r#"{{"op":"knn","q":"{}","qid":null,"nq":1,"t":null,"tid":"{id}/2","nt":{},"k":{k}}}"#,
                b64(&pairs[0].prev.descriptors[q]),
                pairs[0].cur.descriptors.len()
            );
            rows(&knn_answer(&req, &pairs)).remove(0)
        };
        let want = |v: &Json| -> Vec<(i64, f32)> {
            v.as_arr()
                .unwrap()
                .iter()
                .map(|m| (m.as_arr().unwrap()[0].as_i64().unwrap(), m.as_arr().unwrap()[1].as_f32().unwrap()))
                .collect()
        };
        let queries = g.get("queries").and_then(Json::as_arr).unwrap();
        for c in queries {
            let q = c.get("q").and_then(Json::as_i64).unwrap() as usize;
            let why = c.get("why").and_then(Json::as_str).unwrap_or("");
            assert_eq!(answer(q, 2), want(c.get("k2").unwrap()), "{}: query {q} ({why}) k=2", path.display());
            assert_eq!(answer(q, 5), want(c.get("k5").unwrap()), "{}: query {q} ({why}) k=5", path.display());
            if let Some(kx) = c.get("kx") {
                let k = kx.get("k").and_then(Json::as_i64).unwrap();
                assert_eq!(
                    answer(q, k),
                    want(kx.get("matches").unwrap()),
                    "{}: query {q} ({why}) k={k}",
                    path.display()
                );
            }
        }
        for c in g.get("full").and_then(Json::as_arr).unwrap() {
            let q = c.get("q").and_then(Json::as_i64).unwrap() as usize;
            let k = c.get("k").and_then(Json::as_i64).unwrap();
            assert_eq!(answer(q, k), want(c.get("matches").unwrap()), "{}: query {q} k={k}", path.display());
        }
        // By reference: every query at k = 2 in one request, the same rows.
        let all = rows(&knn_answer(&format!(r#"{{"op":"knn","qid":"{id}/1","tid":"{id}/2","k":2}}"#), &pairs));
        for c in queries {
            let q = c.get("q").and_then(Json::as_i64).unwrap() as usize;
            assert_eq!(all[q], want(c.get("k2").unwrap()), "{}: query {q} by reference", path.display());
        }
    }
}

/// A knn answer as (trainIdx, distance) rows, from the compact or the list form.
fn rows(answer: &str) -> Vec<Vec<(i64, f32)>> {
    let v = json::parse(answer).unwrap_or_else(|e| panic!("{e}: {answer}"));
    if let Some(m) = v.get("matches") {
        return m
            .as_arr()
            .unwrap()
            .iter()
            .map(|r| {
                r.as_arr()
                    .unwrap()
                    .iter()
                    .map(|m| (m.as_arr().unwrap()[0].as_i64().unwrap(), m.as_arr().unwrap()[1].as_f32().unwrap()))
                    .collect()
            })
            .collect();
    }
    let kk = v.get("kk").and_then(Json::as_i64).unwrap_or_else(|| panic!("{answer}")) as usize;
    let words = |k: &str| unbase64(v.get(k).and_then(Json::as_str).unwrap()).unwrap();
    let (t, d) = (words("t"), words("d"));
    let t: Vec<i64> = t.chunks(4).map(|b| i32::from_le_bytes(b.try_into().unwrap()) as i64).collect();
    let d: Vec<f32> = d.chunks(4).map(|b| f32::from_le_bytes(b.try_into().unwrap())).collect();
    t.chunks(kk).zip(d.chunks(kk)).map(|(t, d)| t.iter().copied().zip(d.iter().copied()).collect()).collect()
}
