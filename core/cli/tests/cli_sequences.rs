//! Sequences beyond the lab's: the bundled KITTI 00 frames copied into
//! KITTI's own layout (`sequences/NN/image_0`, `sequences/NN/calib.txt`,
//! `poses/NN.txt`) give the lab layout's output byte for byte; with
//! sequence 03's camera in `calib.txt` the odometry equals OpenCV's loop run
//! with that camera (tests/fixtures/vo_kitti03, written by
//! `tests/references/vo_reference.py --fixtures --camera-fixture`); and every
//! broken dataset gets one clear message and a non-zero exit.

use std::fs;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..").canonicalize().unwrap()
}

fn lab_dataset() -> PathBuf {
    repo_root().join("www/demo/MyKITTI")
}

/// `siftlab ARGS` run in `cwd` (the view commands write their PNG there).
fn siftlab_in(cwd: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_siftlab")).current_dir(cwd).args(args).output().unwrap()
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("siftlab-seq-{}-{name}", std::process::id()));
    let _ = fs::remove_dir_all(&dir);
    fs::create_dir_all(&dir).unwrap();
    dir
}

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// KITTI's sequences/00/calib.txt, P0 and P1 (camera 0 is the lab's).
const CALIB_00: &str = "P0: 7.188560000000e+02 0.000000000000e+00 6.071928000000e+02 0.000000000000e+00 \
0.000000000000e+00 7.188560000000e+02 1.852157000000e+02 0.000000000000e+00 0.000000000000e+00 \
0.000000000000e+00 1.000000000000e+00 0.000000000000e+00\n\
P1: 7.188560000000e+02 0.000000000000e+00 6.071928000000e+02 -3.861448000000e+02 0.000000000000e+00 \
7.188560000000e+02 1.852157000000e+02 0.000000000000e+00 0.000000000000e+00 0.000000000000e+00 \
1.000000000000e+00 0.000000000000e+00\n";

/// The bundled frames 0..frames as sequence `seq` in KITTI's layout under
/// `root` (hard links where the file system allows, else copies), with
/// `calib` as its calib.txt and the bundled poses as poses/SEQ.txt.
fn kitti_copy(root: &Path, seq: &str, frames: usize, calib: Option<&str>, poses: bool) {
    let dir = root.join("sequences").join(seq).join("image_0");
    fs::create_dir_all(&dir).unwrap();
    for i in 0..frames {
        let name = format!("{i:06}.png");
        let from = lab_dataset().join("gray/00/image_0").join(&name);
        if fs::hard_link(&from, dir.join(&name)).is_err() {
            fs::copy(&from, dir.join(&name)).unwrap();
        }
    }
    if let Some(text) = calib {
        fs::write(root.join("sequences").join(seq).join("calib.txt"), text).unwrap();
    }
    if poses {
        fs::create_dir_all(root.join("poses")).unwrap();
        fs::copy(lab_dataset().join("poses/00.txt"), root.join("poses").join(format!("{seq}.txt"))).unwrap();
    }
}

/// stdout without the `vo params:` line, whose last field is the dataset path.
fn without_params(s: &str) -> String {
    s.lines().filter(|l| !l.starts_with("vo params: ")).map(|l| format!("{l}\n")).collect()
}

fn positions(text: &str) -> Vec<[f64; 3]> {
    text.lines()
        .map(|l| {
            let v: Vec<f64> = l.split(' ').map(|x| x.parse().unwrap()).collect();
            [v[3], v[7], v[11]]
        })
        .collect()
}

