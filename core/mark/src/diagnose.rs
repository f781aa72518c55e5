//! Each case judged: correct, wrong or an error, and for a failed case why.
//! The self-check's mistakes ([`Mistake`]) where they apply, and the ones a
//! whole result shows (a list per query dropped, float64 distances, another
//! order, a threshold ignored, the empty case, …).

use crate::cases::Case;
use crate::escape::escaped;
use crate::protocol::{ErrorKind, Reply};
use crate::pyvalue::{info_type_problem, info_value, PyValue};
use crate::reference::{
    difference_at, expected_text, first_difference, got_lists_text, info_equal, info_json, matches_equal,
    returned_matches, shorten, Expected, Got,
};
use siftlab_core::json::Json;
use siftlab_core::matching::{knn_match, match_all, matching_info, DMatch, MatchInfo, Mistake, Strategy};
use siftlab_core::pyfmt::{py_f32, py_float};
use siftlab_core::sift::Features;

/// How a case ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Status {
    /// The returned value equals the reference's.
    Correct,
    /// A value of the right type, not equal to the reference's.
    Wrong,
    /// No value: an exception, a wrong return type, or over the time limit
    /// (the lab's "runtime error", which costs the task's 0.5 marks).
    Error,
}

impl Status {
    pub fn name(self) -> &'static str {
        match self {
            Status::Correct => "correct",
            Status::Wrong => "wrong",
            Status::Error => "error",
        }
    }
}

/// Why a case failed.
#[derive(Clone, Debug, PartialEq)]
pub enum Diagnosis {
    /// One of the self-check's common mistakes (`matching::Mistake`).
    Mistake(Mistake),
    /// dt keeps at most k matches per query: `knnMatch(…, k)` with k < len(des2).
    TruncatedK(usize),
    /// nndr tested `d1 / d2 < t`, which rounds differently from `d1 < t * d2`.
    RatioDivision,
    /// nn with a threshold kept every nearest neighbour.
    NnIgnoresThreshold,
    /// nn with `None` kept no match.
    NnNoneKeepsNothing,
    /// The lists of queries without a match left out.
    DroppedEmptyLists,
    /// Another number of lists than query descriptors.
    Length { expected: usize, got: usize },
    /// The same matches, distances the float64 L2 distance, not the float32.
    NotFloat32,
    /// The same matches per query in another order.
    Order,
    /// matching_info: coordinates rounded, not truncated.
    Rounded,
    /// matching_info: coordinates left as floats.
    FloatCoordinates,
    /// matching_info: (y, x) instead of (x, y).
    SwappedXY,
    /// matching_info on an empty list: not `((0, 0), [], [])` (with the
    /// exception's message if it raised one).
    EmptyCase(Option<String>),
    /// matching_info's value is not `((x, y), [(x, y), …], [d, …])`.
    InfoShape(String),
    /// matching_info's numbers are right but Python's `==` tells the value
    /// from the lab's tuple (lists for points, numpy arrays, …).
    InfoTypes,
    /// A wrong return type or shape (the harness's message).
    WrongType(String),
    /// An exception, with a hint when the case explains it.
    Runtime { message: String, hint: Option<&'static str> },
    /// Over the per-call limit; the process was stopped.
    Timeout { seconds: f64 },
    /// Not run: the task's time was used up.
    TaskTimeLimit { seconds: f64 },
    /// The Python process ended during the call.
    Crashed(String),
    /// None of the above: where the value first differs.
    Differs(String),
}

impl Diagnosis {
    /// A stable name for the JSON report and tests.
    pub fn code(&self) -> &'static str {
        match self {
            Diagnosis::Mistake(Mistake::LessOrEqual) => "less_or_equal",
            Diagnosis::Mistake(Mistake::TruncatedK100) => "k_too_small",
            Diagnosis::Mistake(Mistake::RatioInverted) => "ratio_inverted",
            Diagnosis::Mistake(Mistake::NnMoreThanOne) => "nn_more_than_one",
            Diagnosis::Mistake(Mistake::WrongFrameOrder) => "frames_swapped",
            Diagnosis::TruncatedK(_) => "k_too_small",
            Diagnosis::RatioDivision => "ratio_division",
            Diagnosis::NnIgnoresThreshold => "nn_ignores_threshold",
            Diagnosis::NnNoneKeepsNothing => "nn_ignores_none",
            Diagnosis::DroppedEmptyLists => "empty_lists_dropped",
            Diagnosis::Length { .. } => "wrong_length",
            Diagnosis::NotFloat32 => "not_float32",
            Diagnosis::Order => "wrong_order",
            Diagnosis::Rounded => "rounded",
            Diagnosis::FloatCoordinates => "float_coordinates",
            Diagnosis::SwappedXY => "swapped_xy",
            Diagnosis::EmptyCase(_) => "empty_case",
            Diagnosis::InfoShape(_) => "wrong_shape",
            Diagnosis::InfoTypes => "wrong_types_inside",
            Diagnosis::WrongType(_) => "wrong_type",
            Diagnosis::Runtime { .. } => "runtime_error",
            Diagnosis::Timeout { .. } => "timeout",
            Diagnosis::TaskTimeLimit { .. } => "task_time_limit",
            Diagnosis::Crashed(_) => "crashed",
            Diagnosis::Differs(_) => "differs",
        }
    }

