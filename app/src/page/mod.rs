//! The page, grouped by feature over the role layers (a feature's
//! components here, its logic in `model`, its workers behind `services`):
//! the matching explorer, "see inside" (SIFT's anatomy, whole-frame
//! matching), the odometry, "Mark my code" and the class's results; `app`
//! puts them in the lab's order and keeps the link in step. Widgets more than
//! one feature uses sit beside them: the figures' legend, the descriptor
//! drawing, reading a file input or a drop.

mod app;
mod class_results;
mod descriptor;
mod file_input;
mod legend;
mod mark;
mod matching;
mod odometry;
mod see_inside;

pub use app::{apply_url, url_state, App, Explorer, DEMO_FEATURE};
pub use descriptor::DescriptorGrid;
pub use matching::{
    apply_example, current_example, Controls, DistanceChart, Exercises, Explanation, FramesView, Loader,
    ManualComparison, ManualExamples, ResultPanel, SelfCheck, Status,
};
pub use odometry::OdometryView;
pub use see_inside::SeeInside;
