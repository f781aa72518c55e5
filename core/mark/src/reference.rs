//! The reference value of a case (siftlab's engine, equal to OpenCV 4.8's)
//! and the comparison with what the student's function returned.

use crate::b64::unbase64;
use crate::cases::{Case, NUM_FEATURES};
use siftlab_core::error::{Error, Result};
use siftlab_core::json::Json;
use siftlab_core::matching::{match_all, match_feature, matching_info, DMatch, MatchInfo};
use siftlab_core::pyfmt::{py_f32, py_float};
use siftlab_core::sift::Features;

/// What the reference implementation returns for a case.
#[derive(Clone, Debug, PartialEq)]
pub enum Expected {
    /// dt / nn / nndr: one list per query descriptor of des1.
    Matches(Vec<Vec<DMatch>>),
    /// matching_info: the matches it is called with and its tuple.
    Info { matches: Vec<DMatch>, info: MatchInfo },
}

impl Expected {
    /// The matches a matching_info call is given (empty for the others).
    pub fn info_matches(&self) -> &[DMatch] {
        match self {
            Expected::Info { matches, .. } => matches,
            Expected::Matches(_) => &[],
        }
    }
}

/// The reference value of `case` on its pair (`prev` = frame FRAME_ID-1).
pub fn reference(case: &Case, prev: &Features, cur: &Features) -> Result<Expected> {
    match *case {
        Case::Info { strategy, feature, .. } => {
            if feature >= prev.keypoints.len() {
                return Err(Error::InvalidArgument(format!(
                    "frame {} has {} keypoints, fewer than the {NUM_FEATURES} feature ids the marker draws from: mark on \
                     frames with a full set of keypoints",
                    case.frame().saturating_sub(1),
                    prev.keypoints.len()
                )));
            }
            let matches = match_feature(&strategy, prev, cur, feature)?;
            let info = matching_info(&prev.keypoints, &cur.keypoints, &matches);
            Ok(Expected::Info { matches, info })
        }
        _ => Ok(Expected::Matches(match_all(&case.strategy(), prev, cur)?)),
    }
}

/// One returned match: queryIdx, trainIdx and `float(distance)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Got {
    pub query: i64,
    pub train: i64,
    pub distance: f64,
}

impl Got {
    /// The same match as the reference's, its distance the f32 exactly.
    pub fn equals(&self, m: &DMatch) -> bool {
        self.query == m.query_idx as i64 && self.train == m.train_idx as i64 && self.distance == m.distance as f64
    }
}

/// The harness's lists of `[q, t, d]`, or its compact form
/// `{"n": [len per query], "q", "t": B64 int32, "d": B64 float32}` (little
/// endian), or a message saying how the value is neither.
pub fn returned_matches(v: &Json) -> std::result::Result<Vec<Vec<Got>>, String> {
    if let Json::Obj(_) = v {
        return compact_matches(v);
    }
    let outer = v.as_arr().ok_or_else(|| format!("the value is a {}, not a list of lists", v.py_type()))?;
    let mut out = Vec::with_capacity(outer.len());
    for (i, row) in outer.iter().enumerate() {
        let row = row.as_arr().ok_or_else(|| format!("item {i} is a {}, not a list", row.py_type()))?;
        let mut r = Vec::with_capacity(row.len());
        for (j, m) in row.iter().enumerate() {
            let bad = || format!("item {j} of list {i} is not a DMatch");
            let m = m.as_arr().ok_or_else(bad)?;
            let (Some(q), Some(t), Some(d)) =
                (m.first().and_then(Json::as_i64), m.get(1).and_then(Json::as_i64), m.get(2).and_then(number))
            else {
                return Err(bad());
            };
            if m.len() != 3 {
                return Err(bad());
            }
            r.push(Got { query: q, train: t, distance: d });
        }
        out.push(r);
    }
    Ok(out)
}

/// A number, or the harness's text for a non-finite one ("inf", "-inf", "nan").
fn number(v: &Json) -> Option<f64> {
    match v {
        Json::Str(s) => match s.as_str() {
            "inf" => Some(f64::INFINITY),
            "-inf" => Some(f64::NEG_INFINITY),
            "nan" => Some(f64::NAN),
            _ => None,
        },
        _ => v.as_f64(),
    }
}

