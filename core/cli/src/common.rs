//! What the commands share: the SIFT parameters the flags ask for, the
//! dataset's frames, and the matched pair the visual commands draw.

use crate::args::Cli;
use siftlab_core::dataset::Dataset;
use siftlab_core::error::Result;
use siftlab_core::image::GrayImage;
use siftlab_core::sift::{Features, SiftParams};
use std::path::PathBuf;

pub(crate) fn sift_params(cli: &Cli) -> SiftParams {
    match cli.opencv_lanes.as_deref() {
        Some("16") => SiftParams { opencv_lanes: 16, ..SiftParams::default() },
        Some(_) => SiftParams::default(),
        None => SiftParams::for_host(),
    }
}

/// Everything the visual commands need besides the result tuple.
pub struct MatchContext {
    pub prev_image: GrayImage,
    pub cur_image: GrayImage,
    pub prev: Features,
    pub cur: Features,
    pub feature: usize,
    pub matches: Vec<siftlab_core::matching::DMatch>,
}

pub(crate) fn parse_threshold(s: &Option<String>) -> Result<Option<f64>> {
    s.as_deref().map(siftlab_core::matching::args::parse_threshold).transpose()
}

/// `~` expands like the lab's `os.path.expanduser`.
pub(crate) fn expand_home(p: &str) -> PathBuf {
    if let Some(rest) = p.strip_prefix("~") {
        if rest.is_empty() || rest.starts_with('/') {
            if let Some(home) = std::env::var_os("HOME") {
                return PathBuf::from(format!("{}{rest}", home.to_string_lossy()));
            }
        }
    }
    PathBuf::from(p)
}

/// The sequence `-d` and `-s` name, in whichever layout holds it.
pub(crate) fn open_dataset(cli: &Cli) -> Result<Dataset> {
    Dataset::open_sequence(&expand_home(&cli.dataset), &cli.sequence)
}

/// Says once, on stderr, which camera a command that uses it runs with
/// when it is not the sequence's own `calib.txt`.
pub(crate) fn note_camera(ds: &Dataset) {
    if let Some(note) = ds.camera_note() {
        eprintln!("{note}");
    }
}
