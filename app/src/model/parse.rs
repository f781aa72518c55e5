//! The page's text fields → the core's values, with the messages the page shows.

use siftlab_core::matching::{args, Strategy, StrategyKind};

/// Threshold text → the value `Strategy::parse` takes (empty → none), with
/// the CLI's message.
pub fn parse_threshold(text: &str) -> Result<Option<f64>, String> {
    if text.trim().is_empty() {
        return Ok(None);
    }
    args::parse_threshold(text).map(Some).map_err(|e| e.to_string())
}

/// A strategy from its kind and the threshold text, validated by the core.
pub fn parse_strategy(kind: StrategyKind, threshold: &str) -> Result<Strategy, String> {
    Strategy::parse(kind.name(), parse_threshold(threshold)?).map_err(|e| e.to_string())
}

/// The feature box: the lab's FEATURE_ID, with the CLI's message.
pub fn parse_feature(text: &str) -> Result<usize, String> {
    args::parse_index(text, "FEATURE_ID").map_err(|e| e.to_string())
}

/// A default threshold as the threshold box shows it (none: empty).
pub fn threshold_box_text(t: Option<f64>) -> String {
    t.map_or(String::new(), |t| t.to_string())
}

/// The most SIFT workers a page starts. Each holds its own wasm memory, which
/// peaks at about 62 MB on a KITTI frame (measured: `memory.buffer.byteLength`
/// after `detectAndCompute`, docs/performance.md), so 8 workers hold about half a
/// gigabyte; more cores than that are left to the trackers and the page.
pub const MAX_WORKERS: usize = 8;

/// The SIFT workers for a machine with `cores` logical cores: one per core
/// but one (the page and the odometry's trackers need a core too), at least
/// two (one per frame of a pair), at most [`MAX_WORKERS`]. Unknown: two.
pub fn default_workers(cores: Option<usize>) -> usize {
    cores.map_or(2, |c| c.saturating_sub(1)).clamp(2, MAX_WORKERS)
}

/// The `workers=N` URL parameter (teachers on shared machines, tests): a
/// whole number from 1 to 16.
pub fn parse_workers(text: &str) -> Result<usize, String> {
    match text.trim().parse::<usize>() {
        Ok(n) if (1..=16).contains(&n) => Ok(n),
        _ => Err(format!("workers={} is not a whole number from 1 to 16; using the machine's count", text.trim())),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn worker_counts() {
        assert_eq!(default_workers(None), 2);
        assert_eq!(default_workers(Some(1)), 2);
        assert_eq!(default_workers(Some(2)), 2);
        assert_eq!(default_workers(Some(4)), 3);
        assert_eq!(default_workers(Some(8)), 7);
        assert_eq!(default_workers(Some(16)), MAX_WORKERS);
        assert_eq!(parse_workers(" 3 "), Ok(3));
        assert_eq!(parse_workers("1"), Ok(1));
        assert!(parse_workers("0").unwrap_err().starts_with("workers=0 is not"));
        assert!(parse_workers("17").is_err());
        assert!(parse_workers("two").is_err());
    }
}