    /// What went wrong and what to do, for the student.
    pub fn describe(&self) -> String {
        match self {
            Diagnosis::Mistake(Mistake::WrongFrameOrder) => {
                "des1 and des2 (or kp1 and kp2) are swapped: des1, the previous frame (FRAME_ID-1), is the query: \
                 knnMatch(des1, des2, k)"
                    .into()
            }
            Diagnosis::Mistake(m) => m.describe().into(),
            Diagnosis::TruncatedK(k) => format!(
                "your dt keeps at most {k} matches per query: it asked knnMatch for k={k} neighbours; use \
                 k=len(des2) so every match under the threshold is kept"
            ),
            Diagnosis::RatioDivision => "your nndr tests d1 / d2 < threshold; the lab tests d1 < threshold * d2, \
                 which rounds differently in floating point (m.distance < t * n.distance)"
                .into(),
            Diagnosis::NnIgnoresThreshold => {
                "your nn keeps every nearest neighbour: it ignores the threshold (keep it only if its distance < \
                 threshold)"
                    .into()
            }
            Diagnosis::NnNoneKeepsNothing => "with threshold None your nn keeps no match: None means no threshold, \
                 so every query keeps its nearest neighbour"
                .into(),
            Diagnosis::DroppedEmptyLists => "the lists of queries without a match are left out: return one list per \
                 query descriptor of des1, an empty list where it has no match"
                .into(),
            Diagnosis::Length { expected, got } => {
                format!("returned {got} lists, expected {expected}: one list per query descriptor of des1")
            }
            Diagnosis::NotFloat32 => "the distances are float64 L2 distances, not the float32 ones DMatch holds: \
                 return knnMatch's DMatch distances (OpenCV computes them in float32)"
                .into(),
            Diagnosis::Order => "the right matches in another order: each list is nearest first, equal distances \
                 by lower trainIdx (knnMatch's order)"
                .into(),
            Diagnosis::Rounded => {
                "coordinates are rounded; the lab truncates them: int(x), int(y) of KeyPoint.pt".into()
            }
            Diagnosis::FloatCoordinates => "coordinates are floats: truncate them with int(x), int(y)".into(),
            Diagnosis::SwappedXY => "x and y are swapped: KeyPoint.pt is (x, y)".into(),
            Diagnosis::EmptyCase(raised) => {
                let mut s =
                    "the empty case: for an empty list of matches matching_info returns ((0, 0), [], [])".to_string();
                if let Some(m) = raised {
                    s.push_str(&format!("; it raised {m}"));
                }
                s
            }
            Diagnosis::InfoShape(what) => {
                format!("matching_info must return a tuple ((x, y), [(x, y), ...], [d, ...]): {what}")
            }
            Diagnosis::InfoTypes => "the numbers are right, but Python's == tells the value apart from the lab's \
                 ((x, y), [(x, y), ...], [d, ...]): each point a tuple of two ints, the distances floats"
                .into(),
            Diagnosis::WrongType(m) => format!("wrong return type (counts as a runtime error): {m}"),
            Diagnosis::Runtime { message, hint } => match hint {
                Some(h) => format!("runtime error: {message} ({h})"),
                None => format!("runtime error: {message}"),
            },
            Diagnosis::Timeout { seconds } => format!(
                "the call ran over {seconds} s and was stopped (an endless loop, or far too slow); it counts as a \
                 runtime error"
            ),
            Diagnosis::TaskTimeLimit { seconds } => {
                format!("not run: the task's {seconds} s were used up by the calls before it")
            }
            Diagnosis::Crashed(m) => format!("the Python process ended during the call: {m}"),
            Diagnosis::Differs(m) => m.clone(),
        }
    }
}

/// One marked case.
#[derive(Clone, Debug, PartialEq)]
pub struct CaseResult {
    pub case: Case,
    pub status: Status,
    /// Why it failed (None when correct).
    pub diagnosis: Option<Diagnosis>,
    /// The reference value as shown in the report (empty when correct).
    pub expected: String,
    /// The returned value as shown in the report (empty when correct).
    pub returned: String,
    /// Wall time of the call, knnMatch requests included.
    pub seconds: f64,
}

