//! Which KITTI sequence the frames come from (the demo's 00, or one of a
//! picked folder's, in the lab's layout or KITTI's), its camera, and how the
//! loader names them. Plain functions, tested natively.

use siftlab_core::dataset::{camera_note, describe_camera, CameraSource, SequenceFiles, SequenceLayout};
use siftlab_core::vo::Camera;

/// The sequence being shown and the camera its odometry and epipolar judge use.
#[derive(Clone, Debug, PartialEq)]
pub struct SequenceInfo {
    pub seq: SequenceLayout,
    pub camera: Camera,
    pub camera_source: CameraSource,
    /// Whether `poses/NN.txt` is there (the odometry and the judge need it).
    pub has_poses: bool,
}

impl SequenceInfo {
    /// The demo: the lab's sequence 00, its camera hard-coded as the lab does.
    pub fn demo() -> SequenceInfo {
        SequenceInfo {
            seq: SequenceLayout::lab(),
            camera: Camera::default(),
            camera_source: CameraSource::LabDefault,
            has_poses: true,
        }
    }

    /// `Sequence 03 (KITTI's odometry layout) · camera fx = fy = 721.5377, cx = …, cy = … from sequences/03/calib.txt`.
    pub fn camera_line(&self) -> String {
        let from = match &self.camera_source {
            CameraSource::Calib(file) => format!("from {file}"),
            CameraSource::LabDefault => "the lab's, KITTI 00's (no calib.txt)".into(),
        };
        let poses = if self.has_poses { "" } else { " · no ground-truth poses" };
        format!(
            "Sequence {} ({}) · camera {} {from}{poses}",
            self.seq.sequence,
            self.seq.layout.name(),
            describe_camera(&self.camera)
        )
    }

    /// The warning for another sequence run with the lab's 00 camera.
    pub fn warning(&self) -> Option<String> {
        camera_note(&self.seq, &self.camera_source).filter(|n| n.starts_with("warning"))
    }
}

/// The folder's sequence choice: `03 · sequences/ · 151 frames · poses · calib.txt`.
pub fn sequence_option(key: &SequenceLayout, files: &SequenceFiles) -> String {
    let dir = key.layout.sequences_dir();
    let mut parts = vec![format!("{} · {dir}/", key.sequence), format!("{} frames", files.frames.len())];
    parts.push(if files.poses.is_some() { "poses".into() } else { "no poses".into() });
    if files.calib.is_some() {
        parts.push("calib.txt".into());
    }
    parts.join(" · ")
}

/// The sequence a folder opens on: the one shown before if the folder has
/// it, else the lab's 00, else its first.
pub fn default_sequence<'a>(
    keys: impl IntoIterator<Item = &'a SequenceLayout>,
    current: Option<&SequenceLayout>,
) -> Option<SequenceLayout> {
    let keys: Vec<&SequenceLayout> = keys.into_iter().collect();
    if let Some(c) = current.filter(|c| keys.contains(c)) {
        return Some(c.clone());
    }
    keys.iter().find(|k| k.sequence == "00").or(keys.first()).map(|k| (*k).clone())
}

#[cfg(test)]
mod tests {
    use super::*;
    use siftlab_core::dataset::Layout;

    #[test]
    fn the_camera_line_says_where_the_camera_comes_from() {
        assert_eq!(
            SequenceInfo::demo().camera_line(),
            "Sequence 00 (the lab's MyKITTI layout) · camera fx = fy = 718.856, cx = 607.1928, cy = 185.2157 \
             the lab's, KITTI 00's (no calib.txt)"
        );
        let seq = SequenceLayout::new(Layout::Kitti, "03").unwrap();
        let info = SequenceInfo {
            camera: Camera { fx: 721.5377, fy: 721.5377, cx: 609.5593, cy: 172.854 },
            camera_source: CameraSource::Calib(seq.calib_file()),
            seq,
            has_poses: false,
        };
        assert_eq!(
            info.camera_line(),
            "Sequence 03 (KITTI's odometry layout) · camera fx = fy = 721.5377, cx = 609.5593, cy = 172.854 \
             from sequences/03/calib.txt · no ground-truth poses"
        );
        assert_eq!(info.warning(), None);
        let lab07 = SequenceInfo { seq: SequenceLayout::new(Layout::Lab, "07").unwrap(), ..SequenceInfo::demo() };
        assert!(lab07.warning().unwrap().starts_with("warning: gray/07/image_0 has no calib.txt"));
        assert_eq!(SequenceInfo::demo().warning(), None);
    }

    #[test]
    fn a_folder_opens_on_the_sequence_shown_or_00() {
        let found = siftlab_core::dataset::scan_paths([
            "d/sequences/03/image_0/000000.png",
            "d/sequences/03/calib.txt",
            "d/poses/03.txt",
            "d/sequences/00/image_0/000000.png",
            "d/sequences/00/image_0/000001.png",
        ]);
        let k03 = SequenceLayout::new(Layout::Kitti, "03").unwrap();
        assert_eq!(default_sequence(found.keys(), None).unwrap().sequence, "00");
        assert_eq!(default_sequence(found.keys(), Some(&k03)), Some(k03.clone()));
        assert_eq!(default_sequence(found.keys(), Some(&SequenceLayout::lab())).unwrap().sequence, "00");
        assert_eq!(sequence_option(&k03, &found[&k03]), "03 · sequences/ · 1 frames · poses · calib.txt");
        let k00 = SequenceLayout::new(Layout::Kitti, "00").unwrap();
        assert_eq!(sequence_option(&k00, &found[&k00]), "00 · sequences/ · 2 frames · no poses");
        assert_eq!(default_sequence([], None), None);
    }
}
