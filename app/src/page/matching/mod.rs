//! The matching explorer, in the order of the lab's tasks: load the frames,
//! pick the strategy, look at the frames, read the result, follow the
//! explanation, check yourself (and the manual's examples beside them).

mod check;
mod controls;
mod explain;
mod frames;
mod load;
mod manual;
mod result;

pub use check::{Exercises, SelfCheck};
pub use controls::Controls;
pub use explain::{DistanceChart, Explanation};
pub use frames::FramesView;
pub use load::{Loader, Status};
pub use manual::{apply_example, current_example, ManualComparison, ManualExamples};
pub use result::ResultPanel;
