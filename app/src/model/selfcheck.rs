//! "Check my answer": compares a student's pasted `ret value:` with the core's
//! answer field by field, and names the likely mistake. The correct answer and
//! the answers typical mistakes give both come from the core
//! (`explain`, `mistaken_answers`); this module only reads and compares.

use crate::model::pylit::{self, Py};
use siftlab_core::matching::{MatchInfo, Mistake};
use siftlab_core::pyfmt::py_f32;

#[derive(Debug, Clone, PartialEq)]
pub struct FieldCheck {
    pub field: &'static str,
    pub ok: bool,
    pub note: String,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Diagnosis {
    /// The whole answer equals the lab's.
    pub correct: bool,
    pub fields: Vec<FieldCheck>,
    /// Mistakes whose answer is exactly what the student gave.
    pub likely: Vec<String>,
}

/// A student's tuple read as numbers: query, points, distances.
#[derive(Debug, Clone, PartialEq)]
struct Answer<'a> {
    query: Vec<&'a Py>,
    points: Vec<Vec<&'a Py>>,
    distances: Vec<&'a Py>,
}

fn read(v: &Py) -> Result<Answer<'_>, String> {
    let parts = v.items().ok_or("the answer is not a tuple: expected ((x, y), [(x, y), …], [d, …])")?;
    if parts.len() != 3 {
        return Err(format!(
            "the answer has {} parts; matching_info returns 3: ((x, y), [(x, y), …], [d, …])",
            parts.len()
        ));
    }
    let query: Vec<&Py> = parts[0].items().ok_or("the first part should be the query point (x, y)")?.iter().collect();
    let points = parts[1]
        .items()
        .ok_or("the second part should be a list of points [(x, y), …]")?
        .iter()
        .map(|p| p.items().map(|xy| xy.iter().collect::<Vec<_>>()).ok_or("every matched point should be a pair (x, y)"))
        .collect::<Result<Vec<_>, _>>()?;
    let distances: Vec<&Py> =
        parts[2].items().ok_or("the third part should be a list of distances [d, …]")?.iter().collect();
    Ok(Answer { query, points, distances })
}

fn is_int(v: &Py, want: i64) -> bool {
    matches!(v, Py::Int(i) if *i == want as i128)
}

fn point_eq(p: &[&Py], want: (i64, i64)) -> bool {
    p.len() == 2 && is_int(p[0], want.0) && is_int(p[1], want.1)
}

/// Same value as the f32 distance (any spelling that reads back to it).
fn dist_value_eq(v: &Py, want: f32) -> bool {
    v.number().is_some_and(|x| x as f32 == want)
}

/// Exactly how the lab prints it (Python float repr of the f32).
fn dist_exact(v: &Py, want: f32) -> bool {
    match v {
        Py::Float(x, text) => *x == want as f64 && *text == py_f32(want),
        // `105` is not how Python prints the float 105.0.
        _ => false,
    }
}

/// Whether the student's answer is this `MatchInfo`, value for value.
fn same(a: &Answer, m: &MatchInfo) -> bool {
    point_eq(&a.query, m.query)
        && list_eq(&a.points, &m.points, |p, w| point_eq(p, w))
        && list_eq(&a.distances, &m.distances, |d, w| dist_value_eq(d, w))
}

/// `got` is `want` element for element.
fn list_eq<G, W: Copy>(got: &[G], want: &[W], eq: impl Fn(&G, W) -> bool) -> bool {
    got.len() == want.len() && got.iter().zip(want).all(|(g, &w)| eq(g, w))
}

fn has_float_coords(p: &[&Py]) -> bool {
    p.iter().any(|v| matches!(v, Py::Float(..)))
}

fn describe_point(p: &[&Py]) -> String {
    let s: Vec<String> = p
        .iter()
        .map(|v| match v {
            Py::Int(i) => i.to_string(),
            Py::Float(_, t) => t.clone(),
            other => format!("{other:?}"),
        })
        .collect();
    format!("({})", s.join(", "))
}

fn check_query(a: &Answer, truth: &MatchInfo, query_float: Option<(f32, f32)>) -> FieldCheck {
    let want = truth.query;
    let field = "query point";
    if point_eq(&a.query, want) {
        return FieldCheck { field, ok: true, note: format!("({}, {}) ✓", want.0, want.1) };
    }
    let got = describe_point(&a.query);
    let nums: Vec<f64> = a.query.iter().filter_map(|v| v.number()).collect();
    let note = if a.query.len() != 2 || nums.len() != 2 {
        format!("{got} is not a point (x, y)")
    } else if truth.points.is_empty() && want == (0, 0) {
        format!(
            "{got}, but no match survives here, and then matching_info returns ((0, 0), [], []) — not the query's coordinates"
        )
    } else if nums == [0.0, 0.0] {
        format!("{got}: you returned the empty answer, but the lab finds {} match(es) here", truth.points.len())
    } else if has_float_coords(&a.query) && nums[0].trunc() as i64 == want.0 && nums[1].trunc() as i64 == want.1 {
        format!("{got} are float coordinates: matching_info truncates them with int() → ({}, {})", want.0, want.1)
    } else if query_float.is_some_and(|(x, y)| nums[0] == (x as f64).round() && nums[1] == (y as f64).round()) {
        format!("{got} is rounded; int() truncates toward zero → ({}, {})", want.0, want.1)
    } else if nums[0] as i64 == want.1 && nums[1] as i64 == want.0 {
        format!("{got} has x and y swapped: keypoint.pt is (x, y) → ({}, {})", want.0, want.1)
    } else {
        format!("{got}, expected ({}, {})", want.0, want.1)
    };
    FieldCheck { field, ok: false, note }
}

