//! What a wrong case's picture shows (PrairieLearn's `images[]`, drawn by
//! `siftlab_core::render::difference`): for dt / nn / nndr the first query
//! feature whose list differs, with the reference's list and the returned
//! one; for matching_info the reference's points and the returned ones. A
//! submission may return millions of matches: each list keeps at most
//! [`MAX_SHOWN`], so what a report holds stays small whatever it returned.

use crate::reference::Got;
use siftlab_core::json::Json;
use siftlab_core::matching::{DMatch, MatchInfo};
use std::collections::HashSet;

/// Matches (or points) of one list kept for the picture.
pub const MAX_SHOWN: usize = 64;

/// A returned point (x, y), as Python numbers.
pub type Point = (f64, f64);

#[derive(Clone, Debug, PartialEq)]
pub enum Difference {
    /// The first list (query feature `feature`) that differs, as the
    /// matches in both lists, in the reference's only and in the returned
    /// one's only (as (queryIdx, trainIdx) pairs), each cut to
    /// [`MAX_SHOWN`]; `counts` are the three over the whole lists.
    Matches { feature: usize, both: Vec<DMatch>, missed: Vec<DMatch>, extra: Vec<Got>, counts: (usize, usize, usize) },
    /// matching_info's reference tuple and the returned points, where the
    /// value had the tuple's shape (`None` otherwise).
    Info { expected: MatchInfo, returned: Option<(Point, Vec<Point>)> },
}

impl Difference {
    /// The first list that differs, split in three (a list cut at k = 100
    /// shows the reference's matches past 100 as missed).
    pub fn of_matches(feature: usize, expected: &[Vec<DMatch>], got: &[Vec<Got>]) -> Difference {
        let e = expected.get(feature).map_or(&[][..], Vec::as_slice);
        let g = got.get(feature).map_or(&[][..], Vec::as_slice);
        let in_e: HashSet<(i64, i64)> = e.iter().map(|m| (m.query_idx as i64, m.train_idx as i64)).collect();
        let in_g: HashSet<(i64, i64)> = g.iter().map(|m| (m.query, m.train)).collect();
        let (both, missed): (Vec<DMatch>, Vec<DMatch>) =
            e.iter().partition(|m| in_g.contains(&(m.query_idx as i64, m.train_idx as i64)));
        let extra: Vec<Got> = g.iter().filter(|m| !in_e.contains(&(m.query, m.train))).copied().collect();
        let counts = (both.len(), missed.len(), extra.len());
        let cut = |mut v: Vec<DMatch>| {
            v.truncate(MAX_SHOWN);
            v
        };
        let extra = extra.into_iter().take(MAX_SHOWN).collect();
        Difference::Matches { feature, both: cut(both), missed: cut(missed), extra, counts }
    }

    /// matching_info's value read as `((x, y), [(x, y), …], …)` where it has
    /// that shape; the points cut to [`MAX_SHOWN`].
    pub fn of_info(expected: &MatchInfo, got: &Json) -> Difference {
        let point = |p: &Json| match p.as_arr() {
            Some([x, y]) => Some((x.as_f64()?, y.as_f64()?)),
            _ => None,
        };
        let returned = got.as_arr().and_then(|parts| {
            let query = point(parts.first()?)?;
            let points = parts.get(1)?.as_arr()?.iter().take(MAX_SHOWN).map(point).collect::<Option<Vec<_>>>()?;
            Some((query, points))
        });
        let mut expected = expected.clone();
        expected.points.truncate(MAX_SHOWN);
        expected.distances.truncate(MAX_SHOWN);
        Difference::Info { expected, returned }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use siftlab_core::json::parse;

    fn m(q: usize, t: usize, d: f32) -> DMatch {
        DMatch { query_idx: q, train_idx: t, distance: d }
    }

    #[test]
    fn matches_split_in_three_cut_short() {
        let g = |q: i64, t: i64| Got { query: q, train: t, distance: 1.0 };
        let expected = vec![vec![m(0, 1, 1.0)], vec![m(1, 2, 1.0), m(1, 5000, 1.0)]];
        let got = vec![vec![g(0, 1)], (0..1000).map(|t| g(1, t)).collect()];
        let Difference::Matches { feature, both, missed, extra, counts } = Difference::of_matches(1, &expected, &got)
        else {
            panic!("a matches case gives Difference::Matches")
        };
        assert_eq!((feature, both, missed, counts), (1, vec![m(1, 2, 1.0)], vec![m(1, 5000, 1.0)], (1, 1, 999)));
        assert_eq!((extra.len(), extra[1], extra[2]), (MAX_SHOWN, g(1, 1), g(1, 3)));
        // k too small: the reference's matches past the returned ones are missed.
        let long = vec![(0..200).map(|t| m(0, t, 1.0)).collect::<Vec<_>>()];
        let short = vec![(0..100).map(|t| g(0, t as i64)).collect::<Vec<_>>()];
        let Difference::Matches { missed, counts, .. } = Difference::of_matches(0, &long, &short) else { panic!() };
        assert_eq!((missed[0], missed.len(), counts), (m(0, 100, 1.0), MAX_SHOWN, (100, 100, 0)));
        // A list the student left out: everything missed, not an error.
        let Difference::Matches { counts, .. } = Difference::of_matches(1, &expected, &got[..1]) else { panic!() };
        assert_eq!(counts, (0, 2, 0));
    }

    #[test]
    fn info_reads_points_only_from_the_tuples_shape() {
        let info = MatchInfo { query: (10, 20), points: vec![(1, 2)], distances: vec![3.0] };
        let d = Difference::of_info(&info, &parse("[[20, 10.5], [[2, 1], [4, 3]], [3.0, 4.0]]").unwrap());
        assert_eq!(
            d,
            Difference::Info { expected: info.clone(), returned: Some(((20.0, 10.5), vec![(2.0, 1.0), (4.0, 3.0)])) }
        );
        for v in ["[[20], [], []]", "\"text\"", "[[1, 2], [[1, \"a\"]], []]", "[]"] {
            assert_eq!(
                Difference::of_info(&info, &parse(v).unwrap()),
                Difference::Info { expected: info.clone(), returned: None },
                "{v}"
            );
        }
    }
}
