//! The verdict of one case ([`judge`]): the reply against the reference
//! value (Python's `==` on typed values for matching_info), the value's type
//! checked, and for a failed case the diagnosis and what the report shows;
//! [`failed_call`] for a case that got no reply.

use super::diagnosis::Diagnosis;
use super::difference::Difference;
use super::info::{diagnose_info, info_shape_problem};
use super::matches::diagnose_matches;
use crate::cases::Case;
use crate::escape::escaped;
use crate::protocol::{ErrorKind, Reply};
use crate::pyvalue::{info_type_problem, info_value, PyValue};
use crate::reference::{
    difference_at, expected_text, got_lists_text, info_equal, matches_equal, returned_matches, shorten, Expected,
};
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
    /// What a picture of a wrong value shows (None when correct or no value).
    pub difference: Option<Difference>,
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
        difference: None,
    };
    let wrong = |diagnosis, expected, returned, difference| CaseResult {
        difference: Some(difference),
        ..result(Status::Wrong, Some(diagnosis), expected, returned)
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
                    // Lists that differ have a first differing one.
                    let shown = Difference::of_matches(at.map_or(0, |a| a.0), want, &got);
                    wrong(d, expected_text(want, at), got_lists_text(&got, at), shown)
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
                let picture = Difference::of_info(info, &value);
                if let Some(what) = info_shape_problem(&value) {
                    let d = if matches.is_empty() { Diagnosis::EmptyCase(None) } else { Diagnosis::InfoShape(what) };
                    return wrong(d, info.to_string(), shown, picture);
                }
                let d = if info_equal(info, &value) {
                    Diagnosis::InfoTypes
                } else {
                    diagnose_info(matches, info, &value, prev, cur)
                };
                wrong(d, info.to_string(), shown, picture)
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
        difference: None,
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
