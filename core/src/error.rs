//! One error type for the whole core: every message says what is wrong and
//! what to do about it, because students read them.

use std::fmt;

#[derive(Debug, Clone, PartialEq)]
pub enum Error {
    /// The bytes are not a PNG/JPEG image, or the image is corrupt/truncated.
    Decode(String),
    /// The image is larger than the pixel limit.
    TooLarge { width: u32, height: u32, limit: u64 },
    /// A file of the dataset is missing or unreadable.
    Dataset(String),
    /// An argument is out of range (frame id, feature id, threshold, ...).
    InvalidArgument(String),
    /// Anything the VO pipeline cannot do with its input.
    Odometry(String),
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::Decode(m) => write!(f, "{m}"),
            Error::TooLarge { width, height, limit } => write!(
                f,
                "image is {width}x{height} = {} pixels, above the limit of {limit} pixels; \
                 scale it down (KITTI frames are 1241x376)",
                *width as u64 * *height as u64
            ),
            Error::Dataset(m) => write!(f, "{m}"),
            Error::InvalidArgument(m) => write!(f, "{m}"),
            Error::Odometry(m) => write!(f, "{m}"),
        }
    }
}

impl std::error::Error for Error {}

pub type Result<T> = std::result::Result<T, Error>;
