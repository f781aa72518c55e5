//! The explorer's loading jobs: a pair of frames, a picked or dropped file,
//! the demo or a MyKITTI folder's sequence, each analysed by the SIFT pool
//! and shown as a job while it runs. A newer request for a slot wins over an
//! older one still running; failures become an inline message and what was
//! loaded stays. Where the bytes come from is [`sources`]'s.

use super::sources::{self, frame_path, read_file};
use crate::model::frame::FrameData;
use crate::model::frameset::{first_pair, has_pair, missing_pair_message};
use crate::model::lab::{Job, Lab, Source, Which};
use crate::model::sequence::{default_sequence, sequence_option, SequenceInfo};
use crate::platform::now_ms;
use crate::services::sift_pool;
use leptos::prelude::*;
use siftlab_core::dataset::{scan_paths, sequence_camera, SequenceLayout};
use std::sync::Arc;

static NEXT_JOB: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1);

fn start_job(lab: Lab, what: String, stage: &str) -> u64 {
    let id = NEXT_JOB.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    lab.jobs.update(|j| j.push(Job { id, what, stage: stage.into(), started_ms: now_ms() }));
    id
}

fn job_stage(lab: Lab, id: u64, stage: String) {
    lab.jobs.update(|j| {
        if let Some(job) = j.iter_mut().find(|j| j.id == id) {
            job.stage = stage;
        }
    });
}

fn end_job(lab: Lab, id: u64) {
    lab.jobs.update(|j| j.retain(|j| j.id != id));
}

fn bump(lab: Lab, which: Which) -> u64 {
    let i = which as usize;
    let mut g = 0;
    lab.generation.update(|gen| {
        gen[i] += 1;
        g = gen[i];
    });
    g
}

fn is_current(lab: Lab, which: Which, g: u64) -> bool {
    lab.generation.with_untracked(|gen| gen[which as usize] == g)
}

/// Analyses `bytes` as the frame `which`; on success it replaces that frame,
/// on failure the message is shown and the old frame stays.
pub fn load_bytes(lab: Lab, which: Which, label: String, bytes: Vec<u8>) {
    load_bytes_gen(lab, which, label, bytes, bump(lab, which));
}

fn load_bytes_gen(lab: Lab, which: Which, label: String, bytes: Vec<u8>, g: u64) {
    let job = start_job(lab, format!("{}: {label}", which.name()), "queued");
    let done_label = label.clone();
    let lanes = lab.lanes.get_untracked();
    let kept = Arc::new(bytes.clone());
    sift_pool::sift(
        bytes,
        lanes,
        move |stage| job_stage(lab, job, stage),
        move |r| {
            end_job(lab, job);
            if !is_current(lab, which, g) {
                return;
            }
            match r {
                Ok(res) => {
                    // A good frame in this slot settles an earlier error about it.
                    if lab.load_error.with_untracked(|e| e.as_ref().is_some_and(|e| e.starts_with(which.name()))) {
                        lab.load_error.set(None);
                    }
                    lab.frame(which).set(Some(Arc::new(FrameData::from_result(done_label, res, kept, lanes))));
                }
                Err(e) => lab.load_error.set(Some(format!("{} ({label}): {e}", which.name()))),
            }
        },
    );
}

/// A file picked or dropped for one slot.
pub fn load_file(lab: Lab, which: Which, file: web_sys::File) {
    let g = bump(lab, which);
    let name = file.name();
    leptos::task::spawn_local(async move {
        let job = start_job(lab, format!("{}: {name}", which.name()), "reading the file");
        let bytes = read_file(&file).await;
        end_job(lab, job);
        match bytes {
            Ok(b) => {
                lab.source.set(Source::Files);
                load_bytes_gen(lab, which, name, b, g);
            }
            Err(e) => lab.load_error.set(Some(format!("{} ({name}): {e}", which.name()))),
        }
    });
}

/// Loads the pair (FRAME_ID-1, FRAME_ID) from the current source.
pub fn load_pair(lab: Lab, frame_id: u32) {
    load_pair_from(lab, frame_id, false);
}

/// `fresh`: the source just changed, so frames with the same names are not the same frames.
fn load_pair_from(lab: Lab, frame_id: u32, fresh: bool) {
    let source = lab.source.get_untracked();
    let where_ = match source {
        Source::Demo(_) => "the demo",
        _ => "the folder",
    };
    if let Some(message) = missing_pair_message(where_, source.frames(), frame_id) {
        lab.load_error.set(Some(message));
        return;
    }
    let showing =
        |w: Which, id: u32| lab.frame(w).with_untracked(|f| f.as_ref().is_some_and(|f| f.label == frame_path(id)));
    let pending = lab.jobs.with_untracked(|j| j.iter().any(|j| j.what.ends_with(&frame_path(frame_id))));
    if !fresh
        && lab.frame_id.get_untracked() == frame_id
        && (pending || (showing(Which::Prev, frame_id - 1) && showing(Which::Cur, frame_id)))
    {
        // Already shown or on its way (e.g. a second event for the same FRAME_ID).
        return;
    }
    lab.frame_id.set(frame_id);
    // A pair that is there settles an earlier message about one that was not.
    lab.load_error.set(None);
    for (which, id) in [(Which::Prev, frame_id - 1), (Which::Cur, frame_id)] {
        let g = bump(lab, which);
        let path = frame_path(id);
        let source = source.clone();
        leptos::task::spawn_local(async move {
            let job = start_job(lab, format!("{}: {path}", which.name()), "reading the file");
            let bytes = match source {
                Source::Demo(_) => sources::fetch_bytes(&format!("demo/{path}")).await,
                _ => match sources::folder_file(id) {
                    Some(file) => read_file(&file).await,
                    None => Err("the frame is no longer available; open the folder again".into()),
                },
            };
            end_job(lab, job);
            match bytes {
                Ok(b) => load_bytes_gen(lab, which, path, b, g),
                Err(e) => lab.load_error.set(Some(format!("{} ({path}): {e}", which.name()))),
            }
        });
    }
}