/// Characters of a value shown in a report.
const SHOWN: usize = 300;

/// Judges the harness's reply to `case` against the reference value.
pub fn judge(
    case: &Case,
    expected: &Expected,
    reply: &Reply,
    prev: &Features,
    cur: &Features,
    seconds: f64,
) -> CaseResult {
    let result = |status, diagnosis, expected: String, returned: String| CaseResult {
        case: *case,
        status,
        diagnosis,
        expected: if status == Status::Correct { String::new() } else { expected },
        returned: if status == Status::Correct { String::new() } else { escaped(&returned, SHOWN) },
        seconds,
    };
    match reply {
        Reply::Error { message, kind } => {
            let d = error_diagnosis(case, expected, message, *kind);
            result(Status::Error, Some(d), expected_summary(expected), "no value".into())
        }
        Reply::Ok { value } => match expected {
            Expected::Matches(want) => match returned_matches(value) {
                Err(e) => {
                    let d = Diagnosis::WrongType(format!(
                        "{} must return a list of lists of DMatch: {e}",
                        case.task().name()
                    ));
                    result(Status::Error, Some(d), expected_text(want, None), value.py_repr())
                }
                Ok(got) => {
                    if matches_equal(want, &got) {
                        return result(Status::Correct, None, String::new(), String::new());
                    }
                    let at = difference_at(want, &got);
                    let d = diagnose_matches(&case.strategy(), want, &got, prev, cur);
                    result(Status::Wrong, Some(d), expected_text(want, at), got_lists_text(&got, at))
                }
            },
            Expected::Info { matches, info } => {
                // The verdict is Python's == applied here to the typed value:
                // nothing the student's objects define takes part in it.
                let got = PyValue::from_json(value);
                let shown = got.py_repr();
                if let Some(problem) = info_type_problem(&got) {
                    return result(Status::Error, Some(Diagnosis::WrongType(problem)), info.to_string(), shown);
                }
                if got.py_eq(&info_value(info)) {
                    return result(Status::Correct, None, String::new(), String::new());
                }
                let value = got.to_json();
                // Past the base class's three type checks the reference
                // marker only compares: a value of another shape inside is
                // wrong, not an error (it keeps the task's 0.5).
                if let Some(what) = info_shape_problem(&value) {
                    let d = if matches.is_empty() { Diagnosis::EmptyCase(None) } else { Diagnosis::InfoShape(what) };
                    return result(Status::Wrong, Some(d), info.to_string(), shown);
                }
                let d = if info_equal(info, &value) {
                    Diagnosis::InfoTypes
                } else {
                    diagnose_info(matches, info, &value, prev, cur)
                };
                result(Status::Wrong, Some(d), info.to_string(), shown)
            }
        },
    }
}

/// A case that ended without a reply: a timeout, a crash, the task's limit.
pub fn failed_call(case: &Case, expected: &Expected, diagnosis: Diagnosis, seconds: f64) -> CaseResult {
    CaseResult {
        case: *case,
        status: Status::Error,
        diagnosis: Some(diagnosis),
        expected: expected_summary(expected),
        returned: "no value".into(),
        seconds,
    }
}

fn expected_summary(expected: &Expected) -> String {
    match expected {
        Expected::Matches(want) => expected_text(want, None),
        Expected::Info { info, .. } => shorten(&info.to_string(), SHOWN),
    }
}

fn error_diagnosis(case: &Case, expected: &Expected, message: &str, kind: ErrorKind) -> Diagnosis {
    match kind {
        ErrorKind::Type => return Diagnosis::WrongType(message.to_string()),
        ErrorKind::Protocol => {
            return Diagnosis::Runtime {
                message: message.to_string(),
                hint: Some("the harness refused siftlab's request: a fault of siftlab's, please report it"),
            }
        }
        _ => {}
    }
    let hint = match case {
        Case::Nn { threshold: None, .. } => Some("nn was called with threshold None: keep every nearest neighbour"),
        Case::Info { .. } if expected.info_matches().is_empty() => {
            return Diagnosis::EmptyCase(Some(message.to_string()));
        }
        _ if message.contains("knn > 0") => Some("knnMatch needs k >= 1"),
        _ => None,
    };
    Diagnosis::Runtime { message: message.to_string(), hint }
}

/// The L2 distance in float64: `sqrt` of the exact integer sum.
fn distance_f64(a: &[u8; 128], b: &[u8; 128]) -> f64 {
    let s: u32 = a.iter().zip(b).map(|(&x, &y)| (x as i32 - y as i32).unsigned_abs().pow(2)).sum();
    (s as f64).sqrt()
}

