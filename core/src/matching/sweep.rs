//! The precision / number-of-matches trade-off of the three strategies as
//! each one's threshold sweeps its range, computed once per pair from the
//! full distance table: every candidate's key (dt: its distance; nn: the
//! nearest distance; nndr: d1/d2) sorted once, with the cumulative count of
//! correct ones, so the counts at any threshold are one binary search instead
//! of a re-match.
//!
//! The rules are the lab's (`strategy.rs`): dt keeps d < t, nn keeps d1 < t,
//! nndr keeps d1 < t·d2, all compared in f64.

use super::distance::{distance_rows, TrainSet};
use super::epipolar::{homogeneous, sampson_of, Verdicts};
use super::kind::StrategyKind;
use super::knn::knn_row;
use crate::error::{Error, Result};
use crate::sift::Features;
use nalgebra::Matrix3;

/// The thresholds the app's chart sweeps: dt and nn over distances
/// 0..=500, nndr over ratios 0..=1.
pub fn range(kind: StrategyKind) -> (f64, f64) {
    match kind {
        StrategyKind::Dt | StrategyKind::Nn => (0.0, DISTANCE_MAX),
        StrategyKind::Nndr => (0.0, 1.0),
    }
}

/// The largest dt threshold the sweep can answer: pairs at or beyond it are
/// not kept (on KITTI most of the 1500² pairs are), which keeps the sort small.
pub const DISTANCE_MAX: f64 = 500.0;

/// One strategy's candidates, each with the smallest threshold that
/// passes it encoded as its key: a candidate passes t exactly when key < t.
#[derive(Clone, Debug, PartialEq)]
pub struct Curve {
    pub kind: StrategyKind,
    /// Ascending.
    keys: Vec<f64>,
    /// Each candidate's (query, train) keypoint indices, in key order.
    pairs: Vec<[u32; 2]>,
    /// Whether each candidate is correct; `None` without ground truth.
    ok: Option<Vec<bool>>,
    /// `correct[i]`: how many of the first `i` candidates are correct.
    correct: Option<Vec<u32>>,
    /// Thresholds beyond this are outside what the table holds.
    max: f64,
}

/// Matches of a curve: (query, train) keypoint indices in key order, and
/// their verdicts when judged.
pub type Selected<'a> = (&'a [[u32; 2]], Option<&'a [bool]>);

/// A curve's data: ascending keys, pairs, verdicts, the largest threshold answered.
pub type CurveParts<'a> = (&'a [f64], &'a [[u32; 2]], Option<&'a [bool]>, f64);

/// A candidate before sorting: key, query, train, correct.
type Candidate = (f64, u32, u32, bool);

