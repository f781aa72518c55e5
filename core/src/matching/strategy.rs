//! The lab's three matching strategies, with their argument checks.

use super::distance::{distance_row, distance_rows, TrainSet};
use super::kind::StrategyKind;
use super::knn::{knn_row, DMatch};
use crate::error::{Error, Result};
use crate::sift::Features;

/// A strategy and its threshold, compared in f64 like the lab's Python
/// (`m.distance < t` widens the f32 distance to a Python float).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Strategy {
    /// Distance thresholding: every train descriptor with distance < t.
    Dt(f64),
    /// Nearest neighbour, kept only if its distance < t when t is given.
    Nn(Option<f64>),
    /// Nearest-neighbour distance ratio: the nearest, kept if d1 < t·d2.
    Nndr(f64),
}

impl Strategy {
    /// Builds a strategy from the lab's `-a` / `-t` arguments, refusing what
    /// the lab's code would silently mis-handle.
    pub fn parse(algo: &str, threshold: Option<f64>) -> Result<Strategy> {
        if let Some(t) = threshold {
            if !t.is_finite() {
                return Err(Error::InvalidArgument(format!(
                    "threshold {t} is not a number: give a finite value (dt/nn: a distance such as 100, nndr: a ratio such as 0.8)"
                )));
            }
            if t < 0.0 {
                return Err(Error::InvalidArgument(format!(
                    "threshold {t} is negative: distances are >= 0, so nothing could match; use a value >= 0"
                )));
            }
        }
        match algo {
            "dt" => match threshold {
                Some(t) => Ok(Strategy::Dt(t)),
                None => Err(Error::InvalidArgument(
                    "dt needs a threshold: add -t, e.g. -t 100 (distances of SIFT descriptors are 0..~2900)".into(),
                )),
            },
            "nn" => Ok(Strategy::Nn(threshold)),
            "nndr" => match threshold {
                Some(t) if t <= 1.0 => Ok(Strategy::Nndr(t)),
                Some(t) => Err(Error::InvalidArgument(format!(
                    "nndr threshold {t} is outside [0, 1]: it is a ratio d1/d2 <= 1 (Lowe suggests 0.8)"
                ))),
                None => Err(Error::InvalidArgument(
                    "nndr needs a threshold: add -t, e.g. -t 0.8 (a ratio in [0, 1])".into(),
                )),
            },
            other => Err(Error::InvalidArgument(format!("unknown strategy '{other}': choose dt, nn or nndr"))),
        }
    }

    /// The lab's name for the strategy (`-a`).
    pub fn name(&self) -> &'static str {
        match self {
            Strategy::Dt(_) => "dt",
            Strategy::Nn(_) => "nn",
            Strategy::Nndr(_) => "nndr",
        }
    }

    pub fn threshold(&self) -> Option<f64> {
        match *self {
            Strategy::Dt(t) | Strategy::Nndr(t) => Some(t),
            Strategy::Nn(t) => t,
        }
    }

    /// How many neighbours the lab asks knnMatch for.
    pub fn k(&self, n_train: usize) -> usize {
        match self {
            Strategy::Dt(_) => n_train,
            Strategy::Nn(_) => 1,
            Strategy::Nndr(_) => 2,
        }
    }

    /// Applies the rule to one query's distance row.
    pub fn select(&self, query_idx: usize, row: &[f32]) -> Result<Vec<DMatch>> {
        Ok(match *self {
            Strategy::Dt(t) => {
                // Only the passing candidates need sorting; the sort is stable
                // and they are collected in train order, so ties keep the lower
                // train index first, as knnMatch(k = n_train) orders them.
                // Few distances pass, so a branch-free (vectorised) test of 16
                // at a time skips the chunks with none.
                const CHUNK: usize = 16;
                let mut m: Vec<DMatch> = Vec::new();
                for (c, chunk) in row.chunks(CHUNK).enumerate() {
                    if !chunk.iter().fold(false, |any, &d| any | ((d as f64) < t)) {
                        continue;
                    }
                    for (j, &d) in (c * CHUNK..).zip(chunk) {
                        if (d as f64) < t {
                            m.push(DMatch { query_idx, train_idx: j, distance: d });
                        }
                    }
                }
                m.sort_by(|a, b| a.distance.total_cmp(&b.distance));
                m
            }
            Strategy::Nn(t) => {
                let mut m = knn_row(query_idx, row, 1);
                if let Some(t) = t {
                    m.retain(|m| (m.distance as f64) < t);
                }
                m
            }
            Strategy::Nndr(t) => {
                let m = knn_row(query_idx, row, 2);
                if m.len() < 2 {
                    return Err(Error::InvalidArgument(format!(
                        "nndr needs at least 2 keypoints in the current frame, it has {}",
                        row.len()
                    )));
                }
                if (m[0].distance as f64) < t * m[1].distance as f64 {
                    vec![m[0]]
                } else {
                    Vec::new()
                }
            }
        })
    }
}

