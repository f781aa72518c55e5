//! Why a case failed: the kinds of mistake ([`Diagnosis`]), each with a
//! stable code for the report and what to do, in words, for the student.

use siftlab_core::matching::Mistake;

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
    /// In wall time (the browser), over the limit scaled to the machine's
    /// speed on both tries, on a machine slower than the scale's cap: it
    /// cannot be told from a time-out. `limit` is the scaled limit, `speed`
    /// the slowest factor measured.
    TooSlowHere { limit: f64, speed: f64 },
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
            Diagnosis::TooSlowHere { .. } => "too_slow_here",
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
            Diagnosis::TooSlowHere { limit, speed } => format!(
                "too slow to tell here: this machine ran the reference workload at {speed:.1}x the reference \
                 time, so the call was given {limit:.0} s (the lab's limit scaled, at most that much) and ran over \
                 it twice; whether it keeps to the lab's 10 s of CPU time cannot be told on this machine. It counts \
                 as a time-out here: run `siftlab mark` natively for the real mark"
            ),
            Diagnosis::TaskTimeLimit { seconds } => {
                format!("not run: the task's {seconds} s were used up by the calls before it")
            }
            Diagnosis::Crashed(m) => format!("the Python process ended during the call: {m}"),
            Diagnosis::Differs(m) => m.clone(),
        }
    }

    /// The kind of mistake a code names, in plain words and without any
    /// one student's details (the class summary's explanation): `None`
    /// for a code siftlab does not write.
    pub fn explain_code(code: &str) -> Option<&'static str> {
        Some(match code {
            "less_or_equal" => "kept a match whose distance equals the threshold: the lab keeps distance < threshold",
            "k_too_small" => {
                "dt asked knnMatch for too few neighbours (k < len(des2)): matches under the threshold were lost"
            }
            "ratio_inverted" => "nndr compared the ratio the wrong way round (d2 / d1, or > instead of <)",
            "nn_more_than_one" => "nn kept more than the nearest neighbour of a query",
            "frames_swapped" => "des1 and des2 (or kp1 and kp2) swapped: the previous frame is the query",
            "ratio_division" => {
                "nndr tested d1 / d2 < t instead of d1 < t * d2: a different rounding in floating point"
            }
            "nn_ignores_threshold" => "nn ignored its threshold and kept every nearest neighbour",
            "nn_ignores_none" => "nn with threshold None kept nothing: None means no threshold",
            "empty_lists_dropped" => "left out the empty lists of queries without a match",
            "wrong_length" => "returned another number of lists than query descriptors",
            "not_float32" => "distances computed in float64, not knnMatch's float32",
            "wrong_order" => "the right matches in another order than knnMatch's",
            "rounded" => "matching_info rounded the coordinates; the lab truncates them with int()",
            "float_coordinates" => "matching_info left the coordinates as floats",
            "swapped_xy" => "matching_info gave (y, x) instead of (x, y)",
            "empty_case" => "matching_info on an empty list of matches did not return ((0, 0), [], [])",
            "wrong_shape" => "matching_info's value is not ((x, y), [(x, y), ...], [d, ...])",
            "wrong_types_inside" => "matching_info's numbers are right, their types are not (lists, numpy values, ...)",
            "wrong_type" => "returned a value of the wrong type (a runtime error)",
            "runtime_error" => "raised an exception",
            "timeout" => "ran over the time limit (an endless loop, or far too slow)",
            "too_slow_here" => "ran over the browser's scaled limit: too slow to tell on that machine",
            "task_time_limit" => "not run: the task's time was used up by the calls before it",
            "crashed" => "the Python process ended during the call",
            "differs" => "a value that differs in a way siftlab has no name for",
            _ => return None,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every code a report can carry has its words in the class summary.
    #[test]
    fn every_code_is_explained() {
        let all = [
            Diagnosis::Mistake(Mistake::LessOrEqual),
            Diagnosis::Mistake(Mistake::TruncatedK100),
            Diagnosis::Mistake(Mistake::RatioInverted),
            Diagnosis::Mistake(Mistake::NnMoreThanOne),
            Diagnosis::Mistake(Mistake::WrongFrameOrder),
            Diagnosis::TruncatedK(5),
            Diagnosis::RatioDivision,
            Diagnosis::NnIgnoresThreshold,
            Diagnosis::NnNoneKeepsNothing,
            Diagnosis::DroppedEmptyLists,
            Diagnosis::Length { expected: 1, got: 2 },
            Diagnosis::NotFloat32,
            Diagnosis::Order,
            Diagnosis::Rounded,
            Diagnosis::FloatCoordinates,
            Diagnosis::SwappedXY,
            Diagnosis::EmptyCase(None),
            Diagnosis::InfoShape(String::new()),
            Diagnosis::InfoTypes,
            Diagnosis::WrongType(String::new()),
            Diagnosis::Runtime { message: String::new(), hint: None },
            Diagnosis::Timeout { seconds: 1.0 },
            Diagnosis::TooSlowHere { limit: 1.0, speed: 1.0 },
            Diagnosis::TaskTimeLimit { seconds: 1.0 },
            Diagnosis::Crashed(String::new()),
            Diagnosis::Differs(String::new()),
        ];
        for d in &all {
            assert!(Diagnosis::explain_code(d.code()).is_some_and(|t| !t.is_empty()), "{}", d.code());
        }
        assert_eq!(Diagnosis::explain_code("<b>"), None);
    }
}