/// A list field's check: right when `got` is `want` element for element
/// (`eq`; the note counts the `noun`s), else with `mistake`'s note.
fn check_list<G, W: Copy>(
    field: &'static str,
    noun: &str,
    got: &[G],
    want: &[W],
    eq: impl Fn(&G, W) -> bool,
    mistake: impl FnOnce() -> String,
) -> FieldCheck {
    if list_eq(got, want, eq) {
        FieldCheck { field, ok: true, note: format!("{} {noun}(s) ✓", want.len()) }
    } else {
        FieldCheck { field, ok: false, note: mistake() }
    }
}

fn check_points(a: &Answer, truth: &MatchInfo) -> FieldCheck {
    let mistake = || points_mistake(a, &truth.points);
    check_list("matched points", "point", &a.points, &truth.points, |p, w| point_eq(p, w), mistake)
}

/// What is wrong with matched points that are not `want`.
fn points_mistake(a: &Answer, want: &[(i64, i64)]) -> String {
    if a.points.len() != want.len() {
        let mut n = format!("{} point(s), expected {}", a.points.len(), want.len());
        if a.points.len() == 100 && want.len() > 100 {
            n.push_str(" — exactly 100: knnMatch with k=100 truncates dt; ask for all neighbours");
        }
        n
    } else if a.points.iter().any(|p| has_float_coords(p)) {
        "the points are floats: matching_info truncates each with int()".to_string()
    } else {
        let mut got: Vec<(i128, i128)> = Vec::new();
        for p in &a.points {
            if let [Py::Int(x), Py::Int(y)] = p.as_slice() {
                got.push((*x, *y));
            }
        }
        let mut w: Vec<(i128, i128)> = want.iter().map(|&(x, y)| (x as i128, y as i128)).collect();
        got.sort_unstable();
        w.sort_unstable();
        if got == w {
            "the right points in the wrong order: matches are listed nearest first (ascending distance)".to_string()
        } else {
            let i = a.points.iter().zip(want).position(|(p, &w)| !point_eq(p, w)).unwrap_or(0);
            format!(
                "point {i} is {}, expected ({}, {})",
                a.points.get(i).map(|p| describe_point(p)).unwrap_or_default(),
                want[i].0,
                want[i].1
            )
        }
    }
}

fn check_distances(a: &Answer, truth: &MatchInfo) -> FieldCheck {
    let mistake = || distances_mistake(a, &truth.distances);
    check_list("distances", "distance", &a.distances, &truth.distances, |d, w| dist_exact(d, w), mistake)
}

/// What is wrong with distances that are not `want` as the lab prints them.
fn distances_mistake(a: &Answer, want: &[f32]) -> String {
    if a.distances.len() != want.len() {
        format!("{} distance(s), expected {}", a.distances.len(), want.len())
    } else if a.distances.iter().zip(want).all(|(d, &w)| dist_value_eq(d, w)) {
        let i = a.distances.iter().zip(want).position(|(d, &w)| !dist_exact(d, w)).unwrap_or(0);
        let shown = match a.distances[i] {
            Py::Float(_, t) => t.clone(),
            other => format!("{other:?}"),
        };
        format!(
            "the right values, printed differently: {shown} vs {} — the lab prints m.distance as a Python float (float(m.distance)), not as a numpy float32",
            py_f32(want[i])
        )
    } else if a
        .distances
        .iter()
        .zip(want)
        .all(|(d, &w)| d.number().is_some_and(|x| (x - (w as f64) * (w as f64)).abs() <= 0.5))
    {
        "these are squared distances: BFMatcher() uses NORM_L2, the square root of the sum of squares".to_string()
    } else if a
        .distances
        .iter()
        .zip(want)
        .all(|(d, &w)| matches!(d, Py::Int(i) if *i as f64 == (w as f64).trunc() || *i as f64 == (w as f64).round()))
    {
        "the distances were converted to int: keep them as floats".to_string()
    } else {
        let i = a.distances.iter().zip(want).position(|(d, &w)| !dist_value_eq(d, w)).unwrap_or(0);
        format!(
            "distance {i} is {}, expected {}",
            a.distances[i].number().map(|x| x.to_string()).unwrap_or_else(|| "not a number".into()),
            py_f32(want[i])
        )
    }
}

