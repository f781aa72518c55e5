//! The `matching` target: the matcher and the lab's three strategies against
//! a naive version on fuzzed descriptors, counts and thresholds.

use super::check_message;
use siftlab_core::matching::{self, knn_match, DMatch, Strategy};
use siftlab_core::sift::{Features, KeyPoint};

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