impl Curve {
    fn new(kind: StrategyKind, mut cands: Vec<Candidate>, truth: bool, max: f64) -> Curve {
        // Ties in (query, train) order, so the order is fixed without a
        // stable sort (the unstable one is faster on dt's ~600k candidates).
        cands.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)).then(a.2.cmp(&b.2)));
        let ok = truth.then(|| cands.iter().map(|c| c.3).collect());
        let pairs = cands.iter().map(|c| [c.1, c.2]).collect();
        Curve::assemble(kind, cands.into_iter().map(|c| c.0).collect(), pairs, ok, max)
    }

    fn assemble(kind: StrategyKind, keys: Vec<f64>, pairs: Vec<[u32; 2]>, ok: Option<Vec<bool>>, max: f64) -> Curve {
        let correct = ok.as_ref().map(|ok: &Vec<bool>| {
            let mut c = Vec::with_capacity(ok.len() + 1);
            c.push(0u32);
            for (i, &b) in ok.iter().enumerate() {
                c.push(c[i] + b as u32);
            }
            c
        });
        Curve { kind, keys, pairs, ok, correct, max }
    }

    /// The curve's data (keys ascending, pairs, verdicts, range limit), to
    /// send it from a worker to the page.
    pub fn parts(&self) -> CurveParts<'_> {
        (&self.keys, &self.pairs, self.ok.as_deref(), self.max)
    }

    /// Rebuilds a curve from [`Curve::parts`]; errors if they do not fit.
    pub fn from_parts(
        kind: StrategyKind,
        keys: Vec<f64>,
        pairs: Vec<[u32; 2]>,
        ok: Option<Vec<bool>>,
        max: f64,
    ) -> Result<Curve> {
        let sorted = keys.windows(2).all(|w| w[0] <= w[1]);
        if !sorted || pairs.len() != keys.len() || ok.as_ref().is_some_and(|o| o.len() != keys.len()) {
            return Err(Error::InvalidArgument(format!(
                "a {} sweep needs ascending keys and one pair (and verdict) per key",
                kind.name()
            )));
        }
        Ok(Curve::assemble(kind, keys, pairs, ok, max))
    }

    /// The matches the strategy gives at threshold `t`, (query, train) in
    /// key order, with their verdicts (`None` past the range).
    pub fn matches_at(&self, t: f64) -> Option<Selected<'_>> {
        let m = self.at(t)?.matches;
        Some((&self.pairs[..m], self.ok.as_ref().map(|o| &o[..m])))
    }

    /// Every candidate's matches (nn without a threshold).
    pub fn all_matches(&self) -> Selected<'_> {
        (&self.pairs, self.ok.as_deref())
    }

    /// The counts the strategy gives at threshold `t` (`None` past the
    /// sweep's range, where the table is incomplete).
    pub fn at(&self, t: f64) -> Option<Verdicts> {
        if t > self.max {
            return None;
        }
        Some(self.first(self.keys.partition_point(|&k| k < t)))
    }

    /// The counts of the `m` candidates with the lowest keys.
    fn first(&self, m: usize) -> Verdicts {
        Verdicts { matches: m, correct: self.correct.as_ref().map(|c| c[m] as usize) }
    }

    /// Every candidate the table holds (nn: every query, i.e. nn without a threshold).
    pub fn all(&self) -> Verdicts {
        self.first(self.keys.len())
    }

    /// `steps + 1` evenly spaced thresholds over the strategy's range, with
    /// their counts: the chart's polyline.
    pub fn sample(&self, steps: usize) -> Vec<(f64, Verdicts)> {
        let (lo, hi) = range(self.kind);
        (0..=steps)
            .filter_map(|i| {
                let t = lo + (hi - lo) * i as f64 / steps.max(1) as f64;
                Some((t, self.at(t)?))
            })
            .collect()
    }

    /// Precision after the first `m` candidates (1 ≤ m ≤ all).
    fn precision_of_first(&self, m: usize) -> Option<f64> {
        self.first(m).precision()
    }

    /// Where this curve and `other` cross in the (matches, precision) plane:
    /// the match counts m ≥ `from` at which the sign of their precision
    /// difference changes, with the precision there. A change counts once
    /// the new order holds by more than [`CROSSING_MARGIN`], so two curves
    /// running together do not "cross" at every step; it is reported where
    /// the difference first took the new sign.
    pub fn crossings(&self, other: &Curve, from: usize) -> Vec<(usize, f64)> {
        let n = self.keys.len().min(other.keys.len());
        let mut out = Vec::new();
        let (mut last, mut since): (Option<bool>, Option<(usize, f64)>) = (None, None);
        for m in from.max(1)..=n {
            let (Some(a), Some(b)) = (self.precision_of_first(m), other.precision_of_first(m)) else { return out };
            let (above, clear) = (a > b, (a - b).abs() > CROSSING_MARGIN);
            match last {
                None if clear => last = Some(above),
                Some(l) if l != above && a != b => {
                    let start = *since.get_or_insert((m, a));
                    if clear {
                        out.push(start);
                        (last, since) = (Some(above), None);
                    }
                }
                _ => since = None,
            }
        }
        out
    }
}

/// How far apart (in precision) two curves must get for a crossing to count.
pub const CROSSING_MARGIN: f64 = 0.005;

/// The three curves of one pair.
#[derive(Clone, Debug, PartialEq)]
pub struct Sweep {
    pub dt: Curve,
    pub nn: Curve,
    pub nndr: Curve,
}

