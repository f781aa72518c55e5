//! The lab manual's eight `get_info` examples ([`siftlab_core::manual::EXAMPLES`])
//! as the explorer's settings: what a click on one puts in the controls, and
//! which example (if any) the current view is, so the manual's printed value
//! can be shown beside siftlab's whichever way the view got there (a click, a
//! link, or typing the same settings). The introduction's example is also
//! "the view" at feature 132, where OpenCV 4.8.0.76 has the manual's keypoint.

use crate::model::parse::{parse_feature, parse_threshold};
use siftlab_core::manual::{ManualExample, EXAMPLES};
use siftlab_core::matching::StrategyKind;

/// The threshold box's text for an example, as the manual writes `-t`
/// (`100`, `0.97`; empty for `nn` without one).
pub fn example_threshold_box(ex: &ManualExample) -> String {
    ex.threshold.map(|t| t.to_string()).unwrap_or_default()
}

/// The example the settings are, by value: the threshold as a number (so
/// `300` and `300.0` are the same `-t`, as the lab's argparse reads it), the
/// feature as a whole number: the manual's, or the index OpenCV 4.8.0.76
/// gives its keypoint when the two differ.
pub fn example_for(frame_id: u32, algo: StrategyKind, threshold: &str, feature: &str) -> Option<usize> {
    let t = parse_threshold(threshold).ok()?;
    let f = parse_feature(feature).ok()?;
    EXAMPLES.iter().position(|ex| {
        ex.frame == frame_id as usize
            && ex.algo == algo.name()
            && ex.threshold == t
            && (ex.feature == f || ex.differs.is_some_and(|d| d.feature == f))
    })
}

/// How siftlab's value should read against the manual's for `ex` viewed at
/// `feature`: (the value siftlab should print, the mark when it does). At the
/// manual's index of the one differing example that is OpenCV 4.8.0.76's
/// other tuple; at the moved index, the manual's own.
pub fn expectation(ex: &ManualExample, feature: usize) -> (&'static str, String) {
    match ex.differs {
        Some(d) if feature == d.feature => (
            ex.expected,
            format!(
                "✓ equal: feature {} here is the manual's feature {} (OpenCV 4.8.0.76 orders this frame's keypoints a little differently from the manual's build)",
                d.feature, ex.feature
            ),
        ),
        Some(d) => (
            d.siftlab,
            format!(
                "≠ the manual's tuple, as OpenCV 4.8.0.76 prints it too: the manual's build ordered frame {}'s keypoints differently, and its feature {} is feature {} here",
                ex.frame - 1,
                ex.feature,
                d.feature
            ),
        ),
        None => (ex.expected, "✓ equal: siftlab prints the manual's value".into()),
    }
}

/// The example's strategy (the manual's `-a`; every example names one of the three).
pub fn example_kind(ex: &ManualExample) -> Option<StrategyKind> {
    StrategyKind::parse(ex.algo)
}

/// The mark beside the two values: siftlab's is what OpenCV 4.8.0.76 prints
/// ([`expectation`]), as text.
pub fn verdict(ex: &ManualExample, feature: usize, got: &str) -> (bool, String) {
    let (want, ok) = expectation(ex, feature);
    if want == got {
        (true, ok)
    } else if ex.differs.is_some() {
        (false, format!("✗ differs from OpenCV 4.8.0.76's value {want}"))
    } else {
        (false, "✗ differs from the manual's value".into())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::lab::get_info_command;

    #[test]
    fn every_example_is_found_from_its_own_settings() {
        for (i, ex) in EXAMPLES.iter().enumerate() {
            let t = example_threshold_box(ex);
            let kind = example_kind(ex).unwrap();
            assert_eq!(example_for(ex.frame as u32, kind, &t, &ex.feature.to_string()), Some(i), "{}", ex.command());
            // What the box shows is what the manual's command line says after -t.
            assert_eq!(ex.command(), get_info_command(kind, &t, &ex.frame.to_string(), &ex.feature.to_string()));
        }
    }

    #[test]
    fn the_task_1_link_is_an_example_and_near_misses_are_not() {
        // ?src=demo&frame=150&feature=209&algo=dt&t=300
        assert_eq!(example_for(150, StrategyKind::Dt, "300", "209"), Some(2));
        assert_eq!(example_for(150, StrategyKind::Dt, " 300.0 ", "209"), Some(2));
        assert_eq!(example_for(150, StrategyKind::Nn, "", "209"), Some(3));
        assert_eq!(example_for(150, StrategyKind::Dt, "301", "209"), None);
        assert_eq!(example_for(149, StrategyKind::Dt, "300", "209"), None);
        assert_eq!(example_for(150, StrategyKind::Dt, "300", "208"), None);
        assert_eq!(example_for(150, StrategyKind::Nndr, "300", "209"), None);
        assert_eq!(example_for(150, StrategyKind::Dt, "abc", "209"), None);
    }

    #[test]
    fn the_mark_says_equal_or_differs() {
        let nn50 = &EXAMPLES[5];
        assert_eq!(nn50.expected, "((0, 0), [], [])");
        assert!(verdict(nn50, 209, "((0, 0), [], [])").0);
        let (ok, text) = verdict(nn50, 209, "((1, 0), [], [])");
        assert!(!ok && text.starts_with('✗'));
    }

    #[test]
    fn the_introductions_example_reads_at_both_indices() {
        let intro = &EXAMPLES[0];
        assert_eq!(example_for(101, StrategyKind::Dt, "232.5", "127"), Some(0));
        assert_eq!(example_for(101, StrategyKind::Dt, "232.5", "132"), Some(0));
        assert_eq!(example_for(101, StrategyKind::Dt, "232.5", "131"), None);
        let ours = "((1068, 47), [(1033, 47), (1032, 44)], [60.4400520324707, 105.0])";
        let (ok, text) = verdict(intro, 127, ours);
        assert!(ok && text.starts_with('≠') && text.contains("feature 132 here"), "{text}");
        let (ok, text) = verdict(intro, 132, intro.expected);
        assert!(ok && text.starts_with('✓'), "{text}");
        assert!(!verdict(intro, 127, intro.expected).0, "the manual's tuple at 127 would be a different SIFT");
    }
}
