//! What the commands share: the SIFT parameters the flags ask for, the
//! dataset's frames, and the matched pair the visual commands draw.

use super::args::Cli;
use crate::error::{Error, Result};
use crate::image::GrayImage;
use crate::sift::{Features, SiftParams};
use std::path::{Path, PathBuf};

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
    pub matches: Vec<crate::matching::DMatch>,
}

pub(crate) fn parse_threshold(s: &Option<String>) -> Result<Option<f64>> {
    s.as_deref().map(crate::matching::args::parse_threshold).transpose()
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

/// The lab's frame file: `gray/00/image_0/%06d.png` under the dataset.
pub fn frame_path(root: &Path, id: usize) -> PathBuf {
    root.join("gray").join("00").join("image_0").join(format!("{id:06}.png"))
}

pub(crate) fn load_frame(root: &Path, id: usize) -> Result<GrayImage> {
    let path = frame_path(root, id);
    let bytes = std::fs::read(&path).map_err(|e| {
        if !root.is_dir() {
            Error::Dataset(format!(
                "dataset folder {} not found: pass the MyKITTI folder with -d (it holds gray/00/image_0/ and poses/00.txt)",
                root.display()
            ))
        } else {
            Error::Dataset(format!(
                "cannot read frame {id}: {} ({e}); the dataset needs gray/00/image_0/{id:06}.png",
                path.display()
            ))
        }
    })?;
    GrayImage::decode(&bytes).map_err(|e| Error::Decode(format!("frame {} : {e}", path.display())))
}
