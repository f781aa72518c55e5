//! The lab's arguments as text → values, with the CLI's messages (the app
//! shows the same ones), and the thresholds each view starts with.

use super::kind::StrategyKind;
use crate::{Error, Result};

/// A threshold as typed (`-t`, or the app's box): a number.
pub fn parse_threshold(text: &str) -> Result<f64> {
    text.trim().parse::<f64>().map_err(|_| Error::InvalidArgument(format!("threshold must be a number, got '{text}'")))
}

/// A FRAME_ID or FEATURE_ID (`what`) as typed: a whole number ≥ 0.
pub fn parse_index(text: &str, what: &str) -> Result<usize> {
    let v: i64 = text
        .trim()
        .parse()
        .map_err(|_| Error::InvalidArgument(format!("{what} must be a whole number, got '{text}'")))?;
    if v < 0 {
        return Err(Error::InvalidArgument(format!("{what} must be >= 0, got {v}")));
    }
    Ok(v as usize)
}

/// The FRAME_ID of a pair (`get_info`, `view_feature`, `view_info`,
/// `match_all`) as typed: a whole number ≥ 1, since frames FRAME_ID-1 and
/// FRAME_ID are matched. Text that is not a whole number ≥ 0 gets
/// [`parse_index`]'s messages, 0 one of its own. A `usize` like the
/// dataset's frame numbers: a FRAME_ID past the dataset is the dataset's to
/// report (it names the missing frame).
pub fn parse_frame_id(text: &str) -> Result<usize> {
    let frame = parse_index(text, "FRAME_ID")?;
    if frame < 1 {
        return Err(Error::InvalidArgument("FRAME_ID must be >= 1: frames FRAME_ID-1 and FRAME_ID are matched".into()));
    }
    Ok(frame)
}

/// Checks FEATURE_ID `feature` against the `n_keypoints` keypoints of the
/// query frame (the previous one). `frame` is that frame's number when the
/// caller knows it (the CLI's message names it); without it the message says
/// "the previous frame".
pub fn check_feature_id(feature: usize, n_keypoints: usize, frame: Option<usize>) -> Result<()> {
    if feature < n_keypoints {
        return Ok(());
    }
    let n = n_keypoints;
    Err(Error::InvalidArgument(match frame {
        // No keypoints: no id is valid, so no range to give.
        Some(frame) if n == 0 => format!(
            "FEATURE_ID {feature} is out of range: frame {frame} has no keypoints, so it has no feature to show \
             (pick another frame)"
        ),
        Some(frame) => {
            format!("FEATURE_ID {feature} is out of range: frame {frame} has {n} keypoints (valid: 0 to {})", n - 1)
        }
        None if n == 0 => format!("feature id {feature} is out of range: the previous frame has no keypoints"),
        None => format!(
            "feature id {feature} is out of range: the previous frame has {n} keypoints (valid ids: 0 to {})",
            n - 1
        ),
    }))
}

/// nndr's ratio in every view that starts with one (Lowe's 0.8).
pub const NNDR_RATIO: f64 = 0.8;

/// The threshold a strategy starts with in the matching views: dt 100 (a
/// distance most of the lab's features have a few matches under), nn none.
pub fn matching_default(kind: StrategyKind) -> Option<f64> {
    match kind {
        StrategyKind::Dt => Some(100.0),
        StrategyKind::Nn => None,
        StrategyKind::Nndr => Some(NNDR_RATIO),
    }
}

/// The threshold a strategy starts with as the odometry's tracker: dt 200,
/// where consecutive KITTI frames still give the loop enough matches.
pub fn odometry_default(kind: StrategyKind) -> Option<f64> {
    match kind {
        StrategyKind::Dt => Some(200.0),
        StrategyKind::Nn => None,
        StrategyKind::Nndr => Some(NNDR_RATIO),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn messages_and_defaults() {
        assert_eq!(parse_threshold(" 232.5 ").unwrap(), 232.5);
        assert_eq!(parse_threshold("x").unwrap_err().to_string(), "threshold must be a number, got 'x'");
        assert_eq!(parse_index("42", "FEATURE_ID").unwrap(), 42);
        assert_eq!(parse_index("-1", "FEATURE_ID").unwrap_err().to_string(), "FEATURE_ID must be >= 0, got -1");
        assert_eq!(parse_index("a", "FRAME_ID").unwrap_err().to_string(), "FRAME_ID must be a whole number, got 'a'");
        assert_eq!(matching_default(StrategyKind::Dt), Some(100.0));
        assert_eq!(odometry_default(StrategyKind::Dt), Some(200.0));
        assert_eq!(odometry_default(StrategyKind::Nn), None);
    }

    #[test]
    fn frame_id_messages() {
        assert_eq!(parse_frame_id("1").unwrap(), 1);
        assert_eq!(parse_frame_id(" 150 ").unwrap(), 150);
        assert_eq!(
            parse_frame_id("0").unwrap_err().to_string(),
            "FRAME_ID must be >= 1: frames FRAME_ID-1 and FRAME_ID are matched"
        );
        assert_eq!(parse_frame_id("-3").unwrap_err().to_string(), "FRAME_ID must be >= 0, got -3");
        assert_eq!(parse_frame_id("x").unwrap_err().to_string(), "FRAME_ID must be a whole number, got 'x'");
        assert_eq!(parse_frame_id("1.5").unwrap_err().to_string(), "FRAME_ID must be a whole number, got '1.5'");
    }

    #[test]
    fn feature_id_messages() {
        assert!(check_feature_id(0, 1, Some(0)).is_ok());
        assert!(check_feature_id(1499, 1500, None).is_ok());
        assert_eq!(
            check_feature_id(1500, 1500, Some(149)).unwrap_err().to_string(),
            "FEATURE_ID 1500 is out of range: frame 149 has 1500 keypoints (valid: 0 to 1499)"
        );
        assert_eq!(
            check_feature_id(0, 0, Some(3)).unwrap_err().to_string(),
            "FEATURE_ID 0 is out of range: frame 3 has no keypoints, so it has no feature to show (pick another frame)"
        );
        assert_eq!(
            check_feature_id(7, 5, None).unwrap_err().to_string(),
            "feature id 7 is out of range: the previous frame has 5 keypoints (valid ids: 0 to 4)"
        );
        assert_eq!(
            check_feature_id(0, 0, None).unwrap_err().to_string(),
            "feature id 0 is out of range: the previous frame has no keypoints"
        );
    }
}
