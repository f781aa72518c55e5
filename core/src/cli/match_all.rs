//! `siftlab match_all -a ALGO [-t T] FRAME_ID`: every match of the strategy
//! between frames FRAME_ID-1 and FRAME_ID, judged correct or wrong by the
//! ground-truth epipolar geometry (Sampson distance ≤ `--epipolar-px`), and
//! `matches.png` in the current folder, as the lab's view commands write
//! theirs.

use super::args::{Cli, MatchAllArgs};
use super::common::{expand_home, load_frame, parse_threshold, sift_params};
use crate::camera::Camera;
use crate::dataset::{parse_poses, POSES_FILE};
use crate::error::{Error, Result};
use crate::matching::args::parse_index;
use crate::matching::epipolar::{fundamental, judge, Verdicts};
use crate::matching::{match_all, DMatch, Strategy};
use crate::render::{encode_png, whole_frame};
use crate::sift::detect_and_compute;
use std::io::Write;
use std::path::Path;

pub fn run(cli: &Cli, a: &MatchAllArgs) -> Result<()> {
    let strategy = Strategy::parse(&a.algo, parse_threshold(&a.threshold)?)?;
    if !a.epipolar_px.is_finite() || a.epipolar_px < 0.0 {
        return Err(Error::InvalidArgument(format!(
            "--epipolar-px {} must be a distance in pixels >= 0 (2 is usual)",
            a.epipolar_px
        )));
    }
    let frame = parse_index(&a.frame_id, "FRAME_ID")?;
    if frame < 1 {
        return Err(Error::InvalidArgument("FRAME_ID must be >= 1: frames FRAME_ID-1 and FRAME_ID are matched".into()));
    }
    let root = expand_home(&cli.dataset);
    let params = sift_params(cli);
    let (prev_image, cur_image) = (load_frame(&root, frame - 1)?, load_frame(&root, frame)?);
    let (prev, cur) = (detect_and_compute(&prev_image, &params), detect_and_compute(&cur_image, &params));
    let all: Vec<DMatch> = match_all(&strategy, &prev, &cur)?.into_iter().flatten().collect();
    // Without the pose file the matches are counted, not judged.
    let verdicts = match std::fs::read_to_string(root.join(POSES_FILE)) {
        Ok(text) => {
            let poses = parse_poses(&text)?;
            let (Some(p0), Some(p1)) = (poses.get(frame - 1), poses.get(frame)) else {
                return Err(Error::Dataset(format!(
                    "{POSES_FILE} has {} poses, frame {frame} needs {}",
                    poses.len(),
                    frame + 1
                )));
            };
            let f = fundamental(p0, p1, &Camera::default())?;
            Some(judge(&f, &prev.keypoints, &cur.keypoints, &all, a.epipolar_px))
        }
        Err(_) => {
            eprintln!("no {POSES_FILE} in the dataset: counting matches without judging them");
            None
        }
    };
    let v = Verdicts { matches: all.len(), correct: verdicts.as_ref().map(|v| v.iter().filter(|&&b| b).count()) };
    let mut so = std::io::stdout().lock();
    let _ = writeln!(so, "{}", if a.json { to_json(&strategy, &v) } else { to_text(&strategy, &v, a.epipolar_px) });
    let _ = so.flush();
    let img = whole_frame::draw(&prev_image, &prev.keypoints, &cur_image, &cur.keypoints, &all, verdicts.as_deref())?;
    let out = Path::new("matches.png");
    std::fs::write(out, encode_png(&img)?)
        .map_err(|e| Error::Dataset(format!("cannot write {}: {e}", out.display())))?;
    eprintln!("wrote {} ({}x{})", out.display(), img.width(), img.height());
    Ok(())
}

fn json_num(v: Option<f64>) -> String {
    v.map_or("null".into(), |v| format!("{v:?}"))
}

/// `{"strategy", "threshold", "matches", "correct", "precision"}`; null for
/// no threshold, no ground truth or no matches.
pub fn to_json(s: &Strategy, v: &Verdicts) -> String {
    format!(
        "{{\"strategy\": \"{}\", \"threshold\": {}, \"matches\": {}, \"correct\": {}, \"precision\": {}}}",
        s.name(),
        json_num(s.threshold()),
        v.matches,
        v.correct.map_or("null".into(), |c| c.to_string()),
        json_num(v.precision())
    )
}

fn to_text(s: &Strategy, v: &Verdicts, px: f64) -> String {
    let t = s.threshold().map_or("no threshold".into(), |t| format!("threshold {t}"));
    match (v.correct, v.precision()) {
        (Some(c), Some(p)) => format!(
            "{} ({t}): {} matches, {c} correct within {px} px of the true epipolar line, precision {:.4}",
            s.name(),
            v.matches,
            p
        ),
        _ => format!("{} ({t}): {} matches", s.name(), v.matches),
    }
}
