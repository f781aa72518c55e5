//! A KITTI odometry sequence on disk, in the lab's MyKITTI layout or KITTI's
//! own ([`layout`]): its frames (consecutive from `000000.png`, all one
//! size), its camera (`calib.txt`'s P0, or the lab's sequence-00 camera where
//! the lab's layout has none: [`calib`]) and its ground-truth poses when it
//! has them (KITTI's sequences 11–21 do not: [`poses`]).
//!
//! Parsing works from text/bytes (the web app reads a picked folder); the
//! file-system part is native only.

pub mod calib;
pub mod layout;
pub mod poses;

pub use calib::{describe_camera, parse_calib};
pub use layout::{frame_name, parse_sequence, scan_paths, Layout, SequenceFiles, SequenceLayout};
pub use poses::{check_pose_count, dist3, gt_scale, parse_poses, parse_poses_in, position, PoseRow, POSES_FILE};

use crate::camera::Camera;
use crate::{Error, Result};

/// Where a sequence's camera comes from.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum CameraSource {
    /// Its `calib.txt` (the path relative to the dataset root).
    Calib(String),
    /// The lab's layout without a `calib.txt`: the lab's sequence-00 camera.
    LabDefault,
}

/// The camera of a sequence: `calib.txt`'s text if there is one, else the
/// lab's 00 camera in the lab's layout; KITTI's layout without one is an
/// error (its cameras differ from sequence to sequence).
pub fn sequence_camera(seq: &SequenceLayout, calib: Option<&str>) -> Result<(Camera, CameraSource)> {
    match (calib, seq.layout) {
        (Some(text), _) => Ok((parse_calib(text, &seq.calib_file())?, CameraSource::Calib(seq.calib_file()))),
        (None, Layout::Lab) => Ok((Camera::default(), CameraSource::LabDefault)),
        (None, Layout::Kitti) => Err(Error::Dataset(format!(
            "{} has no {}: in KITTI's layout the camera comes from it (each sequence has its own); \
             put KITTI's calib.txt for sequence {} there",
            seq.describe(),
            seq.calib_file(),
            seq.sequence
        ))),
    }
}

/// What to tell the user about the camera, once: `None` when it came from
/// a `calib.txt`.
pub fn camera_note(seq: &SequenceLayout, source: &CameraSource) -> Option<String> {
    let lab = describe_camera(&Camera::default());
    match source {
        CameraSource::Calib(_) => None,
        CameraSource::LabDefault if seq.sequence == "00" => {
            Some(format!("camera: the lab's, KITTI sequence 00's ({lab}); {} has no calib.txt", seq.frame_dir()))
        }
        CameraSource::LabDefault => Some(format!(
            "warning: {} has no calib.txt, so sequence {}'s odometry uses the lab's sequence-00 camera ({lab}); \
             copy KITTI's sequences/{}/calib.txt to {} for its own",
            seq.frame_dir(),
            seq.sequence,
            seq.sequence,
            seq.calib_file()
        )),
    }
}

/// The error for frame `i` (`what`: its file) whose size differs from
/// frame `j`'s, read before it.
pub fn frame_size_error(what: &str, i: usize, size: (usize, usize), j: usize, first: (usize, usize)) -> Error {
    Error::Dataset(format!(
        "frame {i} ({what}) is {}x{} but frame {j} is {}x{}: every frame of a sequence must have the same size \
         (frames of different KITTI sequences cannot be mixed)",
        size.0, size.1, first.0, first.1
    ))
}

/// Checks that encoded frames 0, 1, … (PNG; other formats are checked
/// when decoded) all have frame 0's size, from their headers alone.
pub fn check_same_size(frames: &[Vec<u8>], seq: &SequenceLayout) -> Result<()> {
    let mut first = None;
    for (i, bytes) in frames.iter().enumerate() {
        let Some((w, h)) = crate::gray_png::ihdr_size(bytes) else { continue };
        let size = (w as usize, h as usize);
        match first {
            None => first = Some((i, size)),
            Some((j, f)) if f != size => return Err(frame_size_error(&seq.frame_path(i), i, size, j, f)),
            Some(_) => {}
        }
    }
    Ok(())
}

