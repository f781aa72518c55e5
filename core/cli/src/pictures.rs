//! PrairieLearn's `images[]`: for each task, the first wrong case drawn
//! (`siftlab_core::render::difference`: the frames at half size, the
//! reference's matches or points beside the returned ones) as a JPEG data
//! URL, so a student sees at once what the report's numbers say.

use siftlab_core::dataset::Dataset;
use siftlab_core::matching::DMatch;
use siftlab_core::render::{difference, encode_jpeg};
use siftlab_mark::{base64, Case, Difference, Marks, Pair, Task};

/// JPEG quality: the lines stay sharp enough at half size; ~60 KB a picture.
const QUALITY: u8 = 80;

/// One task's picture.
pub struct Picture {
    pub task: Task,
    pub label: String,
    /// `data:image/jpeg;base64,…`
    pub url: String,
}

/// The first wrong case of each task that has a picture, drawn on the
/// pair's frames (`pairs`: the features the marking used). A frame that
/// cannot be read any more costs its picture, not the marks.
pub fn first_wrong(marks: &Marks, ds: &Dataset, pairs: &[Pair]) -> Vec<Picture> {
    Task::ALL
        .iter()
        .filter_map(|&task| {
            let r = marks.results.iter().find(|r| r.case.task() == task && r.difference.is_some())?;
            let pair = pairs.iter().find(|p| p.id == r.case.frame())?;
            let f = r.case.frame() as usize;
            let (prev, cur) = (ds.load_frame(f - 1).ok()?, ds.load_frame(f).ok()?);
            let title = r.case.call_text();
            let img = match (r.difference.as_ref()?, &r.case) {
                (Difference::Matches { feature, both, missed, extra, counts }, _) => {
                    let pairs =
                        |v: &[DMatch]| v.iter().map(|m| (m.query_idx as i64, m.train_idx as i64)).collect::<Vec<_>>();
                    let extra: Vec<_> = extra.iter().map(|m| (m.query, m.train)).collect();
                    let (p, c) = (&pair.prev.keypoints, &pair.cur.keypoints);
                    let shown = [&pairs(both)[..], &pairs(missed)[..], &extra[..]];
                    difference::matches(&prev, p, &cur, c, &title, *feature, shown, *counts)
                }
                (Difference::Info { expected, returned }, Case::Info { .. }) => {
                    let got = returned.as_ref().map(|(q, pts)| (*q, pts.as_slice()));
                    difference::info(&prev, &cur, &title, (expected.query, &expected.points), got)
                }
                _ => return None,
            };
            let jpeg = encode_jpeg(&img, QUALITY).ok()?;
            Some(Picture {
                task,
                label: format!("{}: the first wrong case, {title}", task.name()),
                url: format!("data:image/jpeg;base64,{}", base64(&jpeg)),
            })
        })
        .collect()
}
