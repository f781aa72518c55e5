//! Why a feature got the matches it got: the numbers behind each rule, for
//! the app's step-by-step view, and the answers common mistakes produce, for
//! its self-check.

use super::distance::distance_row;
use super::info::{matching_info, MatchInfo};
use super::knn::{ranked_row, DMatch};
use super::strategy::{check_feature, Strategy};
use crate::error::Result;
use crate::pyfmt::{py_f32, py_float};
use crate::sift::{Features, KeyPoint};

/// The rule applied, with its numbers.
#[derive(Clone, Debug, PartialEq)]
pub enum Verdict {
    /// dt: how many distances are below t.
    Dt { t: f64, passed: usize },
    /// nn: the nearest distance and whether it passed the optional threshold.
    Nn { t: Option<f64>, d1: f32, kept: bool },
    /// nndr: the two nearest distances, their ratio, whether d1 < t·d2.
    Nndr { t: f64, d1: f32, d2: f32, ratio: f64, kept: bool },
}

/// Everything the step-by-step explanation shows for one feature.
#[derive(Clone, Debug, PartialEq)]
pub struct Explanation {
    pub strategy: Strategy,
    pub feature: usize,
    pub query: KeyPoint,
    /// Every descriptor of the current frame, nearest first (knnMatch order).
    pub ranked: Vec<DMatch>,
    pub matches: Vec<DMatch>,
    pub verdict: Verdict,
    pub info: MatchInfo,
}

impl Explanation {
    /// One sentence stating the rule with this feature's numbers.
    pub fn rule(&self) -> String {
        match &self.verdict {
            Verdict::Dt { t, passed } => format!(
                "dt keeps every descriptor with distance < {}: {passed} of {} pass",
                py_float(*t),
                self.ranked.len()
            ),
            Verdict::Nn { t: None, d1, .. } => {
                format!("nn without a threshold keeps the nearest descriptor (d1 = {})", py_f32(*d1))
            }
            Verdict::Nn { t: Some(t), d1, kept } => format!(
                "nn keeps the nearest descriptor if d1 < t: {} < {} is {}",
                py_f32(*d1),
                py_float(*t),
                if *kept { "True, kept" } else { "False, no match" }
            ),
            Verdict::Nndr { t, d1, d2, ratio, kept } => format!(
                "nndr keeps the nearest if d1 < t·d2: {} < {} × {} = {} is {} (d1/d2 = {:.4})",
                py_f32(*d1),
                py_float(*t),
                py_f32(*d2),
                py_float(*t * *d2 as f64),
                if *kept { "True, kept" } else { "False, no match" },
                ratio
            ),
        }
    }
}

/// Explains the strategy's result for one feature of the previous frame.
pub fn explain(s: &Strategy, prev: &Features, cur: &Features, feature: usize) -> Result<Explanation> {
    check_feature(feature, prev)?;
    let mut row = Vec::new();
    distance_row(&prev.descriptors[feature], &cur.descriptors, &mut row);
    let matches = s.select(feature, &row)?;
    let ranked = ranked_row(feature, &row);
    let d = |i: usize| ranked.get(i).map(|m| m.distance).unwrap_or(f32::NAN);
    let verdict = match *s {
        Strategy::Dt(t) => Verdict::Dt { t, passed: matches.len() },
        Strategy::Nn(t) => Verdict::Nn { t, d1: d(0), kept: !matches.is_empty() },
        Strategy::Nndr(t) => {
            Verdict::Nndr { t, d1: d(0), d2: d(1), ratio: d(0) as f64 / d(1) as f64, kept: !matches.is_empty() }
        }
    };
    let info = matching_info(&prev.keypoints, &cur.keypoints, &matches);
    Ok(Explanation { strategy: *s, feature, query: prev.keypoints[feature], ranked, matches, verdict, info })
}

/// A mistake students commonly make, and the answer it would produce.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mistake {
    /// `<=` instead of `<` in the threshold test.
    LessOrEqual,
    /// dt with `knnMatch(k=100)`, so at most 100 matches.
    TruncatedK100,
    /// nndr with the ratio the wrong way round (d2 < t·d1 / n.distance / m.distance).
    RatioInverted,
    /// nn returning every candidate of knnMatch(k=2) instead of one.
    NnMoreThanOne,
    /// The frames swapped: the current frame used as the query.
    WrongFrameOrder,
}

impl Mistake {
    pub fn describe(&self) -> &'static str {
        match self {
            Mistake::LessOrEqual => {
                "you used <= where the lab uses a strict < (a distance equal to the threshold must be rejected)"
            }
            Mistake::TruncatedK100 => {
                "your dt asked knnMatch for k=100 neighbours, so it stops at 100 matches; use k=len(des2)"
            }
            Mistake::RatioInverted => {
                "your nndr ratio is inverted: keep the nearest m when m.distance < t * n.distance"
            }
            Mistake::NnMoreThanOne => "your nn returns more than one match: keep only the nearest neighbour (k=1)",
            Mistake::WrongFrameOrder => {
                "the frames are swapped: the previous frame (FRAME_ID-1) is the query, the current frame the train"
            }
        }
    }
}

/// The `matching_info` each common mistake would give, where it differs
/// from the correct one (so a student's answer can be diagnosed).
pub fn mistaken_answers(
    s: &Strategy,
    prev: &Features,
    cur: &Features,
    feature: usize,
) -> Result<Vec<(Mistake, MatchInfo)>> {
    let e = explain(s, prev, cur, feature)?;
    let info = |m: &[DMatch]| matching_info(&prev.keypoints, &cur.keypoints, m);
    let mut out = Vec::new();
    let mut push = |mistake: Mistake, v: MatchInfo| {
        if v != e.info && !out.iter().any(|(_, o)| *o == v) {
            out.push((mistake, v));
        }
    };
    match *s {
        Strategy::Dt(t) => {
            let le: Vec<DMatch> = e.ranked.iter().copied().filter(|m| m.distance as f64 <= t).collect();
            push(Mistake::LessOrEqual, info(&le));
            let k100: Vec<DMatch> = e.matches.iter().copied().take(100).collect();
            push(Mistake::TruncatedK100, info(&k100));
        }
        Strategy::Nn(t) => {
            if let Some(t) = t {
                let le: Vec<DMatch> = e.ranked.iter().copied().take(1).filter(|m| m.distance as f64 <= t).collect();
                push(Mistake::LessOrEqual, info(&le));
            }
            let two: Vec<DMatch> =
                e.ranked.iter().copied().take(2).filter(|m| t.is_none_or(|t| (m.distance as f64) < t)).collect();
            push(Mistake::NnMoreThanOne, info(&two));
        }
        Strategy::Nndr(t) => {
            if e.ranked.len() >= 2 {
                let (d1, d2) = (e.ranked[0].distance as f64, e.ranked[1].distance as f64);
                let le: Vec<DMatch> = if d1 <= t * d2 { vec![e.ranked[0]] } else { vec![] };
                push(Mistake::LessOrEqual, info(&le));
                let inv: Vec<DMatch> = if d2 < t * d1 { vec![e.ranked[0]] } else { vec![] };
                push(Mistake::RatioInverted, info(&inv));
            }
        }
    }
    // Swapped frames: the feature id read in the current frame, matched in the previous.
    if feature < cur.keypoints.len() {
        if let Ok(m) = super::strategy::match_feature(s, cur, prev, feature) {
            push(Mistake::WrongFrameOrder, matching_info(&cur.keypoints, &prev.keypoints, &m));
        }
    }
    Ok(out)
}