/// A sequence of a dataset folder, in either layout.
#[derive(Clone, Debug)]
pub struct Dataset {
    root: std::path::PathBuf,
    seq: SequenceLayout,
    frame_count: usize,
    poses: Option<Vec<PoseRow>>,
    camera: Camera,
    camera_source: CameraSource,
    /// The first frame read and its width and height: every frame read
    /// after it must share them.
    first_size: std::sync::OnceLock<(usize, (usize, usize))>,
}

impl Dataset {
    /// The lab's sequence 00 under `root` ([`Dataset::open_sequence`]).
    #[cfg(not(target_arch = "wasm32"))]
    pub fn open(root: &std::path::Path) -> Result<Dataset> {
        Dataset::open_sequence(root, "00")
    }

    /// Opens sequence `sequence` of `root` in whichever layout holds it,
    /// reads its camera and poses (if any), counts the consecutive frames
    /// from 000000.png and reads frame 0's size.
    #[cfg(not(target_arch = "wasm32"))]
    pub fn open_sequence(root: &std::path::Path, sequence: &str) -> Result<Dataset> {
        let sequence = parse_sequence(sequence)?;
        let layouts = format!(
            "expected gray/{sequence}/image_0/ (the lab's MyKITTI layout) or sequences/{sequence}/image_0/ \
             (KITTI's odometry layout)"
        );
        if !root.is_dir() {
            return Err(Error::Dataset(format!(
                "dataset folder {} does not exist ({layouts}); pass it with -d DATASET",
                root.display()
            )));
        }
        let has = |l: Layout| root.join(SequenceLayout { layout: l, sequence: sequence.clone() }.frame_dir()).is_dir();
        let Some(seq) = layout::pick_layout(&sequence, has(Layout::Lab), has(Layout::Kitti)) else {
            return Err(Error::Dataset(format!(
                "{} has no sequence {sequence}: {layouts}; sequences there: {} (choose one with -s)",
                root.display(),
                layout::describe_sequences(&sequences_in(root))
            )));
        };
        let read_text = |rel: &str| -> Result<Option<String>> {
            let path = root.join(rel);
            if !path.is_file() {
                return Ok(None);
            }
            let bytes =
                std::fs::read(&path).map_err(|e| Error::Dataset(format!("cannot read {}: {e}", path.display())))?;
            String::from_utf8(bytes)
                .map(Some)
                .map_err(|_| Error::Dataset(format!("{} is not a text file", path.display())))
        };
        let (camera, camera_source) = sequence_camera(&seq, read_text(&seq.calib_file())?.as_deref())
            .map_err(|e| Error::Dataset(format!("{}: {e}", root.display())))?;
        let poses = read_text(&seq.poses_file())?
            .map(|t| parse_poses_in(&t, &seq.poses_file()))
            .transpose()
            .map_err(|e| Error::Dataset(format!("{}: {e}", root.display())))?;
        let frames = root.join(seq.frame_dir());
        let mut frame_count = 0;
        while frames.join(frame_name(frame_count)).is_file() {
            frame_count += 1;
        }
        Ok(Dataset {
            root: root.to_path_buf(),
            seq,
            frame_count,
            poses,
            camera,
            camera_source,
            first_size: Default::default(),
        })
    }

    /// A dataset whose frames come from elsewhere (the web app's folder
    /// picker): only the poses and the frame count are known here.
    pub fn from_parts(root: std::path::PathBuf, frame_count: usize, poses: Option<Vec<PoseRow>>) -> Dataset {
        Dataset {
            root,
            seq: SequenceLayout::lab(),
            frame_count,
            poses,
            camera: Camera::default(),
            camera_source: CameraSource::LabDefault,
            first_size: Default::default(),
        }
    }

