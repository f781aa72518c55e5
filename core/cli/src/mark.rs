//! `siftlab mark vision_tasks.py [-n N] [--seed S] [--json] [--no-sandbox]`:
//! the student's file marked as the lab's automarker marks it
//! (docs/marking.md): the command, the frames and pairs a marking uses, and
//! the platforms' results files. The harness runs through `transport.rs`
//! (the native transport of `siftlab_mark::Session`). Exit status: 0 for
//! 20 / 20, 1 for fewer marks, 2 when the file could not be marked at all.

use crate::args::{Cli, MarkArgs};
use crate::common::{open_dataset, sift_params};
use crate::report_files::{atomic_write, gradescope_json, sha256_hex};
use crate::transport::Runner;
use siftlab_core::dataset::Dataset;
use siftlab_core::error::{Error, Result};
use siftlab_core::sift::{detect_and_compute, Features, SiftParams};
use siftlab_mark::{
    escaped, frames_needed, markable_frames, report_json, report_text, Case, Limits, Marks, Pair, Session,
};
use std::collections::HashMap;
use std::io::Write;
use std::time::Instant;

/// Runs `mark` on one file and returns the exit status.
pub fn main(cli: &Cli, a: &MarkArgs) -> i32 {
    match run(cli, a) {
        Ok(m) if m.full() => 0,
        Ok(_) => 1,
        Err(e) => {
            eprintln!("siftlab: error: {e}");
            2
        }
    }
}

/// Marks one file and prints the report (text, or JSON with `--json`);
/// with `--gradescope`, also writes Gradescope's results.json.
pub fn run(cli: &Cli, a: &MarkArgs) -> Result<Marks> {
    let [arg] = a.files.as_slice() else {
        return Err(Error::InvalidArgument(format!(
            "{} submissions given: mark one file, or a class with --out DIR",
            a.files.len()
        )));
    };
    if a.jobs.is_some() || a.resume || a.shard.is_some() {
        return Err(Error::InvalidArgument("--jobs, --resume and --shard go with --out DIR (a class)".into()));
    }
    let started = Instant::now();
    // A folder (Gradescope's /autograder/submission): its first vision_tasks.py.
    let file = crate::submissions::single(arg)?;
    let n = a.n as usize;
    let Some(file) = file else {
        let marks = Marks::new(a.seed, n, Vec::new());
        eprintln!("siftlab: {} scores 0: no vision_tasks.py in it", arg.display());
        let text = format!("{}: 0.00 / 20\nscores 0: no vision_tasks.py was found in the submission\n", arg.display());
        write_platform_results(a, &marks, &text, true, "not run", started, &[])?;
        return Ok(marks);
    };
    let name = file.file_name().map_or_else(|| file.display().to_string(), |n| n.to_string_lossy().into_owned());
    let src = crate::submissions::read_single(arg, &file)?;
    let mut tier = "not run";
    let mut pictures = Vec::new();
    let marks = match crate::submissions::checked(&src) {
        Err(rejection) => {
            eprintln!("siftlab: {name} scores 0: {rejection}");
            Marks::rejected(a.seed, n, rejection)
        }
        Ok(source) => {
            let ds = open_dataset(cli)?;
            let frames = frame_ids(&ds)?;
            let runner = Runner::new(a.no_sandbox)?;
            tier = runner.tier.name();
            eprintln!(
                "marking {name}: {n} calls per task, seed {}, frames 1 to {} of {}",
                a.seed,
                frames.len(),
                ds.root().display()
            );
            // SIFT of each frame the cases use, once, as a class marking does.
            let (pairs, _) = frame_pairs(&ds, &sift_params(cli), &siftlab_mark::plan(a.seed, n, &frames), false)?;
            let session = Session::new(source, a.seed, n, &frames, Limits::default());
            let marks = runner.mark(session, &pairs, 0, true)?;
            if a.prairielearn.is_some() {
                pictures = crate::pictures::first_wrong(&marks, &ds, &pairs);
            }
            marks
        }
    };
    let text = format!("{}: {:.2} / 20\n{}", escaped(&name, 200), marks.total, report_text(&marks));
    let mut out = std::io::stdout().lock();
    if a.json {
        let _ = writeln!(out, "{}", report_json(&marks));
    } else {
        let _ = write!(out, "{text}");
    }
    let _ = out.flush();
    write_platform_results(a, &marks, &text, false, tier, started, &pictures)?;
    Ok(marks)
}

/// `--gradescope` and `--prairielearn`: each platform's results.json, written
/// whole (a temporary file and a rename), after the marking is over.
fn write_platform_results(
    a: &MarkArgs,
    marks: &Marks,
    text: &str,
    none_found: bool,
    tier: &str,
    started: Instant,
    pictures: &[crate::pictures::Picture],
) -> Result<()> {
    if let Some(g) = &a.gradescope {
        atomic_write(g, gradescope_json(marks, text, none_found, tier, started.elapsed().as_secs_f64()).as_bytes())?;
    }
    if let Some(p) = &a.prairielearn {
        atomic_write(p, crate::report_files::prairielearn_json(marks, text, none_found, tier, pictures).as_bytes())?;
    }
    Ok(())
}

/// The pairs the cases use, SIFT of each frame once, and (with
/// `fingerprint`) a SHA-256 over the frames' pixels, for `--resume`.
pub(crate) fn frame_pairs(
    ds: &Dataset,
    params: &SiftParams,
    cases: &[Case],
    fingerprint: bool,
) -> Result<(Vec<Pair>, String)> {
    let mut frames: HashMap<u32, Features> = HashMap::new();
    let mut digests = Vec::new();
    for g in frames_needed(cases) {
        let img = ds.load_frame(g as usize)?;
        if fingerprint {
            let mut bytes = format!("{g}:{}x{}:", img.width(), img.height()).into_bytes();
            bytes.extend_from_slice(img.data());
            digests.extend_from_slice(sha256_hex(&bytes).as_bytes());
        }
        frames.insert(g, detect_and_compute(&img, params));
    }
    let ids: std::collections::BTreeSet<u32> = cases.iter().map(Case::frame).collect();
    let pairs = ids.iter().map(|&f| Pair { id: f, prev: frames[&(f - 1)].clone(), cur: frames[&f].clone() }).collect();
    Ok((pairs, if fingerprint { sha256_hex(&digests) } else { String::new() }))
}

/// The FRAME_IDs a marking may draw from the dataset's frames
/// (`siftlab_mark::markable_frames`: each with its previous frame).
pub(crate) fn frame_ids(ds: &Dataset) -> Result<Vec<u32>> {
    let count = ds.frame_count() as u32;
    let frames = markable_frames(&(0..count).collect::<Vec<_>>());
    if frames.is_empty() {
        return Err(Error::Dataset(format!(
            "{} has {count} frame(s) in {}/ from 000000.png on: marking needs at least two",
            ds.root().display(),
            ds.sequence().frame_dir()
        )));
    }
    Ok(frames)
}
