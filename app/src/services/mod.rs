//! The page side of the workers and of file I/O: the SIFT pool and its cache
//! ([`sift_pool`]), odometry runs ([`odometry`]), the see-inside jobs
//! ([`inside`]) and loading frames from the demo, files and folders
//! ([`loading`]).

pub mod inside;
pub mod loading;
pub mod mark;
pub mod odometry;
pub mod sift_pool;
pub mod worker_handle;
