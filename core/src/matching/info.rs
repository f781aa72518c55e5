//! The lab's `matching_info`: integer coordinates of the query keypoint and
//! of its matches, and the match distances.

use super::knn::DMatch;
use crate::pyfmt::py_f32;
use crate::sift::KeyPoint;
use std::fmt;

/// `((x, y), [(x, y), ...], [d, ...])`: what `matching_info` returns.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MatchInfo {
    pub query: (i64, i64),
    pub points: Vec<(i64, i64)>,
    pub distances: Vec<f32>,
}

/// Python's `int()` of a coordinate: truncation toward zero.
#[inline]
pub fn py_int(v: f32) -> i64 {
    v.trunc() as i64
}

/// `matching_info(prev_kps, cur_kps, matches)`: an empty list gives
/// `((0, 0), [], [])`; otherwise the query point is taken from the first
/// match's `queryIdx`.
pub fn matching_info(prev: &[KeyPoint], cur: &[KeyPoint], matches: &[DMatch]) -> MatchInfo {
    let Some(first) = matches.first() else {
        return MatchInfo::default();
    };
    let Some(q) = prev.get(first.query_idx) else {
        return MatchInfo::default();
    };
    let mut info = MatchInfo { query: (py_int(q.x), py_int(q.y)), ..MatchInfo::default() };
    for m in matches {
        if let Some(t) = cur.get(m.train_idx) {
            info.points.push((py_int(t.x), py_int(t.y)));
            info.distances.push(m.distance);
        }
    }
    info
}

impl fmt::Display for MatchInfo {
    /// Python's `repr` of the tuple, e.g. `((523, 181), [(517, 183)], [61.400001525878906])`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "(({}, {}), [", self.query.0, self.query.1)?;
        for (i, (x, y)) in self.points.iter().enumerate() {
            if i > 0 {
                f.write_str(", ")?;
            }
            write!(f, "({x}, {y})")?;
        }
        f.write_str("], [")?;
        for (i, d) in self.distances.iter().enumerate() {
            if i > 0 {
                f.write_str(", ")?;
            }
            f.write_str(&py_f32(*d))?;
        }
        f.write_str("])")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn kp(x: f32, y: f32) -> KeyPoint {
        KeyPoint { x, y, size: 2.0, angle: 0.0, response: 0.1, octave: 0 }
    }

    #[test]
    fn empty_matches_give_origin() {
        assert_eq!(matching_info(&[], &[], &[]).to_string(), "((0, 0), [], [])");
    }

    #[test]
    fn truncates_like_python_int() {
        let prev = [kp(0.0, 0.0), kp(523.97, 181.2)];
        let cur = [kp(517.5, 183.99), kp(1.0, 2.0)];
        let m = [
            DMatch { query_idx: 1, train_idx: 0, distance: 61.4 },
            DMatch { query_idx: 1, train_idx: 1, distance: 105.0 },
        ];
        assert_eq!(
            matching_info(&prev, &cur, &m).to_string(),
            "((523, 181), [(517, 183), (1, 2)], [61.400001525878906, 105.0])"
        );
    }
}
