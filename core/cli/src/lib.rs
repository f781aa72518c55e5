//! The `siftlab` command line: the lab's `run_odometry.py` interface
//! (`get_info`, `view_feature`, `view_info`, `view_trajectory`) plus `sift`.
//! Arguments are checked here with messages that say what to do; the work is
//! done by the library.
//!
//! Native only: on wasm32 this crate is empty (its binary an empty `main`).
#![cfg(not(target_arch = "wasm32"))]

pub mod anatomy;
pub mod args;
mod autograder;
mod cgroup;
pub mod class;
pub mod common;
mod container;
mod harness_io;
pub mod mark;
pub mod match_all;
mod meter;
mod pictures;
mod report_files;
mod sandbox;
mod seal;
mod seccomp;
mod submissions;
mod summary;
pub mod trajectory;
mod transport;
pub mod visual;
mod zip;

pub use args::{AnatomyArgs, Cli, Command, MarkArgs, MatchAllArgs, MatchArgs, SiftArgs, TrajectoryArgs};
use clap::Parser;
use common::{open_dataset, parse_threshold, sift_params, MatchContext};
use siftlab_core::error::{Error, Result};
use siftlab_core::image::GrayImage;
use siftlab_core::matching::args::{check_feature_id, parse_frame_id, parse_index};
use siftlab_core::matching::{match_feature, matching_info, MatchInfo, Strategy};
use siftlab_core::pyfmt::{py_float, py_str};
use siftlab_core::sift::{detect_and_compute, Features};
use std::io::Write;
use std::path::Path;

/// Runs the CLI; returns the process exit code.
pub fn main() -> i32 {
    let cli = Cli::parse();
    // SIFTLAB_SIMD caps the kernels (see `siftlab_core::simd`): results are the same
    // at every level, only the time differs.
    if let Some(v) = std::env::var_os("SIFTLAB_SIMD") {
        match v.to_str().and_then(siftlab_core::simd::SimdLevel::parse) {
            Some(level) => siftlab_core::simd::set_cap(level),
            None => {
                eprintln!(
                    "siftlab: error: SIFTLAB_SIMD={} is not a SIMD level: use scalar, avx2 or avx512 (or unset it)",
                    v.to_string_lossy()
                );
                return 2;
            }
        }
    }
    match run(&cli) {
        Ok(code) => code,
        Err(e) => {
            eprintln!("siftlab: error: {e}");
            1
        }
    }
}

/// Runs one command; its exit status (mark's says whether the file got
/// full marks; the others 0), or the error to print (status 1).
fn run(cli: &Cli) -> Result<i32> {
    let done: Result<()> = match &cli.command {
        Command::GetInfo(a) => {
            let (info, _) = run_match(cli, a, "get_info")?;
            let mut out = std::io::stdout().lock();
            let _ = writeln!(out, "ret value: {info}");
            let _ = writeln!(out, "ret count: 3");
            Ok(())
        }
        Command::ViewFeature(a) => {
            let (info, ctx) = run_match(cli, a, "view_feature")?;
            visual::view_feature(&ctx, &info, Path::new("opencv_visual.png"))
        }
        Command::ViewInfo(a) => {
            let (info, ctx) = run_match(cli, a, "view_info")?;
            visual::view_info(&ctx, &info, Path::new("custom_visual.png"))
        }
        Command::ViewTrajectory(a) => {
            let last = match &a.frame_id {
                None => None,
                Some(s) => Some(parse_index(s, "FRAME_ID")?),
            };
            let threshold = parse_threshold(&a.threshold)?;
            let strategy = a.algo.as_deref().map(|algo| Strategy::parse(algo, threshold)).transpose()?;
            // The lab's three stdout lines; progress and siftlab's own summary
            // go to stderr, so stdout compares with the lab's as it is.
            let args = last.map_or(String::new(), |l| format!("{l},"));
            let algo = a.algo.as_deref().map_or("None".to_string(), py_str);
            let t_repr = threshold.map_or("None".to_string(), py_float);
            println!("vo params: ({algo}, {t_repr}, {})", py_str(&cli.dataset));
            println!("debug run: view_trajectory({args})");
            let _ = std::io::stdout().flush();
            let ds = open_dataset(cli)?;
            common::note_camera(&ds);
            let mut last_draw = std::time::Instant::now();
            // Whether the bar's line is open: an error must start on a line
            // of its own, not after "1/3 frames".
            let mut open = false;
            // A terminal gets a redrawn bar; a log (stderr not a terminal) at
            // most one line per 5 %: 4541 frames once made megabytes of it.
            let terminal = std::io::IsTerminal::is_terminal(&std::io::stderr());
            let mut last_step = usize::MAX;
            let mut progress = |done: usize, total: usize| {
                if !terminal {
                    let step = (done * 20).checked_div(total).unwrap_or(20);
                    if step != last_step && (step > 0 || done == total) {
                        last_step = step;
                        eprintln!("{done}/{total} frames ({}%)", step * 5);
                    }
                    return;
                }
                if done == total || last_draw.elapsed().as_millis() >= 100 {
                    last_draw = std::time::Instant::now();
                    open = done != total;
                    let w = 40;
                    let filled = (done * w).checked_div(total).unwrap_or(w);
                    eprint!("\r[{}{}] {done}/{total} frames", "#".repeat(filled), " ".repeat(w - filled));
                    if done == total {
                        eprintln!();
                    }
                }
            };
            let frames = last.map(|l| l + 1);
            let opts = trajectory::Options {
                frames,
                strategy,
                save_poses: a.save_poses.as_deref(),
                save_poses_tum: a.save_poses_tum.as_deref(),
                metrics: a.metrics.as_deref(),
                plot: a.plot.as_deref(),
                trace: a.trace.as_deref(),
                sift: Some(sift_params(cli)),
            };
            let result = trajectory::view_trajectory(&ds, &opts, &a.output, &mut progress);
            if open && result.is_err() {
                eprintln!();
            }
            eprintln!("{}", result?.0);
            println!("ret value: None");
            Ok(())
        }
        Command::Sift(a) => run_sift(cli, a),
        Command::Anatomy(a) => anatomy::run(&a.image, &sift_params(cli), a.json, a.out.as_deref()),
        Command::MatchAll(a) => match_all::run(cli, a),
        Command::Mark(a) => return Ok(mark_command(cli, a)),
        Command::Autograder(a) => autograder::run(cli, a),
    };
    done.map(|()| 0)
}

