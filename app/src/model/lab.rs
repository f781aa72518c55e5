//! The explorer's state: the two frames, the lab's parameters, and what the
//! core derives from them. Everything the user sees is a function of this.

use crate::model::frame::Frame;
use crate::model::parse::{parse_feature, parse_strategy, threshold_box_text};
use leptos::prelude::*;
use siftlab_core::matching::StrategyKind;
use siftlab_core::matching::{explain, Explanation, Strategy};
use siftlab_core::sift::KeyPoint;
use std::sync::Arc;

/// Which frame of the pair.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Which {
    Prev,
    Cur,
}

impl Which {
    pub fn name(self) -> &'static str {
        match self {
            Which::Prev => "previous frame",
            Which::Cur => "current frame",
        }
    }
}

/// Where the frames come from (decides what the URL can restore).
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Source {
    /// The bundled demo frames (`demo/gray/00/image_0/`), ids available.
    Demo(Vec<u32>),
    /// A folder the user opened (one sequence of it, the lab's layout or
    /// KITTI's); ids of that sequence's frames.
    Folder(Vec<u32>),
    /// Two files picked or dropped one by one.
    Files,
}

impl Source {
    pub fn frames(&self) -> &[u32] {
        match self {
            Source::Demo(f) | Source::Folder(f) => f,
            Source::Files => &[],
        }
    }

    pub fn url_name(&self) -> Option<&'static str> {
        match self {
            Source::Demo(_) => Some("demo"),
            Source::Folder(_) => Some("folder"),
            Source::Files => None,
        }
    }
}

/// A computation the user is waiting for (shown as progress, `busy` while any).
#[derive(Debug, Clone, PartialEq)]
pub struct Job {
    pub id: u64,
    pub what: String,
    pub stage: String,
    pub started_ms: f64,
}

/// The derived result for the current settings; compared by identity so the
/// memo does not need `Explanation: PartialEq`.
#[derive(Clone, Debug)]
pub struct Analysis {
    pub explanation: Arc<Explanation>,
    pub strategy: Strategy,
    pub feature: usize,
    /// `ret value:` exactly as the CLI prints it (the core's `MatchInfo` Display).
    pub tuple: String,
    /// Time the core took to derive it, in ms (the 50 ms budget).
    pub ms: f64,
}

impl PartialEq for Analysis {
    fn eq(&self, other: &Self) -> bool {
        Arc::ptr_eq(&self.explanation, &other.explanation)
    }
}

/// The default threshold text shown when a strategy is picked first.
pub fn default_threshold(kind: StrategyKind) -> String {
    threshold_box_text(siftlab_core::matching::args::matching_default(kind))
}

/// The threshold's range as the controls hint it.
pub fn threshold_hint(kind: StrategyKind) -> &'static str {
    match kind {
        StrategyKind::Dt => "0 … 500",
        StrategyKind::Nn => "0 … 500, empty = none",
        StrategyKind::Nndr => "0 … 1",
    }
}

/// The lab's command line for these settings, as a student types it:
/// `get_info -a ALGO [-t T] FRAME_ID FEATURE` (no `-t` when the text is blank).
pub fn get_info_command(kind: StrategyKind, threshold: &str, frame: &str, feature: &str) -> String {
    let t = threshold.trim();
    let t = if t.is_empty() { String::new() } else { format!(" -t {t}") };
    format!("get_info -a {}{t} {frame} {}", kind.name(), feature.trim())
}

/// The menu's label for a strategy.
pub fn strategy_label(kind: StrategyKind) -> &'static str {
    match kind {
        StrategyKind::Dt => "dt — distance threshold",
        StrategyKind::Nn => "nn — nearest neighbour",
        StrategyKind::Nndr => "nndr — nearest-neighbour distance ratio",
    }
}

#[derive(Clone, Copy)]
pub struct Lab {
    pub prev: RwSignal<Option<Frame>>,
    pub cur: RwSignal<Option<Frame>>,
    pub source: RwSignal<Source>,
    /// The source's KITTI sequence and camera (the demo: the lab's 00).
    pub sequence: RwSignal<crate::model::sequence::SequenceInfo>,
    /// A picked folder's sequences, each with its label for the choice.
    pub folder_sequences: RwSignal<Vec<(siftlab_core::dataset::SequenceLayout, String)>>,
    /// The lab's FRAME_ID (demo/folder): frames FRAME_ID-1 and FRAME_ID.
    pub frame_id: RwSignal<u32>,
    pub algo: RwSignal<StrategyKind>,
    /// Threshold text per strategy, in the order dt, nn, nndr.
    pub thresholds: RwSignal<[String; 3]>,
    pub feature_text: RwSignal<String>,
    pub show_all: RwSignal<bool>,
    /// The last load error (inline, dismissable); loaded frames stay.
    pub load_error: RwSignal<Option<String>>,
    pub jobs: RwSignal<Vec<Job>>,
    /// Newest request per slot, so a slow stale result never overwrites a newer one.
    pub generation: RwSignal<[u64; 2]>,
    pub attribution: RwSignal<String>,
    /// OpenCV's SIMD width being reproduced: 8 (AVX2) or 16 (AVX-512).
    pub lanes: RwSignal<usize>,
    /// The strategy and threshold boxes, parsed and validated by the core
    /// once per change; every view of the pair reads this one.
    pub strategy: Memo<Result<Strategy, String>>,
    pub analysis: Memo<Option<Result<Analysis, String>>>,
}

/// Where a strategy's threshold text sits in [`Lab::thresholds`].
fn slot(kind: StrategyKind) -> usize {
    StrategyKind::ALL.iter().position(|&k| k == kind).unwrap_or(0)
}

