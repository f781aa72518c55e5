//! Whole results and matching_info values judged and diagnosed, on a small
//! pair whose distances take few values.

use super::info::py_round;
use super::matches::distance_f64;
use super::{judge, Status};
use crate::cases::Case;
use crate::protocol::{ErrorKind, Reply};
use crate::reference::{info_json, reference, Expected};
use siftlab_core::json::{parse, Json};
use siftlab_core::matching::{knn_match, match_all, DMatch, Strategy};
use siftlab_core::pyfmt::{py_f32, py_float};
use siftlab_core::sift::{Features, KeyPoint};

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
        let pt = |x: f32, y: f32| if swap { format!("[{}, {}]", f(y), f(x)) } else { format!("[{}, {}]", f(x), f(y)) };
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
        Json::Obj(vec![(t.to_string(), Json::Arr(items.iter().map(|x| typed_with(x, d, points_as_lists)).collect()))])
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
