//! Where a sequence's files are, in the two layouts siftlab reads:
//!
//! ```text
//! the lab's MyKITTI                      KITTI's odometry benchmark
//! gray/NN/image_0/000000.png ...         sequences/NN/image_0/000000.png ...
//! gray/NN/calib.txt   (optional)         sequences/NN/calib.txt   (required)
//! poses/NN.txt        (optional)         poses/NN.txt             (optional)
//! ```
//!
//! The lab ships sequence 00 without a `calib.txt` and hard-codes its camera;
//! KITTI's archives put a `calib.txt` beside every sequence's images, and have
//! ground truth for sequences 00–10 only. The functions here work on path
//! text, so the web app (a picked folder's relative paths) and the CLI (the
//! file system) find the same files.

use crate::{Error, Result};
use std::collections::BTreeMap;

/// File name of frame `i`: `%06d.png`.
pub fn frame_name(i: usize) -> String {
    format!("{i:06}.png")
}

/// Which of the two layouts a sequence is stored in.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Layout {
    /// The lab's MyKITTI: `gray/NN/image_0`.
    Lab,
    /// KITTI's odometry layout: `sequences/NN/image_0`.
    Kitti,
}

impl Layout {
    /// The folder holding the sequences: `gray` or `sequences`.
    pub fn sequences_dir(self) -> &'static str {
        match self {
            Layout::Lab => "gray",
            Layout::Kitti => "sequences",
        }
    }

    /// How the layout is named to a user.
    pub fn name(self) -> &'static str {
        match self {
            Layout::Lab => "the lab's MyKITTI layout",
            Layout::Kitti => "KITTI's odometry layout",
        }
    }
}

/// One sequence in one layout: every file name relative to the dataset root.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct SequenceLayout {
    pub layout: Layout,
    /// Two digits, as KITTI names them (`00` … `21`).
    pub sequence: String,
}

impl SequenceLayout {
    pub fn new(layout: Layout, sequence: &str) -> Result<SequenceLayout> {
        Ok(SequenceLayout { layout, sequence: parse_sequence(sequence)? })
    }

    /// The lab's own dataset: sequence 00 in the MyKITTI layout.
    pub fn lab() -> SequenceLayout {
        SequenceLayout { layout: Layout::Lab, sequence: "00".into() }
    }

    /// `gray/NN/image_0` or `sequences/NN/image_0`.
    pub fn frame_dir(&self) -> String {
        format!("{}/{}/image_0", self.layout.sequences_dir(), self.sequence)
    }

    /// Frame `i`: `<frame_dir>/%06d.png`.
    pub fn frame_path(&self, i: usize) -> String {
        format!("{}/{}", self.frame_dir(), frame_name(i))
    }

    /// `poses/NN.txt` (both layouts).
    pub fn poses_file(&self) -> String {
        format!("poses/{}.txt", self.sequence)
    }

    /// `gray/NN/calib.txt` or `sequences/NN/calib.txt`.
    pub fn calib_file(&self) -> String {
        format!("{}/{}/calib.txt", self.layout.sequences_dir(), self.sequence)
    }

    /// `sequence 03 (KITTI's odometry layout)`.
    pub fn describe(&self) -> String {
        format!("sequence {} ({})", self.sequence, self.layout.name())
    }
}

/// A sequence number as the user types it (`-s 3`, `-s 03`) → KITTI's two
/// digits; anything else is refused with what to type.
pub fn parse_sequence(s: &str) -> Result<String> {
    let t = s.trim();
    if !t.is_empty() && t.len() <= 2 && t.bytes().all(|b| b.is_ascii_digit()) {
        return Ok(format!("{:02}", t.parse::<u8>().unwrap_or(0)));
    }
    Err(Error::InvalidArgument(format!(
        "sequence {s:?} is not a KITTI sequence number: give two digits such as 00 or 03 (KITTI has 00 to 21)"
    )))
}

/// The files of one sequence found among a folder's paths (the web app's
/// picked folder): the frames by id, the poses and the calibration, each as
/// an index into the path list.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct SequenceFiles {
    pub frames: BTreeMap<u32, usize>,
    pub poses: Option<usize>,
    pub calib: Option<usize>,
}

/// Every sequence a list of relative paths holds, in either layout, in order
/// (lab before KITTI, then by number). Paths may start with the picked
/// folder's own name (`MyKITTI/gray/00/...`, `dataset/sequences/03/...`):
/// only the part from `gray/` or `sequences/` (or `poses/`) on is read.
pub fn scan_paths<'a>(paths: impl IntoIterator<Item = &'a str>) -> BTreeMap<SequenceLayout, SequenceFiles> {
    let mut found: BTreeMap<SequenceLayout, SequenceFiles> = BTreeMap::new();
    let mut poses: BTreeMap<String, usize> = BTreeMap::new();
    for (idx, path) in paths.into_iter().enumerate() {
        let parts: Vec<&str> = path.split('/').collect();
        let n = parts.len();
        // …/poses/NN.txt
        if n >= 2 && parts[n - 2] == "poses" {
            if let Some(seq) = parts[n - 1].strip_suffix(".txt").filter(|s| is_seq(s)) {
                poses.insert(seq.to_string(), idx);
            }
            continue;
        }
        // …/{gray,sequences}/NN/calib.txt
        if n >= 3 && parts[n - 1] == "calib.txt" && is_seq(parts[n - 2]) {
            if let Some(layout) = layout_of(parts[n - 3]) {
                let key = SequenceLayout { layout, sequence: parts[n - 2].to_string() };
                found.entry(key).or_default().calib = Some(idx);
            }
            continue;
        }
        // …/{gray,sequences}/NN/image_0/DDDDDD.png
        if n >= 4 && parts[n - 2] == "image_0" && is_seq(parts[n - 3]) {
            if let (Some(layout), Some(id)) = (layout_of(parts[n - 4]), frame_id(parts[n - 1])) {
                let key = SequenceLayout { layout, sequence: parts[n - 3].to_string() };
                found.entry(key).or_default().frames.insert(id, idx);
            }
        }
    }
    // A sequence is one with frames; a calib.txt alone is not one.
    found.retain(|_, f| !f.frames.is_empty());
    for (key, files) in found.iter_mut() {
        files.poses = poses.get(&key.sequence).copied();
    }
    found
}