impl Strategy {
    /// The strategy's kind (its threshold dropped).
    pub fn kind(&self) -> StrategyKind {
        match self {
            Strategy::Dt(_) => StrategyKind::Dt,
            Strategy::Nn(_) => StrategyKind::Nn,
            Strategy::Nndr(_) => StrategyKind::Nndr,
        }
    }
}

/// Checks a feature id against the query frame's keypoints
/// ([`super::args::check_feature_id`], without a frame number).
pub fn check_feature(feature: usize, prev: &Features) -> Result<()> {
    super::args::check_feature_id(feature, prev.keypoints.len(), None)
}

/// The matches of one feature of the previous frame (the query) in the
/// current frame (the train), as the lab's strategy returns them.
pub fn match_feature(s: &Strategy, prev: &Features, cur: &Features, feature: usize) -> Result<Vec<DMatch>> {
    check_feature(feature, prev)?;
    let mut row = Vec::new();
    distance_row(&prev.descriptors[feature], &cur.descriptors, &mut row);
    s.select(feature, &row)
}

/// Queries per call of the multi-query distance kernel in [`match_all`]:
/// 32 rows of 1500 distances (192 KB) stay in L2 until selected.
const BLOCK: usize = 32;

/// A block's first query index and its matches, as a worker returns them.
#[cfg(not(target_arch = "wasm32"))]
type Block = (usize, Vec<Vec<DMatch>>);

