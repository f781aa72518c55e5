//! The `siftlab` command line's arguments (clap): the lab's `run_odometry.py`
//! commands and siftlab's own.

use clap::{Args, Parser, Subcommand};
use std::path::PathBuf;

#[derive(Parser, Debug)]
#[command(name = "siftlab", version, about = "The COMP24011 feature-matching lab (OpenCV 4.8 SIFT) in Rust")]
pub struct Cli {
    /// The dataset folder: the lab's MyKITTI layout (gray/NN/image_0/NNNNNN.png, poses/NN.txt)
    /// or KITTI's (sequences/NN/image_0/, sequences/NN/calib.txt, poses/NN.txt).
    #[arg(short = 'd', long = "dataset", default_value = "~/MyKITTI", global = true)]
    pub dataset: String,
    /// The KITTI sequence to read (00 to 21); its camera comes from its calib.txt.
    #[arg(short = 's', long = "sequence", default_value = "00", global = true)]
    pub sequence: String,
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
    MatchAll(MatchAllArgs),
    /// Mark a student's vision_tasks.py as the lab's automarker does (python3 in a bubblewrap sandbox).
    Mark(MarkArgs),
    /// Write an autograder for a course platform: gradescope (the files and a zip to upload)
    /// or prairielearn (a grader image's Dockerfile, its entrypoint, the question's options).
    Autograder(AutograderArgs),
}

#[derive(Args, Debug)]
pub struct AutograderArgs {
    /// The platform the autograder is for.
    #[arg(value_parser = ["gradescope", "prairielearn"])]
    pub platform: String,
    /// A new (or empty) folder for the autograder's files and autograder.zip.
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// The seed of the cases every submission is marked on.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Calls per task.
    #[arg(short = 'n', long = "cases", default_value_t = 25, value_parser = clap::value_parser!(u32).range(1..=1000))]
    pub n: u32,
    /// The siftlab binary to bundle (default: this one). Gradescope's image is Ubuntu 22.04:
    /// give a static build (glibc with crt-static: docs/marking.md) when this one is dynamic.
    #[arg(long, value_name = "PATH")]
    pub binary: Option<PathBuf>,
}

#[derive(Args, Debug)]
pub struct MarkArgs {
    /// The student's vision_tasks.py; with --out, any number of files and folders (a folder
    /// with vision_tasks.py at its top is one student, any other holds one per sub-folder or
    /// <student id>.py); with --merge or --summary, class output folders.
    #[arg(required = true, value_name = "SUBMISSION")]
    pub files: Vec<PathBuf>,
    /// Mark a whole class into DIR: grades.csv and, per student, report.txt, report.json and
    /// Gradescope's results.json.
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Students marked at once (default: the cores available), each in a sandbox of its own.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=256))]
    pub jobs: Option<u32>,
    /// Skip a student whose report.json records the same seed, n, dataset, file and siftlab.
    #[arg(long)]
    pub resume: bool,
    /// Mark only the I-th of K disjoint slices of the class (by student id), e.g. 2/3.
    #[arg(long, value_name = "I/K")]
    pub shard: Option<String>,
    /// Join the grades.csv of shard output folders (the SUBMISSION arguments) into --out.
    #[arg(long)]
    pub merge: bool,
    /// Rebuild the class summary (summary.html and summary.json: marks, mistakes, hardest cases)
    /// from class output folders (the SUBMISSION arguments: one, or its shards) into that folder
    /// or --out.
    #[arg(long, conflicts_with = "merge")]
    pub summary: bool,
    /// Write Gradescope's results.json for one submission (a file, or a folder holding vision_tasks.py).
    #[arg(long, value_name = "RESULTS_JSON")]
    pub gradescope: Option<PathBuf>,
    /// Write PrairieLearn's external-grader results.json for one submission (a file, or a
    /// folder holding vision_tasks.py, e.g. /grade/student).
    #[arg(long, value_name = "RESULTS_JSON")]
    pub prairielearn: Option<PathBuf>,
    /// Calls per task (the lab's marking: 25).
    #[arg(short = 'n', long = "cases", default_value_t = 25, value_parser = clap::value_parser!(u32).range(1..=1000))]
    pub n: u32,
    /// The seed the cases are drawn from (the same seed, dataset and n give the same cases).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Print the report as JSON.
    #[arg(long)]
    pub json: bool,
    /// Run the file without the sandbox, with your own rights: only to check your own file
    /// (inside a platform's container, siftlab runs its container tier instead).
    #[arg(long = "no-sandbox")]
    pub no_sandbox: bool,
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
    /// Write one JSON object per frame (JSON Lines): frame, points_in, tracked,
    /// essential_inliers, pose_inliers, redetected.
    #[arg(long = "trace")]
    pub trace: Option<PathBuf>,
}

#[derive(Args, Debug)]
pub struct SiftArgs {
    /// A PNG or JPEG image.
    pub image: PathBuf,
    /// Print keypoints and descriptors as JSON.
    #[arg(long)]
    pub json: bool,
    /// Time detect+compute this many times and report the best and the mean
    /// (for benchmarks: tests/benchmarks/bench_interleaved.py).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=1000))]
    pub repeat: u32,
}

#[derive(Args, Debug)]
pub struct MatchAllArgs {
    /// Matching strategy.
    #[arg(short = 'a', long = "algorithm", value_parser = ["dt", "nn", "nndr"])]
    pub algo: String,
    /// Threshold: a distance for dt/nn, a ratio in [0, 1] for nndr.
    #[arg(short = 't', long = "threshold", allow_negative_numbers = true)]
    pub threshold: Option<String>,
    /// A match is correct when its Sampson distance to the true epipolar geometry is at most this (pixels).
    #[arg(long = "epipolar-px", default_value_t = 2.0, allow_negative_numbers = true)]
    pub epipolar_px: f64,
    /// Print the counts and every match (query, train, distance, Sampson distance, verdict) as JSON.
    #[arg(long)]
    pub json: bool,
    /// matches.png: `flow` draws each match on the current frame from where its point was to where it is;
    /// `side` both frames side by side with a line per match.
    #[arg(long, value_parser = ["flow", "side"], default_value = "flow")]
    pub layout: String,
    /// The current frame (>= 1); frame FRAME_ID-1 is the previous one.
    #[arg(allow_negative_numbers = true)]
    pub frame_id: String,
}