    pub fn root(&self) -> &std::path::Path {
        &self.root
    }

    /// The sequence and the layout it is stored in.
    pub fn sequence(&self) -> &SequenceLayout {
        &self.seq
    }

    /// Number of consecutive frames 000000.png, 000001.png, ... present.
    pub fn frame_count(&self) -> usize {
        self.frame_count
    }

    /// The size of the frames read so far (`None` before the first).
    pub fn frame_size(&self) -> Option<(usize, usize)> {
        self.first_size.get().map(|f| f.1)
    }

    /// The ground-truth poses; empty when the sequence has none.
    pub fn poses(&self) -> &[PoseRow] {
        self.poses.as_deref().unwrap_or(&[])
    }

    /// Whether `poses/NN.txt` is there.
    pub fn has_poses(&self) -> bool {
        self.poses.is_some()
    }

    /// The poses, or why `what` cannot run without them.
    pub fn require_poses(&self, what: &str) -> Result<&[PoseRow]> {
        self.poses.as_deref().ok_or_else(|| {
            Error::Dataset(format!(
                "{what} needs the ground-truth poses {} (the lab's loop takes each frame's scale from them), \
                 and {} has none for sequence {} (KITTI publishes poses for sequences 00 to 10 only)",
                self.seq.poses_file(),
                self.root.display(),
                self.seq.sequence
            ))
        })
    }

    /// The camera the odometry and the epipolar judge use.
    pub fn camera(&self) -> &Camera {
        &self.camera
    }

    pub fn camera_source(&self) -> &CameraSource {
        &self.camera_source
    }

    /// What to say once about the camera (the lab's default in use).
    pub fn camera_note(&self) -> Option<String> {
        camera_note(&self.seq, &self.camera_source)
    }

    pub fn frame_path(&self, i: usize) -> std::path::PathBuf {
        self.root.join(self.seq.frame_path(i))
    }

    /// Checks that frames 0..n and their poses exist.
    pub fn check_frames(&self, n: usize) -> Result<()> {
        // A picked folder can have no frame at all (`from_parts` with 0):
        // "frames 0 to -1" cannot be said, and `frame_count - 1` underflowed
        // (found by fuzzing, tests/fuzz/regressions/poses).
        if n > 0 && self.frame_count == 0 {
            return Err(Error::Dataset(format!(
                "frames 0 to {} are needed but {} has no frame {}",
                n - 1,
                self.root.display(),
                self.seq.frame_path(0)
            )));
        }
        if n > self.frame_count {
            return Err(Error::Dataset(format!(
                "frames 0 to {} are needed but {} has frames 0 to {} only ({} is missing); ask for FRAME_ID {} or less",
                n - 1,
                self.root.display(),
                self.frame_count - 1,
                self.seq.frame_path(self.frame_count),
                self.frame_count - 1
            )));
        }
        let poses = self.require_poses("the odometry")?;
        check_pose_count(&self.seq.poses_file(), poses.len(), n)
    }

    /// Frame `i` as `cv2.imread(path, 0)` reads it; a frame whose size is
    /// not frame 0's is an error.
    #[cfg(not(target_arch = "wasm32"))]
    pub fn load_frame(&self, i: usize) -> Result<crate::GrayImage> {
        let path = self.frame_path(i);
        let bytes = std::fs::read(&path).map_err(|e| {
            Error::Dataset(format!(
                "cannot read frame {i}: {} ({e}); {} needs {}",
                path.display(),
                self.seq.describe(),
                self.seq.frame_path(i)
            ))
        })?;
        let img = crate::GrayImage::decode(&bytes)
            .map_err(|e| Error::Decode(format!("frame {i} ({}): {e}", path.display())))?;
        let size = (img.width(), img.height());
        let &(j, first) = self.first_size.get_or_init(|| (i, size));
        if size != first {
            return Err(frame_size_error(&self.seq.frame_path(i), i, size, j, first));
        }
        Ok(img)
    }
}