fn compact_matches(v: &Json) -> std::result::Result<Vec<Vec<Got>>, String> {
    let bad = |what: &str| format!("the harness's compact lists are malformed ({what})");
    let n: Vec<usize> = v
        .get("n")
        .and_then(Json::as_arr)
        .ok_or_else(|| bad("no \"n\""))?
        .iter()
        .map(|x| x.as_i64().and_then(|x| usize::try_from(x).ok()))
        .collect::<Option<_>>()
        .ok_or_else(|| bad("\"n\""))?;
    let words = |key: &str| -> std::result::Result<Vec<[u8; 4]>, String> {
        let b = v.get(key).and_then(Json::as_str).and_then(unbase64).ok_or_else(|| bad(key))?;
        if b.len() % 4 != 0 {
            return Err(bad(key));
        }
        Ok(b.as_chunks::<4>().0.to_vec())
    };
    let (q, t, d) = (words("q")?, words("t")?, words("d")?);
    // The lengths are the student's: summed with a check (they may add up
    // past usize::MAX and wrap to the words' count), each row then taken
    // from what is left, so no index can leave the words.
    let total = n.iter().try_fold(0usize, |sum, &len| sum.checked_add(len)).ok_or_else(|| bad("lengths"))?;
    if q.len() != total || t.len() != total || d.len() != total {
        return Err(bad("lengths"));
    }
    let mut rows = Vec::with_capacity(n.len());
    let mut rest = q.iter().zip(&t).zip(&d);
    for &len in &n {
        let row: Vec<Got> = rest
            .by_ref()
            .take(len)
            .map(|((q, t), d)| Got {
                query: i32::from_le_bytes(*q) as i64,
                train: i32::from_le_bytes(*t) as i64,
                distance: f32::from_le_bytes(*d) as f64,
            })
            .collect();
        if row.len() != len {
            return Err(bad("lengths"));
        }
        rows.push(row);
    }
    Ok(rows)
}

/// Every list equal, in order: each DMatch's queryIdx, trainIdx and its
/// distance equal to the reference's f32.
pub fn matches_equal(expected: &[Vec<DMatch>], got: &[Vec<Got>]) -> bool {
    expected.len() == got.len()
        && expected.iter().zip(got).all(|(e, g)| e.len() == g.len() && e.iter().zip(g).all(|(e, g)| g.equals(e)))
}

/// The first query whose list differs (`None` when all compared lists are
/// equal; with different lengths, the first index past the shorter).
pub fn first_difference(expected: &[Vec<DMatch>], got: &[Vec<Got>]) -> Option<usize> {
    let common = expected.len().min(got.len());
    (0..common)
        .find(|&i| expected[i].len() != got[i].len() || !expected[i].iter().zip(&got[i]).all(|(e, g)| g.equals(e)))
        .or((expected.len() != got.len()).then_some(common))
}

/// matching_info's tuple as the JSON the harness sends for it.
pub fn info_json(info: &MatchInfo) -> Json {
    let pt = |(x, y): (i64, i64)| Json::Arr(vec![Json::Int(x as i128), Json::Int(y as i128)]);
    Json::Arr(vec![
        pt(info.query),
        Json::Arr(info.points.iter().copied().map(pt).collect()),
        Json::Arr(info.distances.iter().map(|&d| Json::Float(d as f64)).collect()),
    ])
}

/// matching_info's returned value equal to the reference tuple, as Python's
/// `==` compares them (ints exactly, floats exactly; the JSON does not tell
/// tuples from lists).
pub fn info_equal(info: &MatchInfo, got: &Json) -> bool {
    info_json(info).py_eq(got)
}

/// Text longer than `max` characters cut, with how much was left out.
pub fn shorten(s: &str, max: usize) -> String {
    let n = s.chars().count();
    if n <= max {
        return s.to_string();
    }
    let kept: String = s.chars().take(max).collect();
    format!("{kept} … ({} more characters)", n - max)
}

/// A list of matches as Python shows `(queryIdx, trainIdx, distance)`
/// triples: at most `max` of them from `from` on, with how many are left
/// out before and after.
fn list_text<T>(items: &[T], from: usize, max: usize, one: impl Fn(&T) -> String) -> String {
    let from = from.min(items.len());
    let mut s = String::from("[");
    if from > 0 {
        s.push_str(&format!("… {from} before, "));
    }
    for (i, m) in items[from..].iter().take(max).enumerate() {
        if i > 0 {
            s.push_str(", ");
        }
        s.push_str(&one(m));
    }
    let after = items.len() - from - (items.len() - from).min(max);
    if after > 0 {
        s.push_str(&format!(", … {after} more"));
    }
    s.push(']');
    s
}

