//! Why matching_info's tuple differs from the reference's: not the shape
//! `((x, y), [(x, y), …], [d, …])`, the empty case, coordinates rounded,
//! left as floats or swapped, the frames swapped, float64 distances.

use super::diagnosis::Diagnosis;
use super::matches::distance_f64;
use crate::reference::{info_json, shorten};
use siftlab_core::json::Json;
use siftlab_core::matching::{matching_info, DMatch, MatchInfo, Mistake};
use siftlab_core::sift::Features;

/// What is wrong with the shape of matching_info's value, if anything.
pub(super) fn info_shape_problem(v: &Json) -> Option<String> {
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
pub(super) fn py_round(v: f32) -> i64 {
    (v as f64).round_ties_even() as i64
}

/// Why matching_info's tuple differs from the reference's.
pub(super) fn diagnose_info(
    matches: &[DMatch],
    info: &MatchInfo,
    got: &Json,
    prev: &Features,
    cur: &Features,
) -> Diagnosis {
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