/// Diagnoses `answer` against the core's `truth` and its `mistakes` (from
/// `mistaken_answers`); `query_float` is the query keypoint's float pt.
pub fn diagnose(
    answer: &str,
    truth: &MatchInfo,
    mistakes: &[(Mistake, MatchInfo)],
    query_float: Option<(f32, f32)>,
) -> Diagnosis {
    let parsed = match pylit::parse(answer) {
        Ok(v) => v,
        Err(e) => {
            return Diagnosis {
                correct: false,
                fields: vec![FieldCheck {
                    field: "format",
                    ok: false,
                    note: format!("cannot read the answer ({e}); paste the tuple your code printed after `ret value:`"),
                }],
                likely: vec![],
            }
        }
    };
    let a = match read(&parsed) {
        Ok(a) => a,
        Err(e) => {
            return Diagnosis {
                correct: false,
                fields: vec![FieldCheck { field: "format", ok: false, note: e }],
                likely: vec![],
            }
        }
    };
    let fields = vec![check_query(&a, truth, query_float), check_points(&a, truth), check_distances(&a, truth)];
    let correct = fields.iter().all(|f| f.ok);
    let likely = if correct {
        vec![]
    } else {
        mistakes.iter().filter(|(_, m)| same(&a, m)).map(|(k, _)| k.describe().to_string()).collect()
    };
    Diagnosis { correct, fields, likely }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn truth() -> MatchInfo {
        MatchInfo { query: (523, 181), points: vec![(517, 183), (600, 12)], distances: vec![61.4, 105.0] }
    }

    #[test]
    fn the_lab_answer_is_correct() {
        let d = diagnose(
            "ret value: ((523, 181), [(517, 183), (600, 12)], [61.400001525878906, 105.0])",
            &truth(),
            &[],
            None,
        );
        assert!(d.correct, "{d:?}");
        assert!(d.fields.iter().all(|f| f.ok));
    }

    #[test]
    fn names_float_and_rounded_coordinates() {
        let d = diagnose("((523.7, 181.2), [(517, 183), (600, 12)], [61.400001525878906, 105.0])", &truth(), &[], None);
        assert!(!d.correct);
        assert!(d.fields[0].note.contains("float coordinates"), "{:?}", d.fields[0]);
        assert!(d.fields[1].ok && d.fields[2].ok);
        let d = diagnose(
            "((524, 181), [(517, 183), (600, 12)], [61.400001525878906, 105.0])",
            &truth(),
            &[],
            Some((523.7, 181.2)),
        );
        assert!(d.fields[0].note.contains("rounded"), "{:?}", d.fields[0]);
    }

    #[test]
    fn names_float32_repr_squared_and_order() {
        let d = diagnose("((523, 181), [(517, 183), (600, 12)], [61.4, 105.0])", &truth(), &[], None);
        assert!(d.fields[2].note.contains("printed differently"), "{:?}", d.fields[2]);
        let d = diagnose("((523, 181), [(517, 183), (600, 12)], [3769.96, 11025.0])", &truth(), &[], None);
        assert!(d.fields[2].note.contains("squared"), "{:?}", d.fields[2]);
        let d = diagnose("((523, 181), [(600, 12), (517, 183)], [105.0, 61.400001525878906])", &truth(), &[], None);
        assert!(d.fields[1].note.contains("wrong order"), "{:?}", d.fields[1]);
    }

    #[test]
    fn empty_answer_rules() {
        let empty = MatchInfo::default();
        let d = diagnose("((523, 181), [], [])", &empty, &[], None);
        assert!(d.fields[0].note.contains("((0, 0), [], [])"), "{:?}", d.fields[0]);
        let d = diagnose("((0, 0), [], [])", &truth(), &[], None);
        assert!(d.fields[0].note.contains("empty answer"), "{:?}", d.fields[0]);
    }

    #[test]
    fn matches_a_core_mistake() {
        let wrong = MatchInfo { query: (523, 181), points: vec![(517, 183)], distances: vec![61.4] };
        let d = diagnose(
            &wrong.to_string(),
            &truth(),
            &[(Mistake::NnMoreThanOne, truth()), (Mistake::LessOrEqual, wrong.clone())],
            None,
        );
        assert!(!d.correct);
        assert_eq!(d.likely, vec![Mistake::LessOrEqual.describe().to_string()]);
    }

    #[test]
    fn unreadable_answers_say_why() {
        let d = diagnose("hello", &truth(), &[], None);
        assert_eq!(d.fields[0].field, "format");
        let d = diagnose("((1, 2), [])", &truth(), &[], None);
        assert!(d.fields[0].note.contains("has 2 parts"), "{:?}", d.fields[0]);
    }
}
