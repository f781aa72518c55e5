//! The `siftlab` command line: the lab's `run_odometry.py` interface
//! (`get_info`, `view_feature`, `view_info`, `view_trajectory`) plus `sift`.
//! Arguments are checked here with messages that say what to do; the work is
//! done by the library.

pub mod anatomy;
pub mod match_all;
pub mod trajectory;
pub mod visual;

use crate::error::{Error, Result};
use crate::image::GrayImage;
use crate::matching::args::parse_index;
use crate::matching::{match_feature, matching_info, MatchInfo, Strategy};
use crate::pyfmt::{py_float, py_str};
use crate::sift::{detect_and_compute, Features, SiftParams};
use clap::{Args, Parser, Subcommand};
use std::io::Write;
use std::path::{Path, PathBuf};

#[derive(Parser, Debug)]
#[command(name = "siftlab", version, about = "The COMP24011 feature-matching lab (OpenCV 4.8 SIFT) in Rust")]
pub struct Cli {
    /// The MyKITTI dataset folder (gray/00/image_0/NNNNNN.png, poses/00.txt).
    #[arg(short = 'd', long = "dataset", default_value = "~/MyKITTI")]
    pub dataset: String,
    /// SIMD width OpenCV's SIFT ran with on the reference machine (8 = AVX2,
    /// 16 = AVX-512); default: what OpenCV would use on this CPU.
    #[arg(long = "opencv-lanes", value_parser = ["8", "16"], global = true)]
    pub opencv_lanes: Option<String>,
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Print matching_info for one feature of frame FRAME_ID-1 matched into FRAME_ID.
    #[command(name = "get_info")]
    GetInfo(MatchArgs),
    /// Write opencv_visual.png: both frames, lines from the feature to its matches.
    #[command(name = "view_feature")]
    ViewFeature(MatchArgs),
    /// Write custom_visual.png: opencv_visual.png above the frames with matching_info circles.
    #[command(name = "view_info")]
    ViewInfo(MatchArgs),
    /// Run the lab's monocular visual odometry and write trajectory.png.
    #[command(name = "view_trajectory")]
    ViewTrajectory(TrajectoryArgs),
    /// Run SIFT on one image: "N keypoints in T ms", or everything as JSON.
    Sift(SiftArgs),
    /// SIFT's funnel on one image: points per stage, drops per reason; --out writes the pyramid.
    Anatomy(AnatomyArgs),
    /// Every match of frame FRAME_ID-1 into FRAME_ID, judged by the true geometry; writes matches.png.
    #[command(name = "match_all")]
    MatchAll(match_all::MatchAllArgs),
}

#[derive(Args, Debug)]
pub struct AnatomyArgs {
    /// A PNG or JPEG image.
    pub image: PathBuf,
    /// Print the stages as JSON.
    #[arg(long)]
    pub json: bool,
    /// Write every Gaussian and DoG level into this folder as PNG.
    #[arg(long)]
    pub out: Option<PathBuf>,
}

#[derive(Args, Debug)]
pub struct MatchArgs {
    /// Matching strategy.
    #[arg(short = 'a', long = "algorithm", value_parser = ["dt", "nn", "nndr"])]
    pub algo: String,
    /// Threshold: a distance for dt/nn, a ratio in [0, 1] for nndr.
    #[arg(short = 't', long = "threshold", allow_negative_numbers = true)]
    pub threshold: Option<String>,
    /// The current frame (>= 1); frame FRAME_ID-1 is the previous one.
    #[arg(allow_negative_numbers = true)]
    pub frame_id: String,
    /// The feature (keypoint index) of the previous frame.
    #[arg(allow_negative_numbers = true)]
    pub feature_id: String,
}

#[derive(Args, Debug)]
pub struct TrajectoryArgs {
    /// The last frame: frames 0 to FRAME_ID inclusive, as the lab counts
    /// (default: every frame of the dataset).
    pub frame_id: Option<String>,
    /// Also write the estimated poses in KITTI format (12 numbers a line).
    #[arg(long = "save-poses")]
    pub save_poses: Option<PathBuf>,
    /// Where to write the plot.
    #[arg(long = "output", default_value = "trajectory.png")]
    pub output: PathBuf,
    /// Track with the student's matcher (SIFT matching of consecutive frames)
    /// instead of Lucas-Kanade.
    #[arg(short = 'a', long = "algorithm", value_parser = ["dt", "nn", "nndr"])]
    pub algo: Option<String>,
    /// The matcher's threshold: a distance for dt/nn, a ratio in [0, 1] for nndr.
    #[arg(short = 't', long = "threshold", requires = "algo", allow_negative_numbers = true)]
    pub threshold: Option<String>,
    /// Also write the estimated poses in TUM format (for evo): i/10 x y z qx qy qz qw.
    #[arg(long = "save-poses-tum")]
    pub save_poses_tum: Option<PathBuf>,
    /// Write ATE (raw and aligned), RPE and the KITTI metric as JSON.
    #[arg(long = "metrics")]
    pub metrics: Option<PathBuf>,
    /// Write the trajectory and error plot with axes (.png or .svg).
    #[arg(long = "plot")]
    pub plot: Option<PathBuf>,
}

