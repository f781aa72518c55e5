//! The lab's arguments as text → values, with the CLI's messages (the app
//! shows the same ones), and the thresholds each view starts with.

use super::strategy::StrategyKind;
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
}