const SHOWN_MATCHES: usize = 6;

fn dmatch_text(m: &DMatch) -> String {
    format!("({}, {}, {})", m.query_idx, m.train_idx, py_f32(m.distance))
}

fn got_text(g: &Got) -> String {
    format!("({}, {}, {})", g.query, g.train, py_float(g.distance))
}

/// Where the returned lists first differ: the list, and the first position
/// in it that differs (or the shorter one's length).
pub fn difference_at(expected: &[Vec<DMatch>], got: &[Vec<Got>]) -> Option<(usize, usize)> {
    let i = first_difference(expected, got)?;
    let (e, g) = (expected.get(i).map_or(&[][..], Vec::as_slice), got.get(i).map_or(&[][..], Vec::as_slice));
    let j = e.iter().zip(g).position(|(e, g)| !g.equals(e)).unwrap_or(e.len().min(g.len()));
    Some((i, j))
}

/// The reference's lists summed up, with list `at.0` from just before
/// position `at.1`: `1500 lists, 2301 matches; list 17: [… 3 before, (17, 512, 61.4…), …]`.
pub fn expected_text(expected: &[Vec<DMatch>], at: Option<(usize, usize)>) -> String {
    let n: usize = expected.iter().map(Vec::len).sum();
    let mut s = format!("{} lists, {n} matches", expected.len());
    if let Some((i, j)) = at {
        if let Some(row) = expected.get(i) {
            s.push_str(&format!("; list {i}: {}", list_text(row, j.saturating_sub(1), SHOWN_MATCHES, dmatch_text)));
        }
    }
    s
}