/// The sequences a dataset folder holds in either layout (folders with an
/// `image_0` inside), for the message that names them.
#[cfg(not(target_arch = "wasm32"))]
fn sequences_in(root: &std::path::Path) -> Vec<SequenceLayout> {
    let mut out = Vec::new();
    for layout in [Layout::Lab, Layout::Kitti] {
        let Ok(entries) = std::fs::read_dir(root.join(layout.sequences_dir())) else { continue };
        for e in entries.flatten() {
            let name = e.file_name().to_string_lossy().into_owned();
            if name.len() == 2 && name.bytes().all(|b| b.is_ascii_digit()) && e.path().join("image_0").is_dir() {
                out.push(SequenceLayout { layout, sequence: name });
            }
        }
    }
    out.sort();
    out
}

#[cfg(all(test, not(target_arch = "wasm32")))]
mod tests {
    use super::*;
    use std::path::{Path, PathBuf};

    const TWO: &str = "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 0 0 1 0 0 0 0 1 1\n";
    const CALIB03: &str = "P0: 7.215377000000e+02 0.000000000000e+00 6.095593000000e+02 0.000000000000e+00 \
        0.000000000000e+00 7.215377000000e+02 1.728540000000e+02 0.000000000000e+00 0.000000000000e+00 \
        0.000000000000e+00 1.000000000000e+00 0.000000000000e+00\n";

    fn png(w: u32, h: u32) -> Vec<u8> {
        let img = image::GrayImage::from_fn(w, h, |x, y| image::Luma([(x * 20 + y) as u8]));
        let mut buf = Vec::new();
        image::DynamicImage::ImageLuma8(img)
            .write_to(&mut std::io::Cursor::new(&mut buf), image::ImageFormat::Png)
            .unwrap();
        buf
    }

