//! The marker's cases: which function is called on which frame pair with
//! which threshold, drawn from a seed (docs/marking.md §The lab's marking).

use siftlab_core::matching::Strategy;
use siftlab_core::pyfmt::py_float;
use siftlab_core::rng::CvRng;

/// The four marked functions, in the order they are marked.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Task {
    Dt,
    Nn,
    Nndr,
    MatchingInfo,
}

impl Task {
    pub const ALL: [Task; 4] = [Task::Dt, Task::Nn, Task::Nndr, Task::MatchingInfo];

    /// The method's name in `vision_tasks.py`.
    pub fn name(self) -> &'static str {
        match self {
            Task::Dt => "dt",
            Task::Nn => "nn",
            Task::Nndr => "nndr",
            Task::MatchingInfo => "matching_info",
        }
    }
}

/// Cases per task when none are asked for (the lab's marking).
pub const DEFAULT_CASES: usize = 25;

/// `NUM_FEATURES` of the lab's base class: feature ids are drawn below it.
pub const NUM_FEATURES: u32 = 1500;

/// One call of a student's function. `frame` is FRAME_ID: the pair is
/// frames `frame - 1` (the query side, des1/kp1) and `frame`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Case {
    Dt {
        frame: u32,
        threshold: f64,
    },
    Nn {
        frame: u32,
        threshold: Option<f64>,
    },
    Nndr {
        frame: u32,
        threshold: f64,
    },
    /// `matching_info(kp1, kp2, matches)` with the reference matches of
    /// `feature` under `strategy`.
    Info {
        frame: u32,
        strategy: Strategy,
        feature: usize,
    },
}

impl Case {
    pub fn task(&self) -> Task {
        match self {
            Case::Dt { .. } => Task::Dt,
            Case::Nn { .. } => Task::Nn,
            Case::Nndr { .. } => Task::Nndr,
            Case::Info { .. } => Task::MatchingInfo,
        }
    }

    /// FRAME_ID (the current frame of the pair).
    pub fn frame(&self) -> u32 {
        match *self {
            Case::Dt { frame, .. } | Case::Nn { frame, .. } | Case::Nndr { frame, .. } | Case::Info { frame, .. } => {
                frame
            }
        }
    }

    /// The strategy whose result is the reference: the function's own for
    /// dt / nn / nndr, the one that chose the matches for matching_info.
    pub fn strategy(&self) -> Strategy {
        match *self {
            Case::Dt { threshold, .. } => Strategy::Dt(threshold),
            Case::Nn { threshold, .. } => Strategy::Nn(threshold),
            Case::Nndr { threshold, .. } => Strategy::Nndr(threshold),
            Case::Info { strategy, .. } => strategy,
        }
    }

    /// The call as the student's code sees it, with where its arguments
    /// come from: `dt(des1, des2, 232.5) on frames 11 -> 12`.
    pub fn call_text(&self) -> String {
        let f = self.frame();
        let pair = format!("frames {} -> {f}", f.saturating_sub(1));
        match *self {
            Case::Info { strategy, feature, .. } => format!(
                "matching_info(kp1, kp2, matches) on {pair}, matches = {}({}) of feature {feature}",
                strategy.name(),
                py_threshold(strategy.threshold())
            ),
            _ => {
                format!("{}(des1, des2, {}) on {pair}", self.task().name(), py_threshold(self.strategy().threshold()))
            }
        }
    }
}

/// The FRAME_IDs a marking may draw from the frames `present`: each whose
/// previous frame is present too (a pair), ascending, each once. The CLI
/// and the app both decide with this.
pub fn markable_frames(present: &[u32]) -> Vec<u32> {
    let have: std::collections::BTreeSet<u32> = present.iter().copied().collect();
    have.iter().copied().filter(|&f| f >= 1 && have.contains(&(f - 1))).collect()
}

/// The frames the cases read (each case's previous and current frame),
/// ascending, each once: what SIFT must run on before a marking.
pub fn frames_needed(cases: &[Case]) -> Vec<u32> {
    let set: std::collections::BTreeSet<u32> = cases.iter().flat_map(|c| [c.frame() - 1, c.frame()]).collect();
    set.into_iter().collect()
}

/// A threshold argument as Python prints it: `232.5`, `None`.
pub fn py_threshold(t: Option<f64>) -> String {
    t.map_or("None".to_string(), py_float)
}

