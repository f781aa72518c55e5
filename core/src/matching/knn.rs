//! `BFMatcher().knnMatch(query, train, k)` (docs/fidelity.md §SIFT-16).

use super::distance::{distance_rows, TrainSet};

/// One `cv2.DMatch` (imgIdx is always 0 and omitted).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DMatch {
    pub query_idx: usize,
    pub train_idx: usize,
    pub distance: f32,
}

/// The `k` nearest train descriptors of one query, ascending by distance,
/// ties by lower train index, `min(k, n_train)` of them: OpenCV inserts a
/// candidate only if strictly closer than the current k-th and places it
/// after equal distances, which is a stable selection by (distance, index).
pub fn knn_row(query_idx: usize, row: &[f32], k: usize) -> Vec<DMatch> {
    let k = k.min(row.len());
    let m = |(train_idx, distance): (usize, f32)| DMatch { query_idx, train_idx, distance };
    match k {
        0 => Vec::new(),
        // nn and nndr (and knnMatch k = 2) only need the best two: a scan
        // with two registers instead of the general insertion below.
        1 => vec![m(best2(row)[0])],
        2 => best2(row).into_iter().map(m).collect(),
        _ => {
            let mut best: Vec<DMatch> = Vec::with_capacity(k + 1);
            for (j, &d) in row.iter().enumerate() {
                // Not better than the k-th best: a tie keeps the earlier
                // train index (distances are square roots of integers,
                // never NaN).
                if best.len() == k && d >= best[k - 1].distance {
                    continue;
                }
                let pos = best.partition_point(|m| m.distance <= d);
                best.insert(pos, DMatch { query_idx, train_idx: j, distance: d });
                best.truncate(k);
            }
            best
        }
    }
}

/// The two nearest (train index, distance) of a row of >= 2 finite
/// distances, by the same rule as [`knn_row`]: a candidate replaces a slot
/// only if strictly closer, so the lower index wins ties. The +inf start
/// values are beaten by the first two entries (distances are at most
/// sqrt(128 * 255^2)), which is how a not-yet-full list accepts anything.
/// With a single entry the second slot stays (usize::MAX, inf): callers
/// keep only the first.
#[inline]
fn best2(row: &[f32]) -> [(usize, f32); 2] {
    let (mut j1, mut d1, mut j2, mut d2) = (usize::MAX, f32::INFINITY, usize::MAX, f32::INFINITY);
    const CHUNK: usize = 16;
    for (c, chunk) in row.chunks(CHUNK).enumerate() {
        // After the first few rows almost no distance beats the current
        // second best: one branch-free (vectorised) test per chunk skips those
        // chunks, and the exact scan below runs only on the rest.
        if !chunk.iter().fold(false, |any, &d| any | (d < d2)) {
            continue;
        }
        for (j, &d) in (c * CHUNK..).zip(chunk) {
            if d < d2 {
                if d < d1 {
                    (j2, d2) = (j1, d1);
                    (j1, d1) = (j, d);
                } else {
                    (j2, d2) = (j, d);
                }
            }
        }
    }
    [(j1, d1), (j2, d2)]
}

/// Every train descriptor of one query, in the order knnMatch with
/// `k = n_train` returns them.
pub fn ranked_row(query_idx: usize, row: &[f32]) -> Vec<DMatch> {
    let mut all: Vec<DMatch> =
        row.iter().enumerate().map(|(j, &d)| DMatch { query_idx, train_idx: j, distance: d }).collect();
    // Stable sort: equal distances keep the lower train index first.
    all.sort_by(|a, b| a.distance.total_cmp(&b.distance));
    all
}

/// `knnMatch(query, train, k)` for every query row.
pub fn knn_match(query: &[[u8; 128]], train: &[[u8; 128]], k: usize) -> Vec<Vec<DMatch>> {
    // Blocks of 32 queries through the multi-query kernel: 32 rows of
    // distances stay in cache until selected.
    const BLOCK: usize = 32;
    let nt = train.len();
    let train = TrainSet::new(train);
    let mut rows = vec![0.0f32; BLOCK * nt];
    let mut out = Vec::with_capacity(query.len());
    for (b, qs) in query.chunks(BLOCK).enumerate() {
        distance_rows(qs, &train, &mut rows);
        for i in 0..qs.len() {
            out.push(knn_row(b * BLOCK + i, &rows[i * nt..(i + 1) * nt], k));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ties_keep_lower_index_and_k_is_capped() {
        let row = [5.0, 1.0, 5.0, 0.5, 1.0];
        let m = knn_row(7, &row, 3);
        let ids: Vec<usize> = m.iter().map(|m| m.train_idx).collect();
        assert_eq!(ids, vec![3, 1, 4]);
        assert!(m.iter().all(|m| m.query_idx == 7));
        assert_eq!(knn_row(0, &[2.0, 1.0], 5).len(), 2);
        assert!(knn_row(0, &[], 2).is_empty());
        let r = ranked_row(0, &row);
        assert_eq!(r.iter().map(|m| m.train_idx).collect::<Vec<_>>(), vec![3, 1, 4, 0, 2]);
    }

    /// The general insertion of `knn_row`, for any k (the reference for the
    /// k <= 2 fast path).
    fn knn_row_by_insertion(row: &[f32], k: usize) -> Vec<(usize, f32)> {
        let mut all: Vec<(usize, f32)> = row.iter().copied().enumerate().collect();
        all.sort_by(|a, b| a.1.total_cmp(&b.1));
        all.truncate(k);
        all
    }

    #[test]
    fn best_two_scan_equals_stable_sort_with_ties() {
        let mut s = 12345u32;
        for n in 0..40 {
            for _ in 0..50 {
                // Few distinct values so ties (and ties at the front) are common.
                let row: Vec<f32> = (0..n)
                    .map(|_| {
                        s = s.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
                        ((s >> 28) % 5) as f32
                    })
                    .collect();
                for k in 1..=3 {
                    let got: Vec<(usize, f32)> =
                        knn_row(3, &row, k).iter().map(|m| (m.train_idx, m.distance)).collect();
                    assert_eq!(got, knn_row_by_insertion(&row, k), "row {row:?} k {k}");
                }
            }
        }
    }

    #[test]
    fn duplicate_rows_match_in_index_order() {
        let mut train = vec![[9u8; 128]; 300];
        for &j in &[5, 100, 250] {
            train[j] = [1u8; 128];
        }
        let m = knn_match(&[[1u8; 128]], &train, 3);
        assert_eq!(m[0].iter().map(|m| m.train_idx).collect::<Vec<_>>(), vec![5, 100, 250]);
        assert_eq!(m[0][0].distance, 0.0);
    }
}
