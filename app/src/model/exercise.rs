//! Automarker-style questions: (frame, feature, strategy, threshold) drawn from
//! a seed, so the same link gives every student the same questions.

use crate::model::lab::get_info_command;
use leptos::prelude::*;
use siftlab_core::matching::StrategyKind;

/// The exercises' state (in the link: `ex`, `q`): the seed (`None`: not
/// started) and the question number.
#[derive(Clone, Copy)]
pub struct ExerciseState {
    pub seed: RwSignal<Option<u64>>,
    pub q: RwSignal<u32>,
}

impl ExerciseState {
    pub fn new() -> Self {
        ExerciseState { seed: RwSignal::new(None), q: RwSignal::new(1) }
    }
}

impl Default for ExerciseState {
    fn default() -> Self {
        Self::new()
    }
}

/// SplitMix64: tiny, well distributed, and identical on every platform.
#[derive(Debug, Clone)]
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Rng(seed)
    }

    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    pub fn unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform integer in [lo, hi].
    pub fn range(&mut self, lo: u64, hi: u64) -> u64 {
        lo + self.next_u64() % (hi - lo + 1)
    }
}

#[derive(Debug, Clone, PartialEq)]
pub struct Question {
    /// The lab's FRAME_ID (frames FRAME_ID-1 and FRAME_ID).
    pub frame_id: u32,
    /// Where in [0, 1) the feature id falls; the id is `floor(pos * count)` once
    /// the frame's keypoint count is known.
    pub feature_pos: f64,
    pub algo: StrategyKind,
    /// Threshold text as the student would type it after `-t` (empty = none).
    pub threshold: String,
}

impl Question {
    pub fn feature(&self, keypoints: usize) -> usize {
        ((self.feature_pos * keypoints as f64) as usize).min(keypoints.saturating_sub(1))
    }

    pub fn command(&self, keypoints: usize) -> String {
        get_info_command(self.algo, &self.threshold, &self.frame_id.to_string(), &self.feature(keypoints).to_string())
    }
}

/// Question `q` (1-based) of the exercise `seed` over the frame ids available
/// (a pair needs FRAME_ID-1 and FRAME_ID). Thresholds are drawn where the
/// answers are interesting: around typical SIFT match distances for dt/nn,
/// around Lowe's 0.8 for nndr.
pub fn question(seed: u64, q: u32, frames: &[u32]) -> Option<Question> {
    let pairs: Vec<u32> = frames.iter().copied().filter(|&f| f >= 1 && frames.contains(&(f - 1))).collect();
    if pairs.is_empty() {
        return None;
    }
    let mut rng = Rng::new(seed ^ (q as u64).wrapping_mul(0xD1B5_4A32_D192_ED03));
    let frame_id = pairs[rng.range(0, pairs.len() as u64 - 1) as usize];
    let feature_pos = rng.unit();
    let (algo, threshold) = match rng.range(0, 2) {
        0 => (StrategyKind::Dt, (rng.range(30, 64) * 5).to_string()),
        1 => {
            if rng.range(0, 2) == 0 {
                (StrategyKind::Nn, String::new())
            } else {
                (StrategyKind::Nn, (rng.range(24, 60) * 5).to_string())
            }
        }
        _ => (StrategyKind::Nndr, format!("{:.2}", rng.range(50, 95) as f64 / 100.0)),
    };
    Some(Question { frame_id, feature_pos, algo, threshold })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn splitmix64_reference_values() {
        // SplitMix64 with seed 0 (Vigna's reference implementation).
        let mut r = Rng::new(0);
        assert_eq!(r.next_u64(), 0xE220_A839_7B1D_CDAF);
        assert_eq!(r.next_u64(), 0x6E78_9E6A_A1B9_65F4);
    }

    #[test]
    fn questions_are_reproducible_and_in_range() {
        let frames = [0, 1, 2, 3, 4, 5];
        for q in 1..200 {
            let a = question(7, q, &frames).unwrap();
            assert_eq!(Some(a.clone()), question(7, q, &frames));
            assert!((1..=5).contains(&a.frame_id));
            assert!((0.0..1.0).contains(&a.feature_pos));
            assert!(a.feature(1500) < 1500);
            match a.algo {
                StrategyKind::Dt => assert!((150..=320).contains(&a.threshold.parse::<u32>().unwrap())),
                StrategyKind::Nn => {
                    assert!(a.threshold.is_empty() || (120..=300).contains(&a.threshold.parse::<u32>().unwrap()))
                }
                StrategyKind::Nndr => assert!((0.5..=0.95).contains(&a.threshold.parse::<f64>().unwrap())),
            }
        }
        assert_ne!(question(7, 1, &frames), question(8, 1, &frames));
        assert_eq!(question(7, 1, &[3]), None, "a single frame has no pair");
        assert_eq!(question(7, 1, &[3, 4]).unwrap().frame_id, 4);
    }
}