fn f64_distance_of(g: &Got, prev: &Features, cur: &Features) -> Option<f64> {
    let q = prev.descriptors.get(usize::try_from(g.query).ok()?)?;
    let t = cur.descriptors.get(usize::try_from(g.train).ok()?)?;
    Some(distance_f64(q, t))
}

fn same_pairs(want: &[Vec<DMatch>], got: &[Vec<Got>]) -> bool {
    want.len() == got.len()
        && want.iter().zip(got).all(|(w, g)| {
            w.len() == g.len()
                && w.iter().zip(g).all(|(w, g)| g.query == w.query_idx as i64 && g.train == w.train_idx as i64)
        })
}

/// Why dt / nn / nndr's lists differ from the reference's.
fn diagnose_matches(
    s: &Strategy,
    want: &[Vec<DMatch>],
    got: &[Vec<Got>],
    prev: &Features,
    cur: &Features,
) -> Diagnosis {
    let equal = |v: &[Vec<DMatch>]| matches_equal(v, got);
    let swapped = || match_all(s, cur, prev).is_ok_and(|v| equal(&v));
    if want.len() != got.len() {
        if swapped() {
            return Diagnosis::Mistake(Mistake::WrongFrameOrder);
        }
        let kept: Vec<Vec<DMatch>> = want.iter().filter(|r| !r.is_empty()).cloned().collect();
        if equal(&kept) {
            return Diagnosis::DroppedEmptyLists;
        }
        return Diagnosis::Length { expected: want.len(), got: got.len() };
    }
    if same_pairs(want, got) {
        let all_f64 = got.iter().flatten().all(|g| f64_distance_of(g, prev, cur) == Some(g.distance));
        if all_f64 {
            return Diagnosis::NotFloat32;
        }
        let (i, j, w, g) = want
            .iter()
            .zip(got)
            .enumerate()
            .find_map(|(i, (w, g))| {
                w.iter().zip(g).enumerate().find(|(_, (w, g))| !g.equals(w)).map(|(j, (w, g))| (i, j, *w, *g))
            })
            .unwrap_or((
                0,
                0,
                DMatch { query_idx: 0, train_idx: 0, distance: 0.0 },
                Got { query: 0, train: 0, distance: 0.0 },
            ));
        return Diagnosis::Differs(format!(
            "the right matches, but distance {j} of list {i} is {}, the reference's is {} (DMatch.distance, a float32)",
            py_float(g.distance),
            py_f32(w.distance)
        ));
    }
    let le = |t: f64| t.next_up();
    let alt = |s2: Strategy| match_all(&s2, prev, cur).is_ok_and(|v| equal(&v));
    match *s {
        Strategy::Dt(t) => {
            if alt(Strategy::Dt(le(t))) {
                return Diagnosis::Mistake(Mistake::LessOrEqual);
            }
            let k = got.iter().map(Vec::len).max().unwrap_or(0);
            if want.iter().any(|r| r.len() > k) {
                let cut: Vec<Vec<DMatch>> = want.iter().map(|r| r[..r.len().min(k)].to_vec()).collect();
                if equal(&cut) {
                    return if k == 100 {
                        Diagnosis::Mistake(Mistake::TruncatedK100)
                    } else {
                        Diagnosis::TruncatedK(k)
                    };
                }
            }
        }
        Strategy::Nn(t) => {
            if let Some(t) = t {
                if alt(Strategy::Nn(Some(le(t)))) {
                    return Diagnosis::Mistake(Mistake::LessOrEqual);
                }
                if alt(Strategy::Nn(None)) {
                    return Diagnosis::NnIgnoresThreshold;
                }
            } else if got.iter().all(Vec::is_empty) {
                return Diagnosis::NnNoneKeepsNothing;
            }
            let two: Vec<Vec<DMatch>> = knn_match(&prev.descriptors, &cur.descriptors, 2)
                .into_iter()
                .map(|r| r.into_iter().filter(|m| t.is_none_or(|t| (m.distance as f64) < t)).collect())
                .collect();
            if equal(&two) {
                return Diagnosis::Mistake(Mistake::NnMoreThanOne);
            }
        }
        Strategy::Nndr(t) => {
            let two = knn_match(&prev.descriptors, &cur.descriptors, 2);
            let keep = |rule: &dyn Fn(f64, f64) -> bool| -> Vec<Vec<DMatch>> {
                two.iter()
                    .map(|r| match r.as_slice() {
                        [m, n] if rule(m.distance as f64, n.distance as f64) => vec![*m],
                        _ => Vec::new(),
                    })
                    .collect()
            };
            if equal(&keep(&|d1, d2| d1 <= t * d2)) {
                return Diagnosis::Mistake(Mistake::LessOrEqual);
            }
            // The ratio turned round in any of the ways students write it.
            let inverted: [&dyn Fn(f64, f64) -> bool; 4] =
                [&|d1, d2| d2 < t * d1, &|d1, d2| t * d1 < d2, &|d1, d2| d1 > t * d2, &|d1, d2| d2 / d1 < t];
            if inverted.iter().any(|rule| equal(&keep(rule))) {
                return Diagnosis::Mistake(Mistake::RatioInverted);
            }
            if equal(&keep(&|d1, d2| d1 / d2 < t)) {
                return Diagnosis::RatioDivision;
            }
        }
    }
    if swapped() {
        return Diagnosis::Mistake(Mistake::WrongFrameOrder);
    }
    let sorted = |r: &[DMatch]| {
        let mut v: Vec<(i64, i64, u64)> =
            r.iter().map(|m| (m.query_idx as i64, m.train_idx as i64, (m.distance as f64).to_bits())).collect();
        v.sort_unstable();
        v
    };
    let sorted_got = |r: &[Got]| {
        let mut v: Vec<(i64, i64, u64)> = r.iter().map(|g| (g.query, g.train, g.distance.to_bits())).collect();
        v.sort_unstable();
        v
    };
    if want.iter().zip(got).all(|(w, g)| sorted(w) == sorted_got(g)) {
        return Diagnosis::Order;
    }
    let i = first_difference(want, got).unwrap_or(0);
    let (w, g) = (&want[i], &got[i]);
    let extra = g.iter().filter(|g| !w.iter().any(|w| g.equals(w))).count();
    let missing = w.iter().filter(|w| !g.iter().any(|g| g.equals(w))).count();
    Diagnosis::Differs(format!(
        "list {i} differs from the reference's first: {missing} of its {} matches missing, {extra} not in it",
        w.len()
    ))
}

