//! The page, grouped by feature over the role layers (a feature's
//! components here, its logic in `model`, its workers behind `services`):
//! the matching explorer, "see inside" (SIFT's anatomy, whole-frame
//! matching), the odometry, and "Mark my code"; `app` puts them in the
//! lab's order and keeps the link in step.

mod app;
mod class_results;
mod legend;
mod mark;
mod matching;
mod odometry;
mod see_inside;

pub use app::{apply_url, url_state, App, Explorer, DEMO_FEATURE};
pub use matching::{
    apply_example, current_example, Controls, DescriptorGrid, DistanceChart, Exercises, Explanation, FramesView,
    Loader, ManualComparison, ManualExamples, ResultPanel, SelfCheck, Status,
};
pub use odometry::OdometryView;
pub use see_inside::SeeInside;