/// The strategy applied to every query descriptor (what the lab's `dt`,
/// `nn` and `nndr` functions return), rows computed in parallel natively.
pub fn match_all(s: &Strategy, prev: &Features, cur: &Features) -> Result<Vec<Vec<DMatch>>> {
    let n = prev.descriptors.len();
    let nt = cur.descriptors.len();
    let train = TrainSet::new(&cur.descriptors);
    // The distances of a block of queries at once (the multi-query kernel),
    // then the rule on each row; `rows` is reused between blocks.
    let run = |range: std::ops::Range<usize>, rows: &mut Vec<f32>| -> Result<Vec<Vec<DMatch>>> {
        let mut out = Vec::with_capacity(range.len());
        let mut start = range.start;
        while start < range.end {
            let end = (start + BLOCK).min(range.end);
            rows.clear();
            rows.resize((end - start) * nt, 0.0);
            distance_rows(&prev.descriptors[start..end], &train, rows);
            for i in start..end {
                out.push(s.select(i, &rows[(i - start) * nt..(i - start + 1) * nt])?);
            }
            start = end;
        }
        Ok(out)
    };
    #[cfg(not(target_arch = "wasm32"))]
    {
        use std::sync::atomic::{AtomicUsize, Ordering};
        let threads = crate::par::cores();
        if threads > 1 && n >= 64 {
            // Small blocks of queries taken from a shared counter rather than
            // one fixed share per thread: on a busy machine a thread that is
            // descheduled for a while would otherwise hold up the whole result
            // while the others sit idle. A block of 32 queries x 1500 train
            // rows is a few hundred microseconds, so the counter is not
            // contended.
            let next = AtomicUsize::new(0);
            let worker = || -> Result<Vec<Block>> {
                let mut row = Vec::new();
                let mut done = Vec::new();
                loop {
                    let start = next.fetch_add(BLOCK, Ordering::Relaxed);
                    if start >= n {
                        return Ok(done);
                    }
                    done.push((start, run(start..(start + BLOCK).min(n), &mut row)?));
                }
            };
            let parts: Vec<Result<Vec<Block>>> = std::thread::scope(|sc| {
                let hs: Vec<_> = (1..threads).map(|_| sc.spawn(worker)).collect();
                // This thread takes blocks too instead of only waiting.
                let mut parts = vec![worker()];
                parts.extend(hs.into_iter().map(|h| {
                    h.join().unwrap_or_else(|_| Err(Error::InvalidArgument("matching thread failed".into())))
                }));
                parts
            });
            let mut blocks = Vec::with_capacity(n.div_ceil(BLOCK));
            for p in parts {
                blocks.extend(p?);
            }
            blocks.sort_unstable_by_key(|&(start, _)| start);
            return Ok(blocks.into_iter().flat_map(|(_, rows)| rows).collect());
        }
    }
    run(0..n, &mut Vec::new())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Features whose descriptors take few distinct values, so equal
    /// distances (ties broken by train index) are common.
    fn tie_heavy_features(n: usize, seed: u32) -> Features {
        let mut s = seed;
        let descriptors: Vec<[u8; 128]> = (0..n)
            .map(|_| {
                std::array::from_fn(|_| {
                    s = s.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
                    [0u8, 1, 255][(s >> 30) as usize % 3] & if (s >> 8).is_multiple_of(16) { 255 } else { 0 }
                })
            })
            .collect();
        let kp = crate::sift::KeyPoint { x: 0.0, y: 0.0, size: 1.0, angle: 0.0, response: 0.0, octave: 0 };
        Features { keypoints: vec![kp; n], descriptors }
    }

    #[test]
    fn match_all_equals_sorted_scalar_reference() {
        let (prev, cur) = (tie_heavy_features(150, 1), tie_heavy_features(97, 2));
        for s in [Strategy::Dt(400.0), Strategy::Nn(None), Strategy::Nn(Some(300.0)), Strategy::Nndr(0.9)] {
            let all = match_all(&s, &prev, &cur).unwrap();
            assert_eq!(all.len(), prev.descriptors.len());
            for (i, got) in all.iter().enumerate() {
                // knnMatch(k = n_train) order from the scalar distance: a stable
                // sort keeps equal distances in train order.
                let mut ranked: Vec<DMatch> = cur
                    .descriptors
                    .iter()
                    .enumerate()
                    .map(|(j, t)| DMatch {
                        query_idx: i,
                        train_idx: j,
                        distance: super::super::distance::distance(&prev.descriptors[i], t),
                    })
                    .collect();
                ranked.sort_by(|a, b| a.distance.total_cmp(&b.distance));
                let want: Vec<DMatch> = match s {
                    Strategy::Dt(t) => ranked.into_iter().filter(|m| (m.distance as f64) < t).collect(),
                    Strategy::Nn(t) => {
                        ranked[..1].iter().copied().filter(|m| t.is_none_or(|t| (m.distance as f64) < t)).collect()
                    }
                    Strategy::Nndr(t) => {
                        if (ranked[0].distance as f64) < t * ranked[1].distance as f64 {
                            vec![ranked[0]]
                        } else {
                            Vec::new()
                        }
                    }
                };
                assert_eq!(got, &want, "{s:?} query {i}");
                assert_eq!(got, &match_feature(&s, &prev, &cur, i).unwrap(), "{s:?} query {i}");
            }
        }
        // Fewer than 2 train rows is still an error for nndr on every path.
        let one = tie_heavy_features(1, 3);
        assert!(match_all(&Strategy::Nndr(0.8), &prev, &one).is_err());
    }

    #[test]
    fn kinds_round_trip_through_their_names() {
        for k in StrategyKind::ALL {
            assert_eq!(StrategyKind::parse(k.name()), Some(k));
        }
        assert_eq!(StrategyKind::ALL.map(StrategyKind::name), ["dt", "nn", "nndr"]);
        assert_eq!(StrategyKind::parse("knn"), None);
        assert_eq!(StrategyKind::parse("NNDR"), None);
        for s in [Strategy::Dt(1.0), Strategy::Nn(None), Strategy::Nndr(0.8)] {
            assert_eq!(s.kind().name(), s.name());
        }
    }

    #[test]
    fn parse_validates_thresholds() {
        assert_eq!(Strategy::parse("dt", Some(100.0)).unwrap(), Strategy::Dt(100.0));
        assert_eq!(Strategy::parse("nn", None).unwrap(), Strategy::Nn(None));
        assert!(Strategy::parse("dt", None).unwrap_err().to_string().contains("needs a threshold"));
        assert!(Strategy::parse("nndr", Some(1.5)).unwrap_err().to_string().contains("outside [0, 1]"));
        assert!(Strategy::parse("nn", Some(-1.0)).unwrap_err().to_string().contains("negative"));
        assert!(Strategy::parse("dt", Some(f64::NAN)).unwrap_err().to_string().contains("not a number"));
        assert!(Strategy::parse("knn", Some(1.0)).unwrap_err().to_string().contains("unknown strategy"));
    }

    #[test]
    fn rules_are_strict_and_in_f64() {
        let row = [3.0f32, 1.0, 2.0, 1.0];
        let ids = |m: Vec<DMatch>| m.iter().map(|m| m.train_idx).collect::<Vec<_>>();
        assert_eq!(ids(Strategy::Dt(2.0).select(0, &row).unwrap()), vec![1, 3]);
        assert_eq!(ids(Strategy::Dt(2.5).select(0, &row).unwrap()), vec![1, 3, 2]);
        assert_eq!(ids(Strategy::Nn(None).select(0, &row).unwrap()), vec![1]);
        assert_eq!(ids(Strategy::Nn(Some(1.0)).select(0, &row).unwrap()), Vec::<usize>::new());
        // d1 = d2 = 1: 1 < 1.0 * 1 is false.
        assert!(Strategy::Nndr(1.0).select(0, &row).unwrap().is_empty());
        assert_eq!(ids(Strategy::Nndr(0.8).select(0, &[1.0, 2.0]).unwrap()), vec![0]);
        // 61.4f widened is 61.400001525878906 > 61.4, so t = 61.4 rejects it.
        assert!(Strategy::Nn(Some(61.4)).select(0, &[61.4f32]).unwrap().is_empty());
        assert!(Strategy::Nndr(0.5).select(0, &[1.0]).is_err());
    }
}