#[derive(Args, Debug)]
pub struct SiftArgs {
    /// A PNG or JPEG image.
    pub image: PathBuf,
    /// Print keypoints and descriptors as JSON.
    #[arg(long)]
    pub json: bool,
    /// Time detect+compute this many times and report the best and the mean
    /// (for benchmarks: tests/scripts/bench_interleaved.py).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=1000))]
    pub repeat: u32,
}

/// Runs the CLI; returns the process exit code.
pub fn main() -> i32 {
    let cli = Cli::parse();
    // SIFTLAB_SIMD caps the kernels (see `crate::simd`): results are the same
    // at every level, only the time differs.
    if let Some(v) = std::env::var_os("SIFTLAB_SIMD") {
        match v.to_str().and_then(crate::simd::SimdLevel::parse) {
            Some(level) => crate::simd::set_cap(level),
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
        Ok(()) => 0,
        Err(e) => {
            eprintln!("siftlab: error: {e}");
            1
        }
    }
}

fn sift_params(cli: &Cli) -> SiftParams {
    match cli.opencv_lanes.as_deref() {
        Some("16") => SiftParams { opencv_lanes: 16, ..SiftParams::default() },
        Some(_) => SiftParams::default(),
        None => SiftParams::for_host(),
    }
}

pub fn run(cli: &Cli) -> Result<()> {
    match &cli.command {
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
            let root = expand_home(&cli.dataset);
            let mut last_draw = std::time::Instant::now();
            // Whether the bar's line is open: an error must start on a line
            // of its own, not after "1/3 frames".
            let mut open = false;
            let mut progress = |done: usize, total: usize| {
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
            };
            let result = trajectory::view_trajectory(&root, &opts, &a.output, &mut progress);
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

fn parse_threshold(s: &Option<String>) -> Result<Option<f64>> {
    s.as_deref().map(crate::matching::args::parse_threshold).transpose()
}

/// `~` expands like the lab's `os.path.expanduser`.
fn expand_home(p: &str) -> PathBuf {
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

fn load_frame(root: &Path, id: usize) -> Result<GrayImage> {
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

fn run_match(cli: &Cli, a: &MatchArgs, name: &str) -> Result<(MatchInfo, MatchContext)> {
    let threshold = parse_threshold(&a.threshold)?;
    let strategy = Strategy::parse(&a.algo, threshold)?;
    let frame = parse_index(&a.frame_id, "FRAME_ID")?;
    if frame < 1 {
        return Err(Error::InvalidArgument("FRAME_ID must be >= 1: frames FRAME_ID-1 and FRAME_ID are matched".into()));
    }
    let feature = parse_index(&a.feature_id, "FEATURE_ID")?;
    let t_repr = threshold.map_or("None".to_string(), py_float);
    println!("vo params: ({}, {t_repr}, {})", py_str(&a.algo), py_str(&cli.dataset));
    println!("debug run: {name}({frame}, {feature})");
    let _ = std::io::stdout().flush();

    let root = expand_home(&cli.dataset);
    let params = sift_params(cli);
    let prev_image = load_frame(&root, frame - 1)?;
    let cur_image = load_frame(&root, frame)?;
    eprintln!("Processing frame {}", frame - 1);
    let prev = detect_and_compute(&prev_image, &params);
    eprintln!("Processing frame {frame}");
    let cur = detect_and_compute(&cur_image, &params);
    let matches = match_feature(&strategy, &prev, &cur, feature).map_err(|e| match e {
        Error::InvalidArgument(m) if m.starts_with("feature id") => Error::InvalidArgument(format!(
            "FEATURE_ID {feature} is out of range: frame {} has {} keypoints (valid: 0 to {})",
            frame - 1,
            prev.keypoints.len(),
            prev.keypoints.len().saturating_sub(1)
        )),
        other => other,
    })?;
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