fn dist(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    (0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<f64>().sqrt()
}

/// get_info, match_all (text, JSON records, matches.png) and view_trajectory
/// (stdout, poses, trajectory.png) on the same frames in both layouts.
#[test]
fn both_layouts_give_identical_output() {
    let root = scratch("same");
    let kitti = root.join("kitti");
    kitti_copy(&kitti, "00", 21, Some(CALIB_00), true);
    let (lab, kit) = (lab_dataset(), kitti.clone());
    let runs: [(&str, &Path); 2] = [("lab", &lab), ("kitti", &kit)];
    let mut outs: Vec<Vec<(String, Vec<u8>)>> = Vec::new();
    for (name, ds) in runs {
        let cwd = root.join(name);
        fs::create_dir_all(&cwd).unwrap();
        let d = ds.to_str().unwrap();
        let mut got = Vec::new();
        let o = siftlab_in(&cwd, &["--opencv-lanes", "8", "-d", d, "get_info", "-a", "dt", "-t", "232.5", "20", "127"]);
        assert!(o.status.success(), "{name} get_info: {}", stderr(&o));
        got.push(("get_info".to_string(), without_params(&stdout(&o)).into_bytes()));
        let o =
            siftlab_in(&cwd, &["--opencv-lanes", "8", "-d", d, "match_all", "-a", "nndr", "-t", "0.8", "--json", "20"]);
        assert!(o.status.success(), "{name} match_all: {}", stderr(&o));
        assert!(stdout(&o).contains("\"correct\": "), "judged: {}", stdout(&o));
        got.push(("match_all".into(), o.stdout.clone()));
        got.push(("matches.png".into(), fs::read(cwd.join("matches.png")).unwrap()));
        let poses = cwd.join("poses.txt");
        let o = siftlab_in(
            &cwd,
            &["--opencv-lanes", "8", "-d", d, "view_trajectory", "20", "--save-poses", poses.to_str().unwrap()],
        );
        assert!(o.status.success(), "{name} view_trajectory: {}", stderr(&o));
        got.push(("view_trajectory".into(), without_params(&stdout(&o)).into_bytes()));
        got.push(("poses.txt".into(), fs::read(&poses).unwrap()));
        got.push(("trajectory.png".into(), fs::read(cwd.join("trajectory.png")).unwrap()));
        // The lab's layout has no calib.txt: the camera is said once; KITTI's has its own.
        let camera_lines = stderr(&o).lines().filter(|l| l.starts_with("camera: ")).count();
        assert_eq!(camera_lines, usize::from(name == "lab"), "{name}: {}", stderr(&o));
        outs.push(got);
    }
    for ((what, a), (_, b)) in outs[0].iter().zip(&outs[1]) {
        assert!(!a.is_empty(), "{what} is empty");
        assert!(
            a == b,
            "{what} differs between the layouts:\n{}\n---\n{}",
            String::from_utf8_lossy(a),
            String::from_utf8_lossy(b)
        );
    }
    let _ = fs::remove_dir_all(&root);
}

/// Sequence 03's camera (fx = fy = 721.5377, cx = 609.5593, cy = 172.854)
/// on the bundled frames 0–150: the positions equal OpenCV's loop with that
/// camera within 1e-6 m per frame (measured: 3.4e-7 m at frame 150), the
/// trace equal line for line, and far from the 00 camera's run.
#[test]
fn another_camera_equals_opencv_with_that_camera() {
    let root = scratch("cam03");
    let ds = root.join("kitti");
    let calib = fs::read_to_string(repo_root().join("tests/fixtures/vo_kitti03/calib.txt")).unwrap();
    kitti_copy(&ds, "03", 151, Some(&calib), true);
    let (poses, trace) = (root.join("p.txt"), root.join("t.jsonl"));
    let o = siftlab_in(
        &root,
        &[
            "--opencv-lanes",
            "8",
            "-d",
            ds.to_str().unwrap(),
            "-s",
            "03",
            "view_trajectory",
            "150",
            "--save-poses",
            poses.to_str().unwrap(),
            "--trace",
            trace.to_str().unwrap(),
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!stderr(&o).contains("camera: "), "the camera comes from calib.txt: {}", stderr(&o));
    let fixture = |f: &str| fs::read_to_string(repo_root().join("tests/fixtures/vo_kitti03").join(f)).unwrap();
    let meta = fixture("meta.json");
    assert!(meta.contains("\"focal\": 721.5377") && meta.contains("\"opencv_simd_lanes\": 8"), "{meta}");
    let (got, want) = (positions(&fs::read_to_string(&poses).unwrap()), positions(&fixture("poses.txt")));
    assert_eq!((got.len(), want.len()), (151, 151));
    let (worst, frame) = got
        .iter()
        .zip(&want)
        .map(|(g, w)| dist(g, w))
        .enumerate()
        .map(|(i, d)| (d, i))
        .fold((0.0, 0), |a, b| if b.0 > a.0 { b } else { a });
    assert!(worst <= 1e-6, "frame {frame}: {worst} m from OpenCV with sequence 03's camera");
    assert_eq!(fs::read_to_string(&trace).unwrap(), fixture("trace.jsonl"));
    // The epipolar judge sees through the same camera: the same matches, other Sampson distances.
    let judge = |args: &[&str]| {
        let o = siftlab_in(&root, args);
        assert!(o.status.success(), "{}", stderr(&o));
        stdout(&o)
    };
    let (d03, dlab) = (ds.to_str().unwrap(), lab_dataset());
    let with03 =
        judge(&["--opencv-lanes", "8", "-d", d03, "-s", "03", "match_all", "-a", "nndr", "-t", "0.8", "--json", "120"]);
    let with00 = judge(&[
        "--opencv-lanes",
        "8",
        "-d",
        dlab.to_str().unwrap(),
        "match_all",
        "-a",
        "nndr",
        "-t",
        "0.8",
        "--json",
        "120",
    ]);
    let field = |s: &str, key: &str| -> Vec<String> {
        s.split(&format!("\"{key}\": ")).skip(1).map(|r| r.split([',', '}']).next().unwrap().to_string()).collect()
    };
    assert_eq!(field(&with03, "query"), field(&with00, "query"));
    assert_eq!(field(&with03, "distance"), field(&with00, "distance"));
    let (s03, s00) = (field(&with03, "sampson"), field(&with00, "sampson"));
    assert!(s03.len() > 700 && s03.iter().zip(&s00).filter(|(a, b)| a != b).count() > s03.len() / 2, "{s03:?}");
    // The camera matters: the 00 camera's run (tests/fixtures/vo_lk) ends metres away.
    let lab = positions(&fs::read_to_string(repo_root().join("tests/fixtures/vo_lk/poses.txt")).unwrap());
    assert!(dist(&got[150], &lab[150]) > 1.0, "{:?} vs {:?}", got[150], lab[150]);
    let _ = fs::remove_dir_all(&root);
}

/// One `siftlab: error:` line naming the problem, a non-zero exit, no panic.
fn assert_one_error(o: &Output, want: &[&str], case: &str) {
    let err = stderr(o);
    assert!(!o.status.success(), "{case}: exit 0; stderr {err}");
    assert!(!err.contains("panicked"), "{case}: {err}");
    let errors: Vec<&str> = err.lines().filter(|l| l.starts_with("siftlab: error: ")).collect();
    assert_eq!(errors.len(), 1, "{case}: {err}");
    for w in want {
        assert!(errors[0].contains(w), "{case}: {:?} lacks {w:?}", errors[0]);
    }
}

fn png(w: u32, h: u32) -> Vec<u8> {
    let buf: Vec<u8> = (0..w * h).map(|i| (i * 37 % 251) as u8).collect();
    let mut out = std::io::Cursor::new(Vec::new());
    image::write_buffer_with_format(&mut out, &buf, w, h, image::ExtendedColorType::L8, image::ImageFormat::Png)
        .unwrap();
    out.into_inner()
}

#[test]
fn broken_datasets_get_one_clear_message() {
    let root = scratch("bad");
    let run = |ds: &Path, args: &[&str]| {
        let mut a = vec!["-d", ds.to_str().unwrap()];
        a.extend_from_slice(args);
        siftlab_in(&root, &a)
    };
    let vo = ["-s", "03", "view_trajectory", "3"];

    let no_calib = root.join("no-calib");
    kitti_copy(&no_calib, "03", 4, None, true);
    assert_one_error(&run(&no_calib, &vo), &["has no sequences/03/calib.txt", "KITTI's layout"], "missing calib.txt");
    let o = run(&no_calib, &["-s", "03", "get_info", "-a", "nn", "1", "0"]);
    assert_one_error(&o, &["sequences/03/calib.txt"], "missing calib.txt, get_info");

    let bad_p0 = root.join("bad-p0");
    kitti_copy(&bad_p0, "03", 4, Some("P0: 7.215377e+02 0 6.095593e+02 0 0 7.215377e+02\n"), true);
    assert_one_error(&run(&bad_p0, &vo), &["sequences/03/calib.txt line 1: P0 has 6 numbers, not 12"], "short P0");
    let bad_p0 = root.join("bad-p0b");
    kitti_copy(&bad_p0, "03", 4, Some("P0: 7.2e+02 0 6.1e+02 0 0 7.2e+02 1.7e+02 0 0 0 one 0\n"), true);
    assert_one_error(&run(&bad_p0, &vo), &["P0 number 11 (\"one\") is not a number"], "P0 with a word");
    let no_p0 = root.join("no-p0");
    kitti_copy(&no_p0, "03", 4, Some("P1: 1 2 3\n"), true);
    assert_one_error(&run(&no_p0, &vo), &["has no `P0:` line"], "no P0 line");

    let mixed = root.join("mixed");
    kitti_copy(
        &mixed,
        "03",
        4,
        Some(&fs::read_to_string(repo_root().join("tests/fixtures/vo_kitti03/calib.txt")).unwrap()),
        true,
    );
    let f2 = mixed.join("sequences/03/image_0/000002.png");
    fs::remove_file(&f2).unwrap();
    fs::write(&f2, png(1226, 370)).unwrap();
    assert_one_error(
        &run(&mixed, &vo),
        &["frame 2 (sequences/03/image_0/000002.png) is 1226x370 but frame 0 is 1241x376", "same size"],
        "mixed frame sizes",
    );
    let o = run(&mixed, &["-s", "03", "get_info", "-a", "nn", "2", "0"]);
    assert_one_error(&o, &["is 1226x370 but frame 1 is 1241x376"], "mixed frame sizes, get_info");
    let o = run(&mixed, &["-s", "03", "view_trajectory", "-a", "dt", "-t", "200", "3"]);
    assert_one_error(&o, &["is 1226x370 but frame 0 is 1241x376"], "mixed frame sizes, matched loop");

    assert_one_error(
        &run(&no_calib, &["-s", "05", "get_info", "-a", "nn", "1", "0"]),
        &["has no sequence 05", "sequences there: 03 (in sequences/)", "-s"],
        "missing sequence folder",
    );
    assert_one_error(
        &run(&lab_dataset(), &["-s", "x3", "get_info", "-a", "nn", "1", "0"]),
        &["not a KITTI sequence number"],
        "bad -s",
    );

    let no_poses = root.join("no-poses");
    kitti_copy(&no_poses, "03", 4, Some("P0: 721.5377 0 609.5593 0 0 721.5377 172.854 0 0 0 1 0\n"), false);
    assert_one_error(
        &run(&no_poses, &vo),
        &["view_trajectory needs the ground-truth poses poses/03.txt"],
        "missing poses",
    );
    // Without poses the matching commands work; match_all counts without judging and says why.
    let o = run(&no_poses, &["-s", "03", "get_info", "-a", "nn", "1", "0"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stdout(&o).contains("ret value: ((3, 121), [(465, 44)], [241.1907958984375])"), "{}", stdout(&o));
    let o = run(&no_poses, &["-s", "03", "match_all", "-a", "nndr", "-t", "0.8", "1"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stdout(&o).starts_with("nndr (threshold 0.8): ") && !stdout(&o).contains("correct"), "{}", stdout(&o));
    assert!(
        stderr(&o).contains("no poses/03.txt in the dataset: counting matches without judging them"),
        "{}",
        stderr(&o)
    );
    let _ = fs::remove_dir_all(&root);
}