impl Lab {
    /// A lab with no clock (the analysis reports 0 ms): tests, and any use off
    /// the page.
    pub fn new() -> Self {
        Self::with_clock(|| 0.0)
    }

    /// A lab timing each analysis with `clock` (milliseconds): the page gives
    /// the platform's, so that model stays plain logic.
    pub fn with_clock(clock: fn() -> f64) -> Self {
        let prev = RwSignal::new(None::<Frame>);
        let cur = RwSignal::new(None::<Frame>);
        let algo = RwSignal::new(StrategyKind::Nndr);
        let thresholds = RwSignal::new(StrategyKind::ALL.map(default_threshold));
        let feature_text = RwSignal::new("0".to_string());
        let strategy = Memo::new(move |_| {
            let algo = algo.get();
            thresholds.with(|t| parse_strategy(algo, &t[slot(algo)]))
        });
        let analysis = Memo::new(move |_| {
            let (p, c) = (prev.get()?, cur.get()?);
            let t0 = clock();
            let analysis = strategy.get().and_then(|s| analyse(&p, &c, s, &feature_text.get()));
            Some(analysis.map(|a| Analysis { ms: clock() - t0, ..a }))
        });
        Lab {
            prev,
            cur,
            source: RwSignal::new(Source::Files),
            sequence: RwSignal::new(crate::model::sequence::SequenceInfo::demo()),
            folder_sequences: RwSignal::new(Vec::new()),
            frame_id: RwSignal::new(1),
            algo,
            thresholds,
            feature_text,
            show_all: RwSignal::new(false),
            load_error: RwSignal::new(None),
            jobs: RwSignal::new(Vec::new()),
            generation: RwSignal::new([0, 0]),
            attribution: RwSignal::new(String::new()),
            lanes: RwSignal::new(8),
            strategy,
            analysis,
        }
    }

    pub fn frame(&self, w: Which) -> RwSignal<Option<Frame>> {
        match w {
            Which::Prev => self.prev,
            Which::Cur => self.cur,
        }
    }

    /// The threshold text of the current strategy.
    pub fn threshold(&self) -> String {
        let algo = self.algo.get();
        self.thresholds.with(|t| t[slot(algo)].clone())
    }

    pub fn set_threshold(&self, text: String) {
        let i = slot(self.algo.get_untracked());
        self.thresholds.update(|t| t[i] = text);
    }

    pub fn feature(&self) -> Option<usize> {
        parse_feature(&self.feature_text.get()).ok()
    }

    pub fn set_feature(&self, f: usize) {
        self.feature_text.set(f.to_string());
    }

    pub fn keypoints(&self, w: Which) -> Option<Vec<KeyPoint>> {
        self.frame(w).with(|f| f.as_ref().map(|f| f.features.keypoints.clone()))
    }

    pub fn busy(&self) -> bool {
        self.jobs.with(|j| !j.is_empty())
    }
}

impl Default for Lab {
    fn default() -> Self {
        Self::new()
    }
}

/// Runs the core on the current settings: validation (the feature range),
/// the strategy, `matching_info` and its formatting all live in the core;
/// this only strings them together.
pub fn analyse(prev: &Frame, cur: &Frame, strategy: Strategy, feature: &str) -> Result<Analysis, String> {
    let feature = parse_feature(feature)?;
    let explanation = explain(&strategy, &prev.features, &cur.features, feature).map_err(|e| e.to_string())?;
    let tuple = explanation.info.to_string();
    Ok(Analysis { explanation: Arc::new(explanation), strategy, feature, tuple, ms: 0.0 })
}

/// Index of the keypoint nearest to (x, y) in image coordinates (the first
/// one on ties), as click-to-select picks it.
pub fn nearest_keypoint(kps: &[KeyPoint], x: f64, y: f64) -> Option<usize> {
    let mut best: Option<(usize, f64)> = None;
    for (i, k) in kps.iter().enumerate() {
        let d = (k.x as f64 - x).powi(2) + (k.y as f64 - y).powi(2);
        if best.is_none_or(|(_, b)| d < b) {
            best = Some((i, d));
        }
    }
    best.map(|(i, _)| i)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_strategy_has_its_own_threshold_slot_and_texts() {
        let slots: Vec<usize> = StrategyKind::ALL.iter().map(|&k| slot(k)).collect();
        assert_eq!(slots, [0, 1, 2]);
        assert_eq!(StrategyKind::ALL.map(default_threshold), ["100", "", "0.8"]);
        assert_eq!(threshold_hint(StrategyKind::Nn), "0 … 500, empty = none");
        assert!(strategy_label(StrategyKind::Nndr).starts_with("nndr — "));
    }

    #[test]
    fn the_command_line_and_the_strategy_from_the_boxes() {
        assert_eq!(get_info_command(StrategyKind::Dt, " 300 ", "150", "209 "), "get_info -a dt -t 300 150 209");
        assert_eq!(get_info_command(StrategyKind::Nn, "  ", "FRAME_ID", "3"), "get_info -a nn FRAME_ID 3");
        assert_eq!(parse_strategy(StrategyKind::Nndr, "0.8"), Ok(Strategy::Nndr(0.8)));
        assert_eq!(parse_strategy(StrategyKind::Nn, ""), Ok(Strategy::Nn(None)));
        assert!(parse_strategy(StrategyKind::Dt, "").unwrap_err().contains("needs a threshold"));
        assert_eq!(parse_strategy(StrategyKind::Dt, "abc").unwrap_err(), "threshold must be a number, got 'abc'");
    }
}