impl Sweep {
    pub fn curve(&self, kind: StrategyKind) -> &Curve {
        match kind {
            StrategyKind::Dt => &self.dt,
            StrategyKind::Nn => &self.nn,
            StrategyKind::Nndr => &self.nndr,
        }
    }
}

/// The sweep of `prev` (queries) against `cur` (train). With `truth` (F and
/// the Sampson threshold in pixels) each candidate is judged; without it the
/// curves hold counts only.
pub fn sweep(prev: &Features, cur: &Features, truth: Option<(&Matrix3<f64>, f64)>) -> Result<Sweep> {
    let nt = cur.descriptors.len();
    if nt < 2 && !prev.descriptors.is_empty() {
        return Err(Error::InvalidArgument(format!(
            "the sweep needs at least 2 keypoints in the current frame (nndr compares the two nearest), it has {nt}"
        )));
    }
    // Fx₁ per query and (Fᵀx₂, x₂) per train keypoint, once each.
    let fa: Vec<_> =
        truth.map_or(Vec::new(), |(f, _)| prev.keypoints.iter().map(|k| f * homogeneous([k.x, k.y])).collect());
    let ftb: Vec<_> = truth.map_or(Vec::new(), |(f, _)| {
        let ft = f.transpose();
        cur.keypoints.iter().map(|k| (ft * homogeneous([k.x, k.y]), homogeneous([k.x, k.y]))).collect()
    });
    let ok = |q: usize, t: usize| truth.is_some_and(|(_, px)| sampson_of(&fa[q], &ftb[t].0, &ftb[t].1) <= px);
    let (mut dt, mut nn, mut nndr) = (Vec::new(), Vec::new(), Vec::new());
    const BLOCK: usize = 32;
    let train = TrainSet::new(&cur.descriptors);
    let mut rows = vec![0f32; BLOCK * nt];
    for (b, qs) in prev.descriptors.chunks(BLOCK).enumerate() {
        distance_rows(qs, &train, &mut rows[..qs.len() * nt]);
        for i in 0..qs.len() {
            let q = b * BLOCK + i;
            let row = &rows[i * nt..(i + 1) * nt];
            for (t, &d) in row.iter().enumerate() {
                if (d as f64) < DISTANCE_MAX {
                    dt.push((d as f64, q as u32, t as u32, ok(q, t)));
                }
            }
            let best = knn_row(q, row, 2);
            let (d1, d2) = (best[0].distance as f64, best[1].distance as f64);
            let j = best[0].train_idx;
            let good = ok(q, j);
            nn.push((d1, q as u32, j as u32, good));
            // d1 < t·d2 ⟺ d1/d2 < t (up to the rounding of the quotient); with
            // d2 = 0 no t passes.
            nndr.push((if d2 > 0.0 { d1 / d2 } else { f64::INFINITY }, q as u32, j as u32, good));
        }
    }
    let truth = truth.is_some();
    Ok(Sweep {
        dt: Curve::new(StrategyKind::Dt, dt, truth, DISTANCE_MAX),
        nn: Curve::new(StrategyKind::Nn, nn, truth, f64::INFINITY),
        nndr: Curve::new(StrategyKind::Nndr, nndr, truth, f64::INFINITY),
    })
}

#[cfg(test)]
mod tests {
    use super::super::epipolar::{fundamental, judge};
    use super::super::strategy::{match_all, Strategy};
    use super::*;
    use crate::camera::Camera;
    use crate::dataset::parse_poses;
    use crate::sift::{detect_and_compute, SiftParams};

    fn frame(i: usize) -> Features {
        let path = format!("{}/../www/demo/MyKITTI/gray/00/image_0/{i:06}.png", env!("CARGO_MANIFEST_DIR"));
        let img = crate::GrayImage::decode(&std::fs::read(path).unwrap()).unwrap();
        detect_and_compute(&img, &SiftParams::default())
    }

