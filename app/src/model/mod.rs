//! The page's state and plain logic, no DOM: the state of each view
//! ([`views`]: the explorer's [`lab`], the exercises, marking, see-inside),
//! parsing, the URL, frame sets, self-checks, the manual's examples, Python
//! literals, the KITTI sequence and its camera, the odometry views' logic
//! ([`odometry`]) and the figures' geometry.

pub mod class_results;
pub mod exercise;
pub mod frame;
pub mod frameset;
pub mod lab;
pub mod lab_manual;
pub mod mark;
pub mod odometry;
pub mod parse;
pub mod plot;
pub mod pylit;
pub mod see_inside;
pub mod selfcheck;
pub mod sequence;
pub mod urlstate;
pub mod views;