    fn scratch(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("siftlab-ds-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    fn put(root: &Path, rel: &str, bytes: &[u8]) {
        let p = root.join(rel);
        std::fs::create_dir_all(p.parent().unwrap()).unwrap();
        std::fs::write(p, bytes).unwrap();
    }

    #[test]
    fn open_checks_the_labs_layout() {
        let dir = scratch("lab");
        let e = Dataset::open(&dir).unwrap_err().to_string();
        assert!(
            e.contains(
                "has no sequence 00: expected gray/00/image_0/ (the lab's MyKITTI layout) or sequences/00/image_0/"
            ),
            "{e}"
        );
        assert!(e.ends_with("sequences there: none (choose one with -s)"), "{e}");
        std::fs::create_dir_all(dir.join(SequenceLayout::lab().frame_dir())).unwrap();
        assert_eq!(Dataset::open(&dir).unwrap().frame_count(), 0);
        put(&dir, "gray/00/image_0/000000.png", &png(8, 6));
        put(&dir, "gray/00/image_0/000001.png", b"not a png");
        // No poses: opens; the odometry says what it lacks.
        let ds = Dataset::open(&dir).unwrap();
        assert_eq!((ds.frame_count(), ds.frame_size(), ds.has_poses()), (2, None, false));
        assert_eq!(ds.camera(), &Camera::default());
        assert!(ds.camera_note().unwrap().starts_with("camera: the lab's, KITTI sequence 00's (fx = fy = 718.856"));
        let e = ds.check_frames(2).unwrap_err().to_string();
        assert!(e.starts_with("the odometry needs the ground-truth poses poses/00.txt (the lab's loop takes"), "{e}");
        put(&dir, POSES_FILE, TWO.as_bytes());
        let ds = Dataset::open(&dir).unwrap();
        assert_eq!(ds.load_frame(0).unwrap().get(2, 1), 41);
        let e = ds.load_frame(1).unwrap_err().to_string();
        assert!(e.starts_with("frame 1 ("), "{e}");
        let e =
            Dataset::from_parts("picked".into(), 0, Some(ds.poses().to_vec())).check_frames(1).unwrap_err().to_string();
        assert!(e.contains("has no frame gray/00/image_0/000000.png"), "{e}");
        let e = ds.check_frames(3).unwrap_err().to_string();
        assert!(e.contains("has frames 0 to 1 only (gray/00/image_0/000002.png is missing)"), "{e}");
        // A frame of another size.
        put(&dir, "gray/00/image_0/000001.png", &png(9, 6));
        let ds = Dataset::open(&dir).unwrap();
        assert_eq!(ds.load_frame(0).unwrap().width(), 8);
        assert_eq!(ds.frame_size(), Some((8, 6)));
        let e = ds.load_frame(1).unwrap_err().to_string();
        assert_eq!(
            e,
            "frame 1 (gray/00/image_0/000001.png) is 9x6 but frame 0 is 8x6: every frame of a sequence must have \
             the same size (frames of different KITTI sequences cannot be mixed)"
        );
        // Malformed poses are named with their file.
        put(&dir, POSES_FILE, b"1 2 3\n");
        let e = Dataset::open(&dir).unwrap_err().to_string();
        assert!(e.ends_with("poses/00.txt line 1: expected 12 numbers (a 3x4 [R|t] matrix), found 3"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn encoded_frames_of_two_sizes_are_refused() {
        let seq = SequenceLayout::new(Layout::Kitti, "04").unwrap();
        assert!(check_same_size(&[png(8, 6), png(8, 6), b"not a png".to_vec()], &seq).is_ok());
        let e = check_same_size(&[png(8, 6), png(8, 6), png(7, 6)], &seq).unwrap_err().to_string();
        assert!(e.starts_with("frame 2 (sequences/04/image_0/000002.png) is 7x6 but frame 0 is 8x6"), "{e}");
    }

    #[test]
    fn open_reads_kittis_layout_and_its_camera() {
        let dir = scratch("kitti");
        put(&dir, "sequences/03/image_0/000000.png", &png(8, 6));
        let e = Dataset::open_sequence(&dir, "03").unwrap_err().to_string();
        assert!(
            e.contains("sequence 03 (KITTI's odometry layout) has no sequences/03/calib.txt: in KITTI's layout the camera comes from it"),
            "{e}"
        );
        put(&dir, "sequences/03/calib.txt", b"P0: 1 2 3\n");
        let e = Dataset::open_sequence(&dir, "03").unwrap_err().to_string();
        assert!(e.contains("sequences/03/calib.txt line 1: P0 has 3 numbers, not 12"), "{e}");
        put(&dir, "sequences/03/calib.txt", CALIB03.as_bytes());
        let ds = Dataset::open_sequence(&dir, "3").unwrap();
        assert_eq!(ds.camera(), &Camera { fx: 721.5377, fy: 721.5377, cx: 609.5593, cy: 172.854 });
        assert_eq!(ds.camera_note(), None);
        assert_eq!(ds.frame_path(4), dir.join("sequences/03/image_0/000004.png"));
        let e = ds.require_poses("view_trajectory").unwrap_err().to_string();
        assert!(
            e.contains("needs the ground-truth poses poses/03.txt") && e.contains("sequences 00 to 10 only"),
            "{e}"
        );
        let e = Dataset::open_sequence(&dir, "05").unwrap_err().to_string();
        assert!(
            e.contains("has no sequence 05") && e.ends_with("sequences there: 03 (in sequences/) (choose one with -s)"),
            "{e}"
        );
        // The lab's layout without calib.txt for another sequence: warned.
        put(&dir, "gray/07/image_0/000000.png", &png(8, 6));
        let note = Dataset::open_sequence(&dir, "07").unwrap().camera_note().unwrap();
        assert!(
            note.starts_with("warning: gray/07/image_0 has no calib.txt, so sequence 07's odometry uses the lab's"),
            "{note}"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
