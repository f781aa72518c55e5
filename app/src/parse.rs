//! The page's text fields → the core's values, with the messages the page shows.

use siftlab_core::matching::{Strategy, StrategyKind};

/// Threshold text → the value `Strategy::parse` takes (empty → none).
pub fn parse_threshold(text: &str) -> Result<Option<f64>, String> {
    let t = text.trim();
    if t.is_empty() {
        return Ok(None);
    }
    t.parse::<f64>().map(Some).map_err(|_| format!("threshold {t:?} is not a number"))
}

/// A strategy from its kind and the threshold text, validated by the core.
pub fn parse_strategy(kind: StrategyKind, threshold: &str) -> Result<Strategy, String> {
    Strategy::parse(kind.name(), parse_threshold(threshold)?).map_err(|e| e.to_string())
}

pub fn parse_feature(text: &str) -> Result<usize, String> {
    let t = text.trim();
    t.parse::<usize>().map_err(|_| format!("feature id {t:?} is not a whole number ≥ 0"))
}
