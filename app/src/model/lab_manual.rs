//! The lab manual's seven `get_info` examples ([`siftlab_core::manual::EXAMPLES`])
//! as the explorer's settings: what a click on one puts in the controls, and
//! which example (if any) the current view is, so the manual's printed value
//! can be shown beside siftlab's whichever way the view got there (a click, a
//! link, or typing the same settings).

use crate::model::parse::{parse_feature, parse_threshold};
use siftlab_core::manual::{ManualExample, EXAMPLES};
use siftlab_core::matching::StrategyKind;

/// The threshold box's text for an example, as the manual writes `-t`
/// (`100`, `0.97`; empty for `nn` without one).
pub fn threshold_text(ex: &ManualExample) -> String {
    ex.threshold.map(|t| t.to_string()).unwrap_or_default()
}

/// The example the settings are, by value: the threshold as a number (so
/// `300` and `300.0` are the same `-t`, as the lab's argparse reads it), the
/// feature as a whole number.
pub fn example_for(frame_id: u32, algo: StrategyKind, threshold: &str, feature: &str) -> Option<usize> {
    let t = parse_threshold(threshold).ok()?;
    let f = parse_feature(feature).ok()?;
    EXAMPLES
        .iter()
        .position(|ex| ex.frame == frame_id as usize && ex.algo == algo.name() && ex.threshold == t && ex.feature == f)
}

/// The example's strategy (the manual's `-a`; every example names one of the three).
pub fn example_kind(ex: &ManualExample) -> Option<StrategyKind> {
    StrategyKind::parse(ex.algo)
}

/// The mark beside the two values: equal as text, exactly as the manual prints it.
pub fn verdict(expected: &str, got: &str) -> (bool, &'static str) {
    if expected == got {
        (true, "✓ equal: siftlab prints the manual's value")
    } else {
        (false, "✗ differs from the manual's value")
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::lab::get_info_command;

    #[test]
    fn every_example_is_found_from_its_own_settings() {
        for (i, ex) in EXAMPLES.iter().enumerate() {
            let t = threshold_text(ex);
            let kind = example_kind(ex).unwrap();
            assert_eq!(example_for(ex.frame as u32, kind, &t, &ex.feature.to_string()), Some(i), "{}", ex.command());
            // What the box shows is what the manual's command line says after -t.
            assert_eq!(ex.command(), get_info_command(kind, &t, &ex.frame.to_string(), &ex.feature.to_string()));
        }
    }

    #[test]
    fn the_task_1_link_is_an_example_and_near_misses_are_not() {
        // ?src=demo&frame=150&feature=209&algo=dt&t=300
        assert_eq!(example_for(150, StrategyKind::Dt, "300", "209"), Some(1));
        assert_eq!(example_for(150, StrategyKind::Dt, " 300.0 ", "209"), Some(1));
        assert_eq!(example_for(150, StrategyKind::Nn, "", "209"), Some(2));
        assert_eq!(example_for(150, StrategyKind::Dt, "301", "209"), None);
        assert_eq!(example_for(149, StrategyKind::Dt, "300", "209"), None);
        assert_eq!(example_for(150, StrategyKind::Dt, "300", "208"), None);
        assert_eq!(example_for(150, StrategyKind::Nndr, "300", "209"), None);
        assert_eq!(example_for(150, StrategyKind::Dt, "abc", "209"), None);
    }

    #[test]
    fn the_mark_says_equal_or_differs() {
        assert!(verdict("((0, 0), [], [])", "((0, 0), [], [])").0);
        let (ok, text) = verdict("((0, 0), [], [])", "((1, 0), [], [])");
        assert!(!ok && text.starts_with('✗'));
    }
}
