//! `view_feature` and `view_info`: the lab's `opencv_visual.png` and
//! `custom_visual.png`. Like `run_odometry.py`, both print `ret value: None`
//! after writing the image (the lab's methods return nothing, so it prints
//! no `ret count`).

use crate::common::MatchContext;
use siftlab_core::error::{Error, Result};
use siftlab_core::matching::MatchInfo;
use siftlab_core::render::{encode_png, info, matches, RgbImage};
use std::io::Write;
use std::path::Path;

fn write_png(img: &RgbImage, out: &Path) -> Result<()> {
    let bytes = encode_png(img)?;
    std::fs::write(out, bytes).map_err(|e| Error::Dataset(format!("cannot write {}: {e}", out.display())))?;
    let mut so = std::io::stdout().lock();
    let _ = writeln!(so, "ret value: None");
    let _ = so.flush();
    eprintln!("wrote {} ({}x{})", out.display(), img.width(), img.height());
    Ok(())
}

/// `cv2.drawMatchesKnn(prev, prev_kp, cur, cur_kp, matches[feature:feature+1], None, flags=2)`.
pub fn view_feature(ctx: &MatchContext, _info: &MatchInfo, out: &Path) -> Result<()> {
    let img =
        matches::draw_feature(&ctx.prev_image, &ctx.prev.keypoints, &ctx.cur_image, &ctx.cur.keypoints, &ctx.matches)?;
    write_png(&img, out)
}

/// The drawMatchesKnn image above both frames with the `matching_info` circles.
pub fn view_info(ctx: &MatchContext, info: &MatchInfo, out: &Path) -> Result<()> {
    let img = info::draw(&ctx.prev_image, &ctx.prev.keypoints, &ctx.cur_image, &ctx.cur.keypoints, &ctx.matches, info)?;
    write_png(&img, out)
}
