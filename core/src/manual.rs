//! The lab manual's eight worked `get_info` examples on KITTI 00 (the
//! introduction's `view_feature` one, then Tasks 1–3), with the value the
//! manual prints for each. The app lists them one click away and the tests
//! check that siftlab prints exactly these values: they are the manual's text,
//! not siftlab's output. One example's printed tuple came from a build whose
//! keypoint order differs from OpenCV 4.8.0.76's; [`Differs`] says where it is.

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
    /// Set when OpenCV 4.8.0.76 (and so siftlab) prints another value.
    pub differs: Option<Differs>,
}

/// An example whose printed tuple OpenCV 4.8.0.76 does not give at the
/// manual's feature index: the build that made the manual ordered the frame's
/// keypoints a little differently, so the same keypoint has another index.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Differs {
    /// What OpenCV 4.8.0.76 and siftlab print for the manual's arguments.
    pub siftlab: &'static str,
    /// The index at which OpenCV 4.8.0.76 gives the manual's tuple.
    pub feature: usize,
}

impl ManualExample {
    /// The strategy the example's arguments give.
    pub fn strategy(&self) -> Strategy {
        // Every example's arguments are valid (see the test below).
        Strategy::parse(self.algo, self.threshold).expect("the manual's arguments are valid")
    }

    /// The command line, as the manual writes it: `get_info -a dt -t 100 150 209`.
    pub fn command(&self) -> String {
        self.command_for(self.feature)
    }

    /// The command line with another feature index (the one [`Differs`] names).
    pub fn command_for(&self, feature: usize) -> String {
        let t = self.threshold.map_or(String::new(), |t| format!(" -t {t}"));
        format!("get_info -a {}{t} {} {feature}", self.algo, self.frame)
    }

    /// What siftlab (OpenCV 4.8.0.76) prints for the manual's arguments.
    pub fn siftlab_value(&self) -> &'static str {
        self.differs.map_or(self.expected, |d| d.siftlab)
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
    ManualExample { task, algo, threshold, frame, feature, expected, differs: None }
}

/// The introduction's example (`view_feature` / `get_info -a dt -t 232.5 101
/// 127`): OpenCV 4.8.0.76, with IPP on or off, prints [`Differs::siftlab`] for
/// it and the manual's tuple for feature 132 of frame 100.
const INTRO: ManualExample = ManualExample {
    task: "Intro (view_feature)",
    algo: "dt",
    threshold: Some(232.5),
    frame: 101,
    feature: 127,
    expected: "((1066, 152), [(1032, 152), (1033, 9)], [70.21395874023438, 172.14529418945312])",
    differs: Some(Differs {
        siftlab: "((1068, 47), [(1033, 47), (1032, 44)], [60.4400520324707, 105.0])",
        feature: 132,
    }),
};

/// The manual's examples, in its order (the introduction, then Task 1: dt,
/// Task 2: nn, Task 3: nndr).
#[rustfmt::skip]
pub const EXAMPLES: [ManualExample; 8] = [
    INTRO,
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
        assert_eq!(cmds[0], "get_info -a dt -t 232.5 101 127");
        assert_eq!(EXAMPLES[0].command_for(132), "get_info -a dt -t 232.5 101 132");
        assert_eq!(cmds[1], "get_info -a dt -t 100 150 209");
        assert_eq!(cmds[3], "get_info -a nn 150 209");
        assert_eq!(cmds[6], "get_info -a nndr -t 0.97 120 45");
        assert_eq!(frames(), vec![100, 101, 119, 120, 149, 150]);
        assert_eq!(EXAMPLES.iter().filter(|e| e.differs.is_some()).count(), 1);
        for e in &EXAMPLES {
            assert_eq!(e.strategy().name(), e.algo);
        }
    }
}