/// The demo: `demo/index.txt` lists the frame ids, `demo/ATTRIBUTION.txt` says
/// where they come from (shown next to the button). Only these two small files
/// are fetched here; a frame is fetched when a pair or the odometry needs it,
/// so the bundled frames cost nothing until then.
pub fn load_demo(lab: Lab, frame_id: Option<u32>) {
    leptos::task::spawn_local(async move {
        let job = start_job(lab, "demo".into(), "reading the demo index");
        let index = sources::fetch_text("demo/index.txt").await;
        if let Ok(a) = sources::fetch_text("demo/ATTRIBUTION.txt").await {
            lab.attribution.set(a.trim().to_string());
        }
        end_job(lab, job);
        let ids: Vec<u32> = match index {
            Ok(t) => t.lines().filter_map(|l| l.trim().parse().ok()).collect(),
            Err(e) => {
                lab.load_error.set(Some(format!("cannot load the demo: {e}")));
                return;
            }
        };
        let Some(first) = first_pair(&ids) else {
            lab.load_error.set(Some("the demo needs two consecutive frames".into()));
            return;
        };
        let fid = frame_id.unwrap_or(first);
        if !has_pair(&ids, fid) && lab.cur.with_untracked(Option::is_none) {
            // A link to a pair the demo lacks: nothing is loaded (another pair's
            // result under the link's settings would read as its answer), the
            // FRAME_ID box shows what was asked, and the message below says why.
            lab.frame_id.set(fid);
        }
        sources::use_labels(SequenceLayout::lab());
        lab.sequence.set(SequenceInfo::demo());
        lab.source.set(Source::Demo(ids));
        load_pair_from(lab, fid, true);
    });
}

/// The files of a directory picker: finds the KITTI sequences in them (the
/// lab's layout or KITTI's) and opens one ([`use_sequence`]).
pub fn open_folder(lab: Lab, all: Vec<web_sys::File>, frame_id: Option<u32>) {
    let paths: Vec<String> = all.iter().map(sources::relative_path).collect();
    if all.is_empty() {
        return;
    }
    let scan = scan_paths(paths.iter().map(String::as_str));
    if scan.is_empty() {
        lab.load_error.set(Some(
            "this folder holds no KITTI frames: expected gray/NN/image_0/NNNNNN.png (the lab's MyKITTI layout) \
             or sequences/NN/image_0/NNNNNN.png (KITTI's odometry layout); open the folder that contains gray/ \
             or sequences/ (and poses/)"
                .into(),
        ));
        return;
    }
    let current = matches!(lab.source.get_untracked(), Source::Folder(_)).then(|| lab.sequence.get_untracked().seq);
    let Some(key) = default_sequence(scan.keys(), current.as_ref()) else { return };
    lab.folder_sequences.set(scan.iter().map(|(k, f)| (k.clone(), sequence_option(k, f))).collect());
    sources::keep_picked(all, scan);
    use_sequence(lab, key, frame_id);
}

/// Opens sequence `key` of the picked folder: reads its camera (its
/// `calib.txt`, or the lab's 00 camera in the lab's layout without one) and
/// shows its pair FRAME_ID (or its first). A camera that cannot be read
/// leaves what was shown and says why.
pub fn use_sequence(lab: Lab, key: SequenceLayout, frame_id: Option<u32>) {
    let picked = sources::picked_sequence(&key);
    let Some((frames, poses, calib)) = picked else {
        lab.load_error.set(Some(format!("the folder has no {}: open the folder again", key.describe())));
        return;
    };
    // A sequence that cannot be opened leaves the shown one (and puts the
    // choice back on it).
    let refuse = move |message: String| {
        lab.load_error.set(Some(message));
        lab.sequence.update(|_| ());
    };
    leptos::task::spawn_local(async move {
        let calib_text = match calib {
            Some(file) => match read_file(&file)
                .await
                .and_then(|b| String::from_utf8(b).map_err(|_| format!("{} is not a text file", key.calib_file())))
            {
                Ok(t) => Some(t),
                Err(e) => return refuse(format!("{}: {e}", key.calib_file())),
            },
            None => None,
        };
        let (camera, camera_source) = match sequence_camera(&key, calib_text.as_deref()) {
            Ok(c) => c,
            Err(e) => return refuse(e.to_string()),
        };
        let ids: Vec<u32> = frames.keys().copied().collect();
        let info = SequenceInfo { seq: key.clone(), camera, camera_source, has_poses: poses.is_some() };
        sources::use_folder(key.clone(), frames, poses, camera);
        sources::use_labels(key);
        lab.sequence.set(info);
        // A sequence that opens settles any earlier loading error.
        lab.load_error.set(None);
        let fid = frame_id.filter(|&f| has_pair(&ids, f)).or_else(|| first_pair(&ids)).unwrap_or(1);
        lab.source.set(Source::Folder(ids));
        load_pair_from(lab, fid, true);
    });
}

/// Re-runs SIFT on the loaded frames (after the SIMD width changed).
pub fn reanalyse(lab: Lab) {
    for which in [Which::Prev, Which::Cur] {
        if let Some(f) = lab.frame(which).get_untracked() {
            if f.lanes != lab.lanes.get_untracked() {
                load_bytes(lab, which, f.label.clone(), f.bytes.as_ref().clone());
            }
        }
    }
}