    /// On a real pair, the sweep's counts at a few thresholds equal a full
    /// re-match with `match_all`, judged match by match.
    #[test]
    fn sweep_equals_rematching_at_sampled_thresholds() {
        let (prev, cur) = (frame(10), frame(11));
        let poses = parse_poses(
            &std::fs::read_to_string(format!("{}/../www/demo/MyKITTI/poses/00.txt", env!("CARGO_MANIFEST_DIR")))
                .unwrap(),
        )
        .unwrap();
        let f = fundamental(&poses[10], &poses[11], &Camera::default()).unwrap();
        let s = sweep(&prev, &cur, Some((&f, 2.0))).unwrap();
        let check = |strategy: Strategy, got: Verdicts| {
            let all: Vec<_> = match_all(&strategy, &prev, &cur).unwrap().into_iter().flatten().collect();
            let ok = judge(&f, &prev.keypoints, &cur.keypoints, &all, 2.0);
            let want = Verdicts { matches: all.len(), correct: Some(ok.iter().filter(|&&b| b).count()) };
            assert_eq!(got, want, "{strategy:?}");
            want
        };
        for t in [0.0, 100.0, 180.0, 250.0, 333.3, 499.9] {
            check(Strategy::Dt(t), s.dt.at(t).unwrap());
            check(Strategy::Nn(Some(t)), s.nn.at(t).unwrap());
        }
        for t in [0.0, 0.5, 0.7, 0.8, 0.95, 1.0] {
            check(Strategy::Nndr(t), s.nndr.at(t).unwrap());
        }
        let all = check(Strategy::Nn(None), s.nn.all());
        // The matches themselves, not only their number: nndr 0.8's pairs
        // are match_all's, and the parts rebuild the same curve.
        let mut want: Vec<[u32; 2]> = match_all(&Strategy::Nndr(0.8), &prev, &cur)
            .unwrap()
            .into_iter()
            .flatten()
            .map(|m| [m.query_idx as u32, m.train_idx as u32])
            .collect();
        let mut got = s.nndr.matches_at(0.8).unwrap().0.to_vec();
        want.sort();
        got.sort();
        assert_eq!(got, want);
        let (k, p, o, max) = s.dt.parts();
        let back = Curve::from_parts(StrategyKind::Dt, k.to_vec(), p.to_vec(), o.map(<[bool]>::to_vec), max).unwrap();
        assert_eq!(back, s.dt);
        assert!(Curve::from_parts(StrategyKind::Dt, vec![2.0, 1.0], vec![[0, 0]; 2], None, max).is_err());
        eprintln!("frames 10-11: {} dt candidates under {DISTANCE_MAX}", k.len());
        assert_eq!(all.matches, prev.keypoints.len());
        // The sample has counts rising with the threshold, and the dt table
        // refuses thresholds it cannot answer.
        let pts = s.nndr.sample(100);
        assert_eq!(pts.len(), 101);
        assert!(pts.windows(2).all(|w| w[0].1.matches <= w[1].1.matches));
        assert_eq!(s.dt.at(500.5), None);
    }

    #[test]
    fn without_truth_the_curves_count_only() {
        let (prev, cur) = (frame(0), frame(1));
        let s = sweep(&prev, &cur, None).unwrap();
        let v = s.nndr.at(0.8).unwrap();
        let want: usize = match_all(&Strategy::Nndr(0.8), &prev, &cur).unwrap().iter().map(Vec::len).sum();
        assert_eq!((v.matches, v.correct), (want, None));
    }

    #[test]
    fn crossings_find_sign_changes() {
        let c = |v: [bool; 4]| (0..4).map(|i| (i as f64 + 1.0, i, i, v[i as usize])).collect::<Vec<_>>();
        let a = Curve::new(StrategyKind::Nn, c([true, false, false, false]), true, 9.0);
        let b = Curve::new(StrategyKind::Dt, c([false, true, true, true]), true, 9.0);
        // a: 1, 1/2, 1/3, 1/4; b: 0, 1/2, 2/3, 3/4 → equal at m = 2, b above from m = 3.
        assert_eq!(a.crossings(&b, 1), vec![(3, 1.0 / 3.0)]);
        // Curves that touch without changing order do not cross.
        assert!(a.crossings(&a, 1).is_empty());
    }
}
