//! Why dt / nn / nndr's lists differ from the reference's: the frames
//! swapped, empty lists dropped, float64 distances, `<=` for `<`, k too
//! small, the threshold ignored, the ratio inverted or divided, another
//! order, or where they first differ.

use super::diagnosis::Diagnosis;
use crate::reference::{first_difference, matches_equal, Got};
use siftlab_core::matching::{knn_match, match_all, DMatch, Mistake, Strategy};
use siftlab_core::pyfmt::{py_f32, py_float};
use siftlab_core::sift::Features;

/// The L2 distance in float64: `sqrt` of the exact integer sum.
pub(super) fn distance_f64(a: &[u8; 128], b: &[u8; 128]) -> f64 {
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
pub(super) fn diagnose_matches(
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
