//! The lab's three matching strategies, with their argument checks.

use super::distance::distance_row;
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
            other => Err(Error::InvalidArgument(format!(
                "unknown strategy '{other}': choose dt, nn or nndr"
            ))),
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
                let mut m: Vec<DMatch> = row
                    .iter()
                    .enumerate()
                    .filter(|&(_, &d)| (d as f64) < t)
                    .map(|(j, &d)| DMatch { query_idx, train_idx: j, distance: d })
                    .collect();
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

/// Checks a feature id against the query frame's keypoints.
pub fn check_feature(feature: usize, prev: &Features) -> Result<()> {
    let n = prev.keypoints.len();
    if feature >= n {
        return Err(Error::InvalidArgument(if n == 0 {
            format!("feature id {feature} is out of range: the previous frame has no keypoints")
        } else {
            format!(
                "feature id {feature} is out of range: the previous frame has {n} keypoints (valid ids: 0 to {})",
                n - 1
            )
        }));
    }
    Ok(())
}

/// The matches of one feature of the previous frame (the query) in the
/// current frame (the train), as the lab's strategy returns them.
pub fn match_feature(s: &Strategy, prev: &Features, cur: &Features, feature: usize) -> Result<Vec<DMatch>> {
    check_feature(feature, prev)?;
    let mut row = Vec::new();
    distance_row(&prev.descriptors[feature], &cur.descriptors, &mut row);
    s.select(feature, &row)
}

/// The strategy applied to every query descriptor (what the lab's `dt`,
/// `nn` and `nndr` functions return), rows computed in parallel natively.
pub fn match_all(s: &Strategy, prev: &Features, cur: &Features) -> Result<Vec<Vec<DMatch>>> {
    let n = prev.descriptors.len();
    let run = |range: std::ops::Range<usize>| -> Result<Vec<Vec<DMatch>>> {
        let mut row = Vec::new();
        range
            .map(|i| {
                distance_row(&prev.descriptors[i], &cur.descriptors, &mut row);
                s.select(i, &row)
            })
            .collect()
    };
    #[cfg(not(target_arch = "wasm32"))]
    {
        let threads = std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1);
        if threads > 1 && n >= 64 {
            let chunk = n.div_ceil(threads);
            let parts: Vec<Result<Vec<Vec<DMatch>>>> = std::thread::scope(|sc| {
                let hs: Vec<_> =
                    (0..threads).map(|t| sc.spawn(move || run(t * chunk..((t + 1) * chunk).min(n)))).collect();
                hs.into_iter()
                    .map(|h| h.join().unwrap_or_else(|_| Err(Error::InvalidArgument("matching thread failed".into()))))
                    .collect()
            });
            let mut out = Vec::with_capacity(n);
            for p in parts {
                out.extend(p?);
            }
            return Ok(out);
        }
    }
    run(0..n)
}

#[cfg(test)]
mod tests {
    use super::*;

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
