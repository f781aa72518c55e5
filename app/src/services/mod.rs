//! The page side of the workers and of file I/O: the SIFT pool and its cache
//! ([`sift_pool`]), odometry runs ([`odometry`]), the see-inside jobs
//! ([`inside`]), the explorer's loading jobs ([`loading`]) and where frames
//! and poses come from: the demo, files and folders ([`sources`]).

pub mod inside;
pub mod loading;
pub mod mark;
pub mod odometry;
pub mod sift_pool;
pub mod sources;
pub mod worker_handle;