/// Draws the cases: `n` per task, all dt cases first, then nn, nndr and
/// matching_info, from one `cv::RNG` seeded with `seed` (0 stands for
/// 0xffffffff, as in `cv::RNG(0)`). `frames` are the FRAME_IDs that may be
/// drawn (each with its previous frame present); none gives no cases.
///
/// Draws per case, in this order (`u(m)` = `rng.uniform(m)`):
/// the frame `frames[u(len)]`; then dt: the distance threshold D; nn:
/// `u(5) == 0` → None, else D; nndr: the ratio R; matching_info: the
/// strategy `u(3)` (dt, nn, nndr) with its threshold as above, then the
/// feature `u(1500)`. D: `b = u(20)`; 0 → 0.0, 1 → 500.0, else
/// `u(5001) / 10`. R: `b = u(20)`; 0 → 0.0, 1 → 1.0, else `u(101) / 100`.
pub fn plan(seed: u64, n: usize, frames: &[u32]) -> Vec<Case> {
    if frames.is_empty() {
        return Vec::new();
    }
    let mut rng = CvRng::new(if seed == 0 { 0xffff_ffff } else { seed });
    let len = u32::try_from(frames.len()).unwrap_or(u32::MAX);
    let mut out = Vec::with_capacity(4 * n);
    for task in Task::ALL {
        for _ in 0..n {
            let frame = frames[rng.uniform(len) as usize];
            out.push(match task {
                Task::Dt => Case::Dt { frame, threshold: distance(&mut rng) },
                Task::Nn => Case::Nn { frame, threshold: nn_threshold(&mut rng) },
                Task::Nndr => Case::Nndr { frame, threshold: ratio(&mut rng) },
                Task::MatchingInfo => {
                    let strategy = match rng.uniform(3) {
                        0 => Strategy::Dt(distance(&mut rng)),
                        1 => Strategy::Nn(nn_threshold(&mut rng)),
                        _ => Strategy::Nndr(ratio(&mut rng)),
                    };
                    Case::Info { frame, strategy, feature: rng.uniform(NUM_FEATURES) as usize }
                }
            });
        }
    }
    out
}

/// A distance threshold: one decimal in [0, 500], each bound 1/20.
fn distance(rng: &mut CvRng) -> f64 {
    match rng.uniform(20) {
        0 => 0.0,
        1 => 500.0,
        // n / 10 is correctly rounded, so it is the f64 Python reads from "n/10" text.
        _ => rng.uniform(5001) as f64 / 10.0,
    }
}

/// nn's threshold: None 1/5, else a distance.
fn nn_threshold(rng: &mut CvRng) -> Option<f64> {
    if rng.uniform(5) == 0 {
        None
    } else {
        Some(distance(rng))
    }
}

/// A ratio: two decimals in [0, 1], each bound 1/20.
fn ratio(rng: &mut CvRng) -> f64 {
    match rng.uniform(20) {
        0 => 0.0,
        1 => 1.0,
        _ => rng.uniform(101) as f64 / 100.0,
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn frames_a_marking_uses() {
        assert_eq!(super::markable_frames(&[5, 0, 1, 2, 4, 2, 7]), [1, 2, 5]);
        assert!(super::markable_frames(&[3]).is_empty());
        let cases = super::plan(1, 2, &[1, 2, 5]);
        let needed = super::frames_needed(&cases);
        assert!(needed.windows(2).all(|w| w[0] < w[1]));
        for c in &cases {
            assert!(needed.contains(&(c.frame() - 1)) && needed.contains(&c.frame()));
        }
    }

    use super::*;

    #[test]
    fn plan_is_deterministic_and_in_range() {
        let frames: Vec<u32> = (1..=150).collect();
        let a = plan(0, 25, &frames);
        assert_eq!(a, plan(0, 25, &frames));
        assert_ne!(a, plan(1, 25, &frames));
        assert_eq!(a, plan(0xffff_ffff, 25, &frames));
        assert_eq!(a.len(), 100);
        for (i, c) in a.iter().enumerate() {
            assert_eq!(c.task(), Task::ALL[i / 25]);
            assert!((1..=150).contains(&c.frame()));
            let t = c.strategy().threshold();
            match c.strategy() {
                Strategy::Nndr(r) => assert!((0.0..=1.0).contains(&r) && (r * 100.0).round() / 100.0 == r),
                _ => assert!(t.is_none_or(|t| (0.0..=500.0).contains(&t) && (t * 10.0).round() / 10.0 == t)),
            }
            if let Case::Info { feature, .. } = c {
                assert!(*feature < 1500);
            }
        }
        // Over many cases: the bounds, None and every strategy all occur.
        let many = plan(7, 2000, &frames);
        let has = |f: &dyn Fn(&Case) -> bool| many.iter().any(f);
        assert!(has(&|c| matches!(c, Case::Dt { threshold, .. } if *threshold == 0.0)));
        assert!(has(&|c| matches!(c, Case::Dt { threshold, .. } if *threshold == 500.0)));
        assert!(has(&|c| matches!(c, Case::Nn { threshold: None, .. })));
        assert!(has(&|c| matches!(c, Case::Nndr { threshold, .. } if *threshold == 1.0)));
        assert!(has(&|c| matches!(c, Case::Info { strategy: Strategy::Nn(None), .. })));
        assert!(has(&|c| matches!(c, Case::Info { strategy: Strategy::Nndr(_), .. })));
        assert!(has(&|c| c.frame() == 1) && has(&|c| c.frame() == 150));
        let nones = many.iter().filter(|c| matches!(c, Case::Nn { threshold: None, .. })).count();
        assert!((300..500).contains(&nones), "{nones} of 2000 nn cases are None");
        assert!(plan(0, 5, &[]).is_empty());
    }

    #[test]
    fn call_text_shows_arguments_as_python() {
        let c = Case::Nn { frame: 12, threshold: None };
        assert_eq!(c.call_text(), "nn(des1, des2, None) on frames 11 -> 12");
        let c = Case::Info { frame: 1, strategy: Strategy::Nndr(0.8), feature: 37 };
        assert_eq!(
            c.call_text(),
            "matching_info(kp1, kp2, matches) on frames 0 -> 1, matches = nndr(0.8) of feature 37"
        );
        assert_eq!(Case::Dt { frame: 5, threshold: 232.5 }.call_text(), "dt(des1, des2, 232.5) on frames 4 -> 5");
    }
}