/// The returned lists summed up like [`expected_text`].
pub fn got_lists_text(got: &[Vec<Got>], at: Option<(usize, usize)>) -> String {
    let n: usize = got.iter().map(Vec::len).sum();
    let mut s = format!("{} lists, {n} matches", got.len());
    if let Some((i, j)) = at {
        if let Some(row) = got.get(i) {
            s.push_str(&format!("; list {i}: {}", list_text(row, j.saturating_sub(1), SHOWN_MATCHES, got_text)));
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use siftlab_core::json::parse;
    use siftlab_core::matching::Strategy;
    use siftlab_core::sift::KeyPoint;

    fn m(q: usize, t: usize, d: f32) -> DMatch {
        DMatch { query_idx: q, train_idx: t, distance: d }
    }

    #[test]
    fn matches_compare_exactly() {
        let e = vec![vec![m(0, 3, 61.4), m(0, 1, 70.0)], vec![]];
        let g = returned_matches(&parse("[[[0, 3, 61.400001525878906], [0, 1, 70.0]], []]").unwrap()).unwrap();
        assert!(matches_equal(&e, &g));
        assert_eq!(first_difference(&e, &g), None);
        // 61.4 as an f64 is not the f32 61.4.
        let g = returned_matches(&parse("[[[0, 3, 61.4], [0, 1, 70.0]], []]").unwrap()).unwrap();
        assert!(!matches_equal(&e, &g));
        assert_eq!(first_difference(&e, &g), Some(0));
        let g = returned_matches(&parse("[[[0, 3, 61.400001525878906], [0, 1, 70.0]]]").unwrap()).unwrap();
        assert_eq!(first_difference(&e, &g), Some(1));
        assert_eq!(returned_matches(&parse("[[[0, 3]]]").unwrap()).unwrap_err(), "item 0 of list 0 is not a DMatch");
        assert_eq!(returned_matches(&parse("[1]").unwrap()).unwrap_err(), "item 0 is a int, not a list");
        // The compact form: q, t as int32 and d as float32, little endian.
        let le = |v: &[u32]| crate::b64::base64(&v.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>());
        let compact = format!(
            r#"{{"n": [2, 0], "q": "{}", "t": "{}", "d": "{}"}}"#,
            le(&[0, 0]),
            le(&[3, 1]),
            le(&[61.4f32.to_bits(), 70f32.to_bits()])
        );
        let g = returned_matches(&parse(&compact).unwrap()).unwrap();
        assert!(matches_equal(&e, &g));
        assert!(returned_matches(&parse(r#"{"n": [3], "q": "", "t": "", "d": ""}"#).unwrap()).is_err());
        // Lengths that wrap when summed (2 × (2^63 - 1) + 3 = 1 as a u64,
        // the words' count): refused, never indexed; lengths that are no
        // usize (negative, past i64, not whole) likewise.
        let one = format!(r#""q": "{0}", "t": "{0}", "d": "{0}""#, le(&[0]));
        for (n, why) in [
            ("[9223372036854775807, 9223372036854775807, 3]", "lengths"),
            ("[9223372036854775807, 9223372036854775807, 2, 0]", "lengths"),
            ("[0, 2, 0]", "lengths"),
            ("[18446744073709551617]", "\"n\""),
            ("[-1, 2]", "\"n\""),
            ("[1e30]", "\"n\""),
            ("[0.5, 0.5]", "\"n\""),
        ] {
            let v = parse(&format!(r#"{{"n": {n}, {one}}}"#)).unwrap();
            let want = format!("the harness's compact lists are malformed ({why})");
            assert_eq!(returned_matches(&v).unwrap_err(), want, "{n}");
        }
        assert_eq!(returned_matches(&parse(&format!(r#"{{"n": [0, 1, 0], {one}}}"#)).unwrap()).unwrap().len(), 3);
        assert_eq!(
            expected_text(&e, Some((0, 0))),
            "2 lists, 2 matches; list 0: [(0, 3, 61.400001525878906), (0, 1, 70.0)]"
        );
        let many: Vec<DMatch> = (0..9).map(|t| m(2, t, 1.0)).collect();
        assert!(list_text(&many, 0, 6, dmatch_text).ends_with("(2, 5, 1.0), … 3 more]"));
        assert_eq!(list_text(&many, 7, 6, dmatch_text), "[… 7 before, (2, 7, 1.0), (2, 8, 1.0)]");
        assert_eq!(
            list_text(&many, 2, 3, dmatch_text),
            "[… 2 before, (2, 2, 1.0), (2, 3, 1.0), (2, 4, 1.0), … 4 more]"
        );
        let g = returned_matches(&parse("[[[0, 3, 61.400001525878906]], []]").unwrap()).unwrap();
        assert_eq!(difference_at(&e, &g), Some((0, 1)));
        assert_eq!(got_lists_text(&g, Some((0, 1))), "2 lists, 1 matches; list 0: [(0, 3, 61.400001525878906)]");
    }

    #[test]
    fn info_compares_as_python() {
        let info = MatchInfo { query: (523, 181), points: vec![(517, 183)], distances: vec![61.4] };
        assert!(info_equal(&info, &parse("[[523, 181], [[517, 183]], [61.400001525878906]]").unwrap()));
        assert!(info_equal(&info, &parse("[[523.0, 181], [[517, 183]], [61.400001525878906]]").unwrap()));
        assert!(!info_equal(&info, &parse("[[523, 181], [[517, 183]], [61.4]]").unwrap()));
        assert!(!info_equal(&info, &parse("[[524, 181], [[517, 183]], [61.400001525878906]]").unwrap()));
        assert!(info_equal(&MatchInfo::default(), &parse("[[0, 0], [], []]").unwrap()));
        assert_eq!(shorten("abcdef", 3), "abc … (3 more characters)");
    }

    #[test]
    fn reference_checks_the_feature() {
        let kp = KeyPoint { x: 1.5, y: 2.5, size: 1.0, angle: 0.0, response: 0.0, octave: 0 };
        let f = Features { keypoints: vec![kp; 3], descriptors: vec![[0u8; 128], [1u8; 128], [9u8; 128]] };
        let c = Case::Info { frame: 1, strategy: Strategy::Nn(None), feature: 2 };
        let Expected::Info { matches, info } = reference(&c, &f, &f).unwrap() else { panic!() };
        assert_eq!(matches, vec![m(2, 2, 0.0)]);
        assert_eq!(info.query, (1, 2));
        let c = Case::Info { frame: 1, strategy: Strategy::Nn(None), feature: 3 };
        assert!(reference(&c, &f, &f).unwrap_err().to_string().contains("frame 0 has 3 keypoints"));
        let Expected::Matches(all) = reference(&Case::Dt { frame: 1, threshold: 12.0 }, &f, &f).unwrap() else {
            panic!()
        };
        assert_eq!(all[1], vec![m(1, 1, 0.0), m(1, 0, 11.313708)]);
    }
}
