//! `BFMatcher().knnMatch(query, train, k)` (spec §16).

use super::distance::distance_row;

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
    if k == 0 {
        return Vec::new();
    }
    let mut best: Vec<DMatch> = Vec::with_capacity(k + 1);
    for (j, &d) in row.iter().enumerate() {
        if best.len() == k && !(d < best[k - 1].distance) {
            continue;
        }
        let pos = best.partition_point(|m| m.distance <= d);
        best.insert(pos, DMatch { query_idx, train_idx: j, distance: d });
        best.truncate(k);
    }
    best
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
    let mut row = Vec::new();
    query
        .iter()
        .enumerate()
        .map(|(i, q)| {
            distance_row(q, train, &mut row);
            knn_row(i, &row, k)
        })
        .collect()
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
