//! The lab manual's seven worked `get_info` examples (Tasks 1–3) on KITTI 00,
//! with the value the manual prints for each. The app lists them one click
//! away and the tests check that siftlab prints exactly these values: they are
//! the manual's text, not siftlab's output.

use crate::matching::Strategy;

/// One `get_info -a ALGO [-t T] FRAME_ID FEATURE_ID` example of the manual.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ManualExample {
    /// Which task of the manual it illustrates.
    pub task: &'static str,
    /// `-a`: `dt`, `nn` or `nndr`.
    pub algo: &'static str,
    /// `-t`, if the example gives one.
    pub threshold: Option<f64>,
    /// The current frame; frame `frame - 1` is matched into it.
    pub frame: usize,
    /// The feature of frame `frame - 1`.
    pub feature: usize,
    /// The `ret value:` the manual prints.
    pub expected: &'static str,
}

impl ManualExample {
    /// The strategy the example's arguments give.
    pub fn strategy(&self) -> Strategy {
        // Every example's arguments are valid (see the test below).
        Strategy::parse(self.algo, self.threshold).expect("the manual's arguments are valid")
    }

    /// The command line, as the manual writes it: `get_info -a dt -t 100 150 209`.
    pub fn command(&self) -> String {
        let t = self.threshold.map_or(String::new(), |t| format!(" -t {t}"));
        format!("get_info -a {}{t} {} {}", self.algo, self.frame, self.feature)
    }
}

const DT_300: &str = "((226, 119), [(208, 115), (394, 52), (519, 213), (872, 160), (402, 48)], \
[72.02082824707031, 242.6643829345703, 282.074462890625, 290.75762939453125, 294.5997314453125])";
const ONE_MATCH_209: &str = "((226, 119), [(208, 115)], [72.02082824707031])";
const NO_MATCH: &str = "((0, 0), [], [])";

/// One row of [`EXAMPLES`]: `(task, algo, threshold, frame, feature, expected)`.
const fn example(
    task: &'static str,
    algo: &'static str,
    threshold: Option<f64>,
    frame: usize,
    feature: usize,
    expected: &'static str,
) -> ManualExample {
    ManualExample { task, algo, threshold, frame, feature, expected }
}

/// The manual's examples, in its order (Task 1: dt, Task 2: nn, Task 3: nndr).
#[rustfmt::skip]
pub const EXAMPLES: [ManualExample; 7] = [
    example("Task 1 (dt)", "dt", Some(100.0), 150, 209, ONE_MATCH_209),
    example("Task 1 (dt)", "dt", Some(300.0), 150, 209, DT_300),
    example("Task 2 (nn)", "nn", None, 150, 209, ONE_MATCH_209),
    example("Task 2 (nn)", "nn", Some(100.0), 150, 209, ONE_MATCH_209),
    example("Task 2 (nn)", "nn", Some(50.0), 150, 209, NO_MATCH),
    example("Task 3 (nndr)", "nndr", Some(0.97), 120, 45, "((22, 14), [(61, 163)], [156.46725463867188])"),
    example("Task 3 (nndr)", "nndr", Some(0.93), 120, 45, NO_MATCH),
];

/// The frames the examples need (each example matches `frame - 1` into `frame`).
pub fn frames() -> Vec<usize> {
    let mut f: Vec<usize> = EXAMPLES.iter().flat_map(|e| [e.frame - 1, e.frame]).collect();
    f.sort_unstable();
    f.dedup();
    f
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn commands_read_as_the_manual_writes_them() {
        let cmds: Vec<String> = EXAMPLES.iter().map(|e| e.command()).collect();
        assert_eq!(cmds[0], "get_info -a dt -t 100 150 209");
        assert_eq!(cmds[2], "get_info -a nn 150 209");
        assert_eq!(cmds[5], "get_info -a nndr -t 0.97 120 45");
        assert_eq!(frames(), vec![119, 120, 149, 150]);
        for e in &EXAMPLES {
            assert_eq!(e.strategy().name(), e.algo);
        }
    }
}
