//! The matcher in the browser on OpenCV's own features: knn against the
//! brute-force definition, and every `get_info` golden of frames 0 and 1.

use crate::{golden_format, performance_now, GET_INFO, IPP0, IPP1};
use siftlab_core::json;
use siftlab_core::matching::{knn_match, match_feature, matching_info, Strategy};
use siftlab_core::sift::Features;
use wasm_bindgen_test::*;

/// OpenCV's own features (default-wheel golden) as `Features`.
fn golden_features(golden: &[u8]) -> Features {
    let g = golden_format::parse_golden(golden, "ipp golden");
    Features { keypoints: g.keypoints, descriptors: g.descriptors }
}

#[wasm_bindgen_test]
fn matching_in_the_browser_equals_the_lab() {
    // The matcher alone, in wasm: OpenCV's own features of frames 0 and 1 (default
    // wheel, which the get_info goldens used); our SIFT is checked above.
    let (prev, cur) = (golden_features(IPP0), golden_features(IPP1));

    // knn k=2 against the brute-force definition (docs/fidelity.md §SIFT-16): exact integer sums,
    // ascending, ties to the lower train index.
    let t0 = performance_now();
    let knn = knn_match(&prev.descriptors, &cur.descriptors, 2);
    let knn_ms = performance_now() - t0;
    assert_eq!(knn.len(), prev.descriptors.len());
    for (q, row) in knn.iter().enumerate().step_by(97) {
        let mut all: Vec<(u32, usize)> = cur
            .descriptors
            .iter()
            .enumerate()
            .map(|(t, d)| {
                let s: u32 =
                    prev.descriptors[q].iter().zip(d).map(|(&a, &b)| (a as i32 - b as i32).pow(2) as u32).sum();
                (s, t)
            })
            .collect();
        all.sort();
        assert_eq!(row.len(), 2.min(all.len()));
        for (m, &(s, t)) in row.iter().zip(&all) {
            assert_eq!((m.query_idx, m.train_idx), (q, t), "query {q}");
            assert_eq!(m.distance.to_bits(), (s as f32).sqrt().to_bits(), "query {q} distance");
        }
    }

    // Every get_info golden for this pair (FRAME_ID 1 = frames 0 and 1).
    let (mut checked, mut failures) = (0, Vec::new());
    for line in GET_INFO.lines().filter(|l| !l.trim().is_empty()) {
        let rec = json::parse(line).expect("golden line is JSON");
        if rec.get("dataset_frame").and_then(|v| v.as_i64()) != Some(1) {
            continue;
        }
        let algo = rec.get("algo").and_then(|v| v.as_str()).expect("algo");
        let threshold = rec.get("threshold").and_then(|v| v.as_f64());
        let feature = rec.get("feature").and_then(|v| v.as_i64()).expect("feature") as usize;
        let stdout = rec.get("stdout").and_then(|v| v.as_str()).expect("stdout");
        let want = stdout.lines().find_map(|l| l.strip_prefix("ret value: ")).expect("golden has a ret value line");
        let s = Strategy::parse(algo, threshold).expect("golden strategy is valid");
        let m = match_feature(&s, &prev, &cur, feature).expect("golden feature is in range");
        let got = matching_info(&prev.keypoints, &cur.keypoints, &m).to_string();
        if got != want {
            let at = want.bytes().zip(got.bytes()).position(|(a, b)| a != b).unwrap_or(want.len().min(got.len()));
            let clip = |t: &str| t.get(at.saturating_sub(40)..(at + 40).min(t.len())).unwrap_or("").to_owned();
            failures.push(format!(
                "get_info -a {algo} -t {threshold:?} 1 {feature}: opencv ...{}... ours ...{}...",
                clip(want),
                clip(&got)
            ));
        }
        checked += 1;
    }
    console_log!(
        "wasm matching: {}/{checked} get_info goldens (FRAME_ID 1) identical; knn k=2 {}x{} {knn_ms:.1} ms; WASM_KNN2_MS={knn_ms:.1}",
        checked - failures.len(),
        prev.descriptors.len(),
        cur.descriptors.len()
    );
    assert!(checked > 0, "no get_info goldens for FRAME_ID 1");
    assert!(failures.is_empty(), "{} of {checked} differ:\n{}", failures.len(), failures.join("\n"));
}
