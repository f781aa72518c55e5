//! `view_trajectory` counts frames as the lab does.

use crate::{assert_fails, dataset, scratch, siftlab, stderr, stdout};
use std::fs;

/// `view_trajectory FRAME_ID` runs frames 0..=FRAME_ID as the lab counts:
/// `--save-poses` writes FRAME_ID+1 lines, stdout is the lab's three lines and
/// the summary goes to stderr.
#[test]
fn view_trajectory_counts_frames_as_the_lab_does() {
    let dir = scratch("vo-count");
    let poses = dir.join("p.txt");
    let png = dir.join("t.png");
    let ds = dataset();
    let o = siftlab(&[
        "-d",
        ds.to_str().unwrap(),
        "view_trajectory",
        "4",
        "--save-poses",
        poses.to_str().unwrap(),
        "--output",
        png.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let want = format!(
        "vo params: (None, None, '{}')\ndebug run: view_trajectory(4,)\nret value: None\n",
        ds.to_str().unwrap()
    );
    assert_eq!(stdout(&o), want);
    assert_eq!(fs::read_to_string(&poses).unwrap().lines().count(), 5, "frames 0..=4");
    assert!(stderr(&o).contains("trajectory error (ATE RMSE, 5 frames)"), "{}", stderr(&o));
    assert!(png.exists());

    // Beyond the bundled run of frames: which frames exist, and what to ask for.
    let o = siftlab(&["-d", ds.to_str().unwrap(), "view_trajectory", "151", "--output", png.to_str().unwrap()]);
    assert_fails(
        &o,
        &["frames 0 to 151", "frames 0 to 150 only", "000151.png", "FRAME_ID 150 or less"],
        "view_trajectory 151",
    );
    let _ = fs::remove_dir_all(&dir);
}