fn layout_of(dir: &str) -> Option<Layout> {
    match dir {
        "gray" => Some(Layout::Lab),
        "sequences" => Some(Layout::Kitti),
        _ => None,
    }
}

fn is_seq(s: &str) -> bool {
    s.len() == 2 && s.bytes().all(|b| b.is_ascii_digit())
}

/// `000042.png` → 42 (six digits, as the lab's `%06d.png`).
pub fn frame_id(name: &str) -> Option<u32> {
    let digits = name.strip_suffix(".png")?;
    (digits.len() == 6 && digits.bytes().all(|b| b.is_ascii_digit())).then(|| digits.parse().ok()).flatten()
}

/// Which layout holds `sequence` under a root, given which of the two frame
/// folders exist. The lab's layout wins when both do (the lab's tool reads
/// only it).
pub fn pick_layout(sequence: &str, lab_exists: bool, kitti_exists: bool) -> Option<SequenceLayout> {
    let layout = if lab_exists {
        Layout::Lab
    } else if kitti_exists {
        Layout::Kitti
    } else {
        return None;
    };
    Some(SequenceLayout { layout, sequence: sequence.to_string() })
}

/// `00 (lab layout), 03 (KITTI layout)`: the sequences a folder has, for
/// the message that says the asked one is not there.
pub fn describe_sequences<'a>(seqs: impl IntoIterator<Item = &'a SequenceLayout>) -> String {
    let names: Vec<String> =
        seqs.into_iter().map(|s| format!("{} (in {}/)", s.sequence, s.layout.sequences_dir())).collect();
    if names.is_empty() {
        "none".into()
    } else {
        names.join(", ")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sequence_numbers_read_as_kitti_names_them() {
        assert_eq!(parse_sequence("00").unwrap(), "00");
        assert_eq!(parse_sequence("3").unwrap(), "03");
        assert_eq!(parse_sequence(" 21 ").unwrap(), "21");
        for bad in ["", "x", "003", "-1", "1.0"] {
            let e = parse_sequence(bad).unwrap_err().to_string();
            assert!(e.contains("is not a KITTI sequence number: give two digits such as 00 or 03"), "{bad}: {e}");
        }
    }

    #[test]
    fn both_layouts_name_their_files() {
        let lab = SequenceLayout::lab();
        assert_eq!(lab.frame_path(7), "gray/00/image_0/000007.png");
        assert_eq!((lab.poses_file(), lab.calib_file()), ("poses/00.txt".into(), "gray/00/calib.txt".into()));
        let k = SequenceLayout::new(Layout::Kitti, "3").unwrap();
        assert_eq!(k.frame_path(150), "sequences/03/image_0/000150.png");
        assert_eq!((k.poses_file(), k.calib_file()), ("poses/03.txt".into(), "sequences/03/calib.txt".into()));
        assert_eq!(k.describe(), "sequence 03 (KITTI's odometry layout)");
    }

    #[test]
    fn a_picked_folder_is_scanned_for_every_sequence() {
        let paths = [
            "dataset/sequences/03/image_0/000000.png",
            "dataset/sequences/03/image_0/000001.png",
            "dataset/sequences/03/calib.txt",
            "dataset/sequences/03/times.txt",
            "dataset/sequences/03/image_1/000000.png",
            "dataset/poses/03.txt",
            "dataset/poses/04.txt",
            "dataset/sequences/12/image_0/000005.png",
            "dataset/sequences/13/calib.txt",
            "MyKITTI/gray/00/image_0/000000.png",
            "dataset/sequences/03/image_0/notes.png",
            "dataset/sequences/03/image_0/00001.png",
        ];
        let found = scan_paths(paths);
        let keys: Vec<String> = found.keys().map(|k| format!("{}:{:?}", k.sequence, k.layout)).collect();
        assert_eq!(keys, ["00:Lab", "03:Kitti", "12:Kitti"]);
        let s03 = &found[&SequenceLayout::new(Layout::Kitti, "03").unwrap()];
        assert_eq!(s03.frames.iter().map(|(k, v)| (*k, *v)).collect::<Vec<_>>(), [(0, 0), (1, 1)]);
        assert_eq!((s03.poses, s03.calib), (Some(5), Some(2)));
        let s12 = &found[&SequenceLayout::new(Layout::Kitti, "12").unwrap()];
        assert_eq!((s12.poses, s12.calib, s12.frames.len()), (None, None, 1));
        assert_eq!(describe_sequences(found.keys()), "00 (in gray/), 03 (in sequences/), 12 (in sequences/)");
        assert_eq!(describe_sequences(&[]), "none");
    }

    #[test]
    fn the_lab_layout_wins_when_both_exist() {
        assert_eq!(pick_layout("00", true, true).unwrap().layout, Layout::Lab);
        assert_eq!(pick_layout("00", false, true).unwrap().layout, Layout::Kitti);
        assert_eq!(pick_layout("00", false, false), None);
        assert_eq!(frame_id("000150.png"), Some(150));
        assert_eq!(frame_id("150.png"), None);
    }
}
