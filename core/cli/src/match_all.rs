//! `siftlab match_all -a ALGO [-t T] FRAME_ID`: every match of the strategy
//! between frames FRAME_ID-1 and FRAME_ID, judged correct or wrong by the
//! ground-truth epipolar geometry (Sampson distance ≤ `--epipolar-px`), and
//! `matches.png` in the current folder, as the lab's view commands write
//! theirs: the matches as flow over the current frame (`--layout flow`, the
//! default) or both frames side by side (`--layout side`). `--json` adds
//! every match with its distance, Sampson distance and verdict.

use crate::args::{Cli, MatchAllArgs};
use crate::common::{note_camera, open_dataset, parse_threshold, sift_params};
use siftlab_core::error::{Error, Result};
use siftlab_core::matching::args::parse_frame_id;
use siftlab_core::matching::epipolar::{fundamental, sampsons, Verdicts};
use siftlab_core::matching::{match_all, DMatch, Strategy};
use siftlab_core::pyfmt::py_f32;
use siftlab_core::render::{encode_png, flow_frame, whole_frame};
use siftlab_core::sift::detect_and_compute;
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
    let frame = parse_frame_id(&a.frame_id)?;
    let ds = open_dataset(cli)?;
    let params = sift_params(cli);
    let (prev_image, cur_image) = (ds.load_frame(frame - 1)?, ds.load_frame(frame)?);
    let (prev, cur) = (detect_and_compute(&prev_image, &params), detect_and_compute(&cur_image, &params));
    let all: Vec<DMatch> = match_all(&strategy, &prev, &cur)?.into_iter().flatten().collect();
    // Without the pose file the matches are counted, not judged.
    let poses_file = ds.sequence().poses_file();
    let distances = if ds.has_poses() {
        let poses = ds.poses();
        let (Some(p0), Some(p1)) = (poses.get(frame - 1), poses.get(frame)) else {
            return Err(Error::Dataset(format!(
                "{poses_file} has {} poses, frame {frame} needs {}",
                poses.len(),
                frame + 1
            )));
        };
        note_camera(&ds);
        let f = fundamental(p0, p1, ds.camera())?;
        Some(sampsons(&f, &prev.keypoints, &cur.keypoints, &all))
    } else {
        eprintln!(
            "no {poses_file} in the dataset: counting matches without judging them (the epipolar judge needs the \
             ground-truth poses)"
        );
        None
    };
    // judge's rule, on the distances kept for --json.
    let verdicts: Option<Vec<bool>> = distances.as_ref().map(|d| d.iter().map(|&s| s <= a.epipolar_px).collect());
    let v = Verdicts { matches: all.len(), correct: verdicts.as_ref().map(|v| v.iter().filter(|&&b| b).count()) };
    let mut so = std::io::stdout().lock();
    if a.json {
        let records = records_json(&all, distances.as_deref(), a.epipolar_px);
        let counts = to_json(&strategy, &v);
        let _ = writeln!(so, "{}, \"records\": {records}}}", &counts[..counts.len() - 1]);
    } else {
        let _ = writeln!(so, "{}", to_text(&strategy, &v, a.epipolar_px));
    }
    let _ = so.flush();
    let img = match a.layout.as_str() {
        "side" => whole_frame(&prev_image, &prev.keypoints, &cur_image, &cur.keypoints, &all, verdicts.as_deref())?,
        _ => flow_frame(&cur_image, &prev.keypoints, &cur.keypoints, &all, verdicts.as_deref())?,
    };
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

/// The matches as a JSON array, one object a line, in `matches`' order:
/// `{"query": q, "train": t, "distance": d, "sampson": s, "correct": c}`.
/// `distance` is the f32 widened to f64 and printed as Python's `repr`, as
/// the lab prints distances (`get_info`); `sampson` is the f64 in Rust's
/// shortest round-trip form. Both are null without ground truth (`sampsons`
/// is `None`), and `sampson` also for the 0/0 of a match from epipole to
/// epipole, which is wrong (NaN ≤ px is false).
pub fn records_json(matches: &[DMatch], sampsons: Option<&[f64]>, px: f64) -> String {
    let mut out = String::with_capacity(24 + matches.len() * 96);
    out.push('[');
    for (i, m) in matches.iter().enumerate() {
        let s = sampsons.map(|s| s[i]);
        let correct = s.map_or("null", |s| if s <= px { "true" } else { "false" });
        let s = s.filter(|s| s.is_finite());
        out.push_str(if i == 0 { "\n" } else { ",\n" });
        out.push_str(&format!(
            "{{\"query\": {}, \"train\": {}, \"distance\": {}, \"sampson\": {}, \"correct\": {correct}}}",
            m.query_idx,
            m.train_idx,
            py_f32(m.distance),
            json_num(s)
        ));
    }
    out.push_str(if matches.is_empty() { "]" } else { "\n]" });
    out
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn records_print_distances_as_the_lab_and_sampsons_round_trip() {
        let m = |q, t, d| DMatch { query_idx: q, train_idx: t, distance: d };
        let all = [m(1, 928, 163.046_f32), m(7, 932, 225.0), m(7, 3, 4.0)];
        let s = [0.10891070720688335, 2.0, f64::NAN];
        assert_eq!(
            records_json(&all, Some(&s), 2.0),
            "[\n{\"query\": 1, \"train\": 928, \"distance\": 163.04600524902344, \"sampson\": 0.10891070720688335, \"correct\": true},\n\
             {\"query\": 7, \"train\": 932, \"distance\": 225.0, \"sampson\": 2.0, \"correct\": true},\n\
             {\"query\": 7, \"train\": 3, \"distance\": 4.0, \"sampson\": null, \"correct\": false}\n]"
        );
        assert_eq!(
            records_json(&all[..1], None, 2.0),
            "[\n{\"query\": 1, \"train\": 928, \"distance\": 163.04600524902344, \"sampson\": null, \"correct\": null}\n]"
        );
        assert_eq!(records_json(&[], None, 2.0), "[]");
    }
}