/// `mark`: one file, a class (--out), the join of shards (--merge) or a
/// summary; its exit status (docs/marking.md).
fn mark_command(cli: &Cli, a: &MarkArgs) -> i32 {
    if a.summary {
        return summary::main(&a.files, a.out.as_deref());
    }
    match (&a.out, a.merge) {
        (Some(out), true) => class::merge(a, out),
        (None, true) => {
            eprintln!("siftlab: error: --merge needs --out DIR, the folder for the joined grades.csv");
            2
        }
        (Some(out), false) => class::run(cli, a, out),
        (None, false) => mark::main(cli, a),
    }
}

fn run_match(cli: &Cli, a: &MatchArgs, name: &str) -> Result<(MatchInfo, MatchContext)> {
    let threshold = parse_threshold(&a.threshold)?;
    let strategy = Strategy::parse(&a.algo, threshold)?;
    let frame = parse_frame_id(&a.frame_id)?;
    let feature = parse_index(&a.feature_id, "FEATURE_ID")?;
    let t_repr = threshold.map_or("None".to_string(), py_float);
    println!("vo params: ({}, {t_repr}, {})", py_str(&a.algo), py_str(&cli.dataset));
    println!("debug run: {name}({frame}, {feature})");
    let _ = std::io::stdout().flush();

    let ds = open_dataset(cli)?;
    let params = sift_params(cli);
    let prev_image = ds.load_frame(frame - 1)?;
    let cur_image = ds.load_frame(frame)?;
    eprintln!("Processing frame {}", frame - 1);
    let prev = detect_and_compute(&prev_image, &params);
    eprintln!("Processing frame {frame}");
    let cur = detect_and_compute(&cur_image, &params);
    check_feature_id(feature, prev.keypoints.len(), Some(frame - 1))?;
    let matches = match_feature(&strategy, &prev, &cur, feature)?;
    let info = matching_info(&prev.keypoints, &cur.keypoints, &matches);
    Ok((info, MatchContext { prev_image, cur_image, prev, cur, feature, matches }))
}

fn run_sift(cli: &Cli, a: &SiftArgs) -> Result<()> {
    let bytes =
        std::fs::read(&a.image).map_err(|e| Error::Dataset(format!("cannot read {}: {e}", a.image.display())))?;
    let img = GrayImage::decode(&bytes)?;
    let params = sift_params(cli);
    let mut times = Vec::with_capacity(a.repeat as usize);
    let mut f = Features::default();
    for _ in 0..a.repeat {
        let t0 = std::time::Instant::now();
        f = detect_and_compute(&img, &params);
        times.push(t0.elapsed().as_secs_f64() * 1e3);
    }
    let best = times.iter().copied().fold(f64::INFINITY, f64::min);
    let mut out = std::io::BufWriter::new(std::io::stdout().lock());
    if a.json {
        write_json(&mut out, &img, &f).map_err(|e| Error::Dataset(format!("cannot write output: {e}")))?;
    } else if times.len() == 1 {
        let _ = writeln!(out, "{} keypoints in {best:.1} ms", f.keypoints.len());
    } else {
        let mean = times.iter().sum::<f64>() / times.len() as f64;
        let _ = writeln!(
            out,
            "{} keypoints in {best:.1} ms (best of {}; mean {mean:.1} ms)",
            f.keypoints.len(),
            times.len()
        );
    }
    let _ = out.flush();
    Ok(())
}

/// Floats as Rust's shortest round-trip f32 text, so a reader parsing them
/// as float32 gets the exact bits back.
fn write_json(out: &mut impl Write, img: &GrayImage, f: &Features) -> std::io::Result<()> {
    write!(out, "{{\"width\":{},\"height\":{},\"keypoints\":[", img.width(), img.height())?;
    for (i, k) in f.keypoints.iter().enumerate() {
        if i > 0 {
            out.write_all(b",")?;
        }
        write!(
            out,
            "{{\"x\":{:?},\"y\":{:?},\"size\":{:?},\"angle\":{:?},\"response\":{:?},\"octave\":{}}}",
            k.x, k.y, k.size, k.angle, k.response, k.octave
        )?;
    }
    out.write_all(b"],\"descriptors\":[")?;
    for (i, d) in f.descriptors.iter().enumerate() {
        if i > 0 {
            out.write_all(b",")?;
        }
        out.write_all(b"[")?;
        for (j, v) in d.iter().enumerate() {
            if j > 0 {
                out.write_all(b",")?;
            }
            write!(out, "{v}")?;
        }
        out.write_all(b"]")?;
    }
    out.write_all(b"]}\n")
}
