//! The page, in the order of the lab's tasks: load frames, pick the strategy,
//! look at the frames, read the result, follow the explanation, check yourself.

mod anatomy;
mod app;
mod canvas2d;
mod check;
mod controls;
mod explain;
mod frames;
mod legend;
mod load;
mod manual;
mod mark;
mod result;
mod see_inside;
mod trajectory;
mod vo_compare;
mod vo_frame;
mod vo_plot;
mod whole_frame;

pub use app::{apply_url, url_state, App, Explorer, DEMO_FEATURE};
pub use check::{Exercises, SelfCheck};
pub use controls::Controls;
pub use explain::{DescriptorGrid, DistanceChart, Explanation};
pub use frames::FramesView;
pub use load::{Loader, Status};
pub use manual::{apply_example, current_example, ManualComparison, ManualExamples};
pub use result::ResultPanel;
pub use see_inside::SeeInside;
pub use trajectory::TrajectoryView;