/// What is wrong with the shape of matching_info's value, if anything.
fn info_shape_problem(v: &Json) -> Option<String> {
    let Some(parts) = v.as_arr() else {
        return Some(format!("it returned a {}", v.py_type()));
    };
    if parts.len() != 3 {
        return Some(format!("it returned a sequence of {} items, not 3", parts.len()));
    }
    let is_point = |p: &Json| p.as_arr().is_some_and(|p| p.len() == 2 && p.iter().all(|c| c.as_f64().is_some()));
    if !is_point(&parts[0]) {
        return Some(format!("its first item {} is not a point (x, y)", shorten(&parts[0].py_repr(), 60)));
    }
    match parts[1].as_arr() {
        Some(ps) if ps.iter().all(is_point) => {}
        _ => return Some(format!("its second item {} is not a list of points", shorten(&parts[1].py_repr(), 60))),
    }
    match parts[2].as_arr() {
        Some(ds) if ds.iter().all(|d| d.as_f64().is_some()) => None,
        _ => Some(format!("its third item {} is not a list of distances", shorten(&parts[2].py_repr(), 60))),
    }
}

/// Python's `round()` of a coordinate: halves to even.
fn py_round(v: f32) -> i64 {
    (v as f64).round_ties_even() as i64
}

/// Why matching_info's tuple differs from the reference's.
fn diagnose_info(matches: &[DMatch], info: &MatchInfo, got: &Json, prev: &Features, cur: &Features) -> Diagnosis {
    if matches.is_empty() {
        return Diagnosis::EmptyCase(None);
    }
    let same = |alt: &Json| alt.py_eq(got);
    let q = prev.keypoints.get(matches[0].query_idx);
    let pts: Vec<_> = matches.iter().filter_map(|m| cur.keypoints.get(m.train_idx)).collect();
    let build = |f: &dyn Fn(f32) -> Json, swap: bool| -> Json {
        let pt = |x: f32, y: f32| {
            let (a, b) = if swap { (y, x) } else { (x, y) };
            Json::Arr(vec![f(a), f(b)])
        };
        Json::Arr(vec![
            q.map_or(Json::Arr(vec![Json::Int(0), Json::Int(0)]), |k| pt(k.x, k.y)),
            Json::Arr(pts.iter().map(|k| pt(k.x, k.y)).collect()),
            Json::Arr(info.distances.iter().map(|&d| Json::Float(d as f64)).collect()),
        ])
    };
    if same(&build(&|v| Json::Int(py_round(v) as i128), false)) {
        return Diagnosis::Rounded;
    }
    if same(&build(&|v| Json::Float(v as f64), false)) {
        return Diagnosis::FloatCoordinates;
    }
    if same(&build(&|v| Json::Int(siftlab_core::matching::py_int(v) as i128), true)) {
        return Diagnosis::SwappedXY;
    }
    // Query from kp2 and matches from kp1.
    let swapped = Json::Arr(vec![
        info_json(&matching_info(&cur.keypoints, &prev.keypoints, matches))
            .as_arr()
            .map_or(Json::Null, |a| a[0].clone()),
        info_json(&MatchInfo {
            query: (0, 0),
            points: matches
                .iter()
                .filter_map(|m| prev.keypoints.get(m.train_idx))
                .map(|k| (siftlab_core::matching::py_int(k.x), siftlab_core::matching::py_int(k.y)))
                .collect(),
            distances: Vec::new(),
        })
        .as_arr()
        .map_or(Json::Null, |a| a[1].clone()),
        Json::Arr(info.distances.iter().map(|&d| Json::Float(d as f64)).collect()),
    ]);
    if same(&swapped) {
        return Diagnosis::Mistake(Mistake::WrongFrameOrder);
    }
    let parts = got.as_arr().unwrap_or(&[]);
    let want = info_json(info);
    let want = want.as_arr().unwrap_or(&[]);
    if parts.len() == 3 && want.len() == 3 && parts[0].py_eq(&want[0]) && parts[1].py_eq(&want[1]) {
        let f64s: Vec<Json> = matches
            .iter()
            .filter_map(|m| {
                Some(Json::Float(distance_f64(prev.descriptors.get(m.query_idx)?, cur.descriptors.get(m.train_idx)?)))
            })
            .collect();
        if parts[2].py_eq(&Json::Arr(f64s)) {
            return Diagnosis::NotFloat32;
        }
        // Recomputed in float64 some other way (e.g. sqrt(round(d ** 2))):
        // each within a few float32 steps of the DMatch value, some not equal.
        let near = parts[2].as_arr().is_some_and(|g| {
            g.len() == info.distances.len()
                && g.iter().zip(&info.distances).all(|(g, &d)| {
                    g.as_f64().is_some_and(|g| (g - d as f64).abs() <= 4.0 * f64::from(f32::EPSILON) * d as f64)
                })
        });
        if near {
            return Diagnosis::NotFloat32;
        }
        return Diagnosis::Differs("the points are right, the distances are not the DMatch distances".into());
    }
    if parts.len() == 3 && want.len() == 3 && !parts[0].py_eq(&want[0]) {
        return Diagnosis::Differs(format!(
            "the query point is {}, the reference's {} (kp1[matches[0].queryIdx].pt, truncated with int())",
            parts[0].py_repr(),
            want[0].py_repr()
        ));
    }
    Diagnosis::Differs("the points differ from the reference's (kp2[m.trainIdx].pt of each match, truncated)".into())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::reference::reference;
    use siftlab_core::json::parse;
    use siftlab_core::sift::KeyPoint;

    /// A pair whose distances take few values (ties and thresholds hit exactly).
    fn pair() -> (Features, Features) {
        let mut s = 99u32;
        let mut f = |n: usize| {
            let descriptors: Vec<[u8; 128]> = (0..n)
                .map(|_| {
                    std::array::from_fn(|_| {
                        s = s.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
                        [0u8, 3, 4, 10][(s >> 30) as usize]
                    })
                })
                .collect();
            let keypoints = (0..n)
                .map(|i| KeyPoint {
                    x: 10.5 + i as f32 * 3.25,
                    y: 200.75 - i as f32 * 1.5,
                    size: 2.0,
                    angle: 0.0,
                    response: 0.0,
                    octave: 0,
                })
                .collect();
            Features { keypoints, descriptors }
        };
        (f(40), f(35))
    }

    fn reply_of(lists: &[Vec<DMatch>], dist: impl Fn(&DMatch) -> String) -> Reply {
        let rows: Vec<String> = lists
            .iter()
            .map(|r| {
                let ms: Vec<String> =
                    r.iter().map(|m| format!("[{}, {}, {}]", m.query_idx, m.train_idx, dist(m))).collect();
                format!("[{}]", ms.join(", "))
            })
            .collect();
        Reply::Ok { value: parse(&format!("[{}]", rows.join(", "))).unwrap() }
    }

    fn f32_text(m: &DMatch) -> String {
        py_f32(m.distance)
    }

    fn verdict(case: Case, lists: &[Vec<DMatch>], p: &(Features, Features)) -> (Status, Option<String>) {
        let e = reference(&case, &p.0, &p.1).unwrap();
        let r = judge(&case, &e, &reply_of(lists, f32_text), &p.0, &p.1, 0.0);
        (r.status, r.diagnosis.map(|d| d.code().to_string()))
    }

    #[test]
    fn whole_results_are_diagnosed() {
        let p = pair();
        let all = |s: Strategy| match_all(&s, &p.0, &p.1).unwrap();
        // A threshold every distance is compared with exactly: the median distance.
        let mut ds: Vec<f32> = all(Strategy::Dt(1e9)).into_iter().flatten().map(|m| m.distance).collect();
        ds.sort_by(f32::total_cmp);
        let t = ds[ds.len() / 2] as f64;
        let dt = Case::Dt { frame: 1, threshold: t };
        assert_eq!(verdict(dt, &all(Strategy::Dt(t)), &p), (Status::Correct, None));
        let code = |c: Case, l: &[Vec<DMatch>]| verdict(c, l, &p).1.unwrap_or_else(|| panic!("{c:?} judged correct"));
        assert_eq!(code(dt, &all(Strategy::Dt(t.next_up()))), "less_or_equal");
        let cut: Vec<Vec<DMatch>> = all(Strategy::Dt(t)).into_iter().map(|r| r.into_iter().take(3).collect()).collect();
        assert_eq!(code(dt, &cut), "k_too_small");
        let mut by_train = all(Strategy::Dt(t));
        by_train.iter_mut().for_each(|r| r.sort_by_key(|m| std::cmp::Reverse(m.train_idx)));
        assert_eq!(code(dt, &by_train), "wrong_order");
        let swapped = match_all(&Strategy::Dt(t), &p.1, &p.0).unwrap();
        assert_eq!(code(dt, &swapped), "frames_swapped");
        assert_eq!(code(dt, &all(Strategy::Dt(t))[..20]), "wrong_length");

        // A threshold equal to a nearest distance.
        let t1 = all(Strategy::Nn(None))[0][0].distance as f64;
        let nn = Case::Nn { frame: 1, threshold: Some(t1) };
        assert_eq!(code(nn, &all(Strategy::Nn(None))), "nn_ignores_threshold");
        assert_eq!(code(nn, &all(Strategy::Nn(Some(t1.next_up())))), "less_or_equal");
        let nn_none = Case::Nn { frame: 1, threshold: None };
        assert_eq!(code(nn_none, &vec![Vec::new(); 40]), "nn_ignores_none");
        let two = knn_match(&p.0.descriptors, &p.1.descriptors, 2);
        assert_eq!(code(nn_none, &two), "nn_more_than_one");
        let some: Vec<Vec<DMatch>> = all(Strategy::Nn(Some(t1))).into_iter().filter(|r| !r.is_empty()).collect();
        assert!(some.len() < 40);
        assert_eq!(code(nn, &some), "empty_lists_dropped");

        let nndr = Case::Nndr { frame: 1, threshold: 1.0 };
        let inverted: Vec<Vec<DMatch>> =
            two.iter().map(|r| if r[1].distance < r[0].distance { vec![r[0]] } else { vec![] }).collect();
        assert_eq!(code(nndr, &inverted), "ratio_inverted");
        // f64 distances for the right pairs.
        let e = reference(&dt, &p.0, &p.1).unwrap();
        let Expected::Matches(want) = &e else { panic!() };
        let r = judge(
            &dt,
            &e,
            &reply_of(want, |m| py_float(distance_f64(&p.0.descriptors[m.query_idx], &p.1.descriptors[m.train_idx]))),
            &p.0,
            &p.1,
            0.0,
        );
        // Distances that are squares' roots of perfect squares are equal in f32 and f64.
        if want
            .iter()
            .flatten()
            .any(|m| m.distance as f64 != distance_f64(&p.0.descriptors[m.query_idx], &p.1.descriptors[m.train_idx]))
        {
            assert_eq!(r.diagnosis.unwrap().code(), "not_float32");
        }
        // A type problem is an error.
        let r = judge(&dt, &e, &Reply::Ok { value: parse("[1, 2]").unwrap() }, &p.0, &p.1, 0.0);
        assert_eq!((r.status, r.diagnosis.unwrap().code()), (Status::Error, "wrong_type"));
        let r = judge(
            &nn_none,
            &reference(&nn_none, &p.0, &p.1).unwrap(),
            &Reply::Error { message: "TypeError: '<' not supported".into(), kind: ErrorKind::Runtime },
            &p.0,
            &p.1,
            0.0,
        );
        assert_eq!(r.status, Status::Error);
        assert!(r.diagnosis.unwrap().describe().contains("threshold None"));
    }

    #[test]
    fn matching_info_mistakes_are_diagnosed() {
        let p = pair();
        let case = Case::Info { frame: 1, strategy: Strategy::Dt(1e9), feature: 3 };
        let e = reference(&case, &p.0, &p.1).unwrap();
        let Expected::Info { matches, info } = &e else { panic!() };
        let judge_v = |text: &str| {
            let r = judge(&case, &e, &Reply::Ok { value: typed(text) }, &p.0, &p.1, 0.0);
            (r.status, r.diagnosis.map(|d| d.code()))
        };
        assert_eq!(judge_v(&info_json(info).to_json()), (Status::Correct, None));
        // Python's ==, applied here: points as lists are not tuples.
        let lists = Reply::Ok { value: typed_with(&info_json(info), 0, true) };
        let r = judge(&case, &e, &lists, &p.0, &p.1, 0.0);
        assert_eq!((r.status, r.diagnosis.map(|d| d.code())), (Status::Wrong, Some("wrong_types_inside")));
        // An object whose __eq__ always says True arrives opaque: wrong, never correct.
        let forged = parse(r#"{"tuple": [{"opaque": "Always"}, {"list": []}, {"list": []}]}"#).unwrap();
        let r = judge(&case, &e, &Reply::Ok { value: forged }, &p.0, &p.1, 0.0);
        assert_eq!(r.status, Status::Error);
        let q = p.0.keypoints[3];
        let pts = |f: &dyn Fn(f32) -> String, swap: bool| -> String {
            let pt =
                |x: f32, y: f32| if swap { format!("[{}, {}]", f(y), f(x)) } else { format!("[{}, {}]", f(x), f(y)) };
            let ps: Vec<String> = matches.iter().map(|m| p.1.keypoints[m.train_idx]).map(|k| pt(k.x, k.y)).collect();
            let ds: Vec<String> = info.distances.iter().map(|d| py_f32(*d)).collect();
            format!("[{}, [{}], [{}]]", pt(q.x, q.y), ps.join(", "), ds.join(", "))
        };
        assert_eq!(judge_v(&pts(&|v| py_round(v).to_string(), false)).1, Some("rounded"));
        assert_eq!(judge_v(&pts(&|v| py_f32(v), false)).1, Some("float_coordinates"));
        assert_eq!(judge_v(&pts(&|v| (v as i64).to_string(), true)).1, Some("swapped_xy"));
        assert_eq!(judge_v("[[0, 0], []]"), (Status::Error, Some("wrong_type")));
        assert_eq!(judge_v("null"), (Status::Error, Some("wrong_type")));
        assert_eq!(judge_v("[[0, 0], [[1]], [1.5]]"), (Status::Wrong, Some("wrong_shape")));
        let empty = Case::Info { frame: 1, strategy: Strategy::Dt(0.0), feature: 3 };
        let e0 = reference(&empty, &p.0, &p.1).unwrap();
        assert!(e0.info_matches().is_empty());
        let r = judge(&empty, &e0, &Reply::Ok { value: typed("[[0, 0], [], []]") }, &p.0, &p.1, 0.0);
        assert_eq!(r.status, Status::Correct);
        let r = judge(
            &empty,
            &e0,
            &Reply::Error { message: "IndexError: list index out of range".into(), kind: ErrorKind::Runtime },
            &p.0,
            &p.1,
            0.0,
        );
        assert_eq!((r.status, r.diagnosis.unwrap().code()), (Status::Error, "empty_case"));
        let r = judge(&empty, &e0, &Reply::Ok { value: typed("[null, [], []]") }, &p.0, &p.1, 0.0);
        assert_eq!(r.diagnosis.unwrap().code(), "wrong_type");
        let r = judge(&empty, &e0, &Reply::Ok { value: typed("[[1, 0], [], []]") }, &p.0, &p.1, 0.0);
        assert_eq!((r.status, r.diagnosis.unwrap().code()), (Status::Wrong, "empty_case"));
    }

    /// matching_info's value as the harness encodes it, from plain JSON
    /// `[p, [p, …], [d, …]]`: the whole and `p` tuples, the two others lists.
    fn typed(text: &str) -> Json {
        typed_with(&parse(text).unwrap(), 0, false)
    }

    fn typed_with(v: &Json, depth: usize, points_as_lists: bool) -> Json {
        let tag = |t: &str, items: &[Json], d: usize| {
            Json::Obj(vec![(
                t.to_string(),
                Json::Arr(items.iter().map(|x| typed_with(x, d, points_as_lists)).collect()),
            )])
        };
        match (v, depth) {
            (Json::Arr(a), 0) if a.len() == 3 => Json::Obj(vec![(
                "tuple".into(),
                Json::Arr(vec![
                    typed_with(&a[0], 3, points_as_lists),
                    tag("list", a[1].as_arr().unwrap_or(&[]), 2),
                    tag("list", a[2].as_arr().unwrap_or(&[]), 3),
                ]),
            )]),
            (Json::Arr(a), 0) => tag("tuple", a, 1),
            (Json::Arr(a), 2) if points_as_lists => tag("list", a, 3),
            (Json::Arr(a), _) => tag("tuple", a, 3),
            (v, _) => v.clone(),
        }
    }
}
