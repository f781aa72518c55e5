//! Getting frame bytes to the SIFT worker: the demo (fetched from our own
//! origin), single files (picker or drop), or a MyKITTI folder (directory
//! picker). Failures become an inline message; what was loaded stays.

use crate::model::frame::FrameData;
use crate::model::frameset::{first_pair, has_pair, missing_pair_message};
use crate::model::lab::{Job, Lab, Source, Which};
use crate::model::sequence::{default_sequence, sequence_option, SequenceInfo};
use crate::platform::now_ms;
use crate::services::sift_pool;
use leptos::prelude::*;
use siftlab_core::dataset::{scan_paths, sequence_camera, SequenceFiles, SequenceLayout};
use siftlab_core::vo::Camera;
use std::cell::RefCell;
use std::collections::BTreeMap;
use std::sync::Arc;
use wasm_bindgen::JsCast;
use wasm_bindgen_futures::JsFuture;

/// Files larger than this are refused before reading: no PNG/JPEG below the
/// core's pixel limit is anywhere near it.
pub const MAX_FILE_BYTES: f64 = 200.0 * 1024.0 * 1024.0;

/// Frame `id`'s path in the current source's sequence: the demo's
/// `gray/00/image_0/%06d.png`, or the picked folder's (`sequences/03/image_0/…`).
/// Frames are labelled by it.
pub fn frame_path(id: u32) -> String {
    LABELS.with(|s| s.borrow().frame_path(id as usize))
}

/// A picked folder: its files and the sequences found among their paths.
struct Picked {
    files: Vec<web_sys::File>,
    scan: BTreeMap<SequenceLayout, SequenceFiles>,
}

/// The sequence in use from a picked folder: its frames by id, its poses
/// file if any, and its camera.
struct Folder {
    seq: SequenceLayout,
    frames: BTreeMap<u32, web_sys::File>,
    poses: Option<web_sys::File>,
    camera: Camera,
}

thread_local! {
    static PICKED: RefCell<Option<Picked>> = const { RefCell::new(None) };
    static FOLDER: RefCell<Option<Folder>> = const { RefCell::new(None) };
    /// The layout frame labels follow (the demo's or the folder's sequence).
    static LABELS: RefCell<SequenceLayout> = RefCell::new(SequenceLayout::lab());
}

fn folder_file(id: u32) -> Option<web_sys::File> {
    FOLDER.with(|f| f.borrow().as_ref().and_then(|f| f.frames.get(&id).cloned()))
}

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

async fn fetch_bytes(url: &str) -> Result<Vec<u8>, String> {
    let window = web_sys::window().ok_or("no window")?;
    let resp = JsFuture::from(window.fetch_with_str(url)).await.map_err(|e| format!("cannot fetch {url}: {e:?}"))?;
    let resp: web_sys::Response = resp.dyn_into().map_err(|_| "fetch did not return a Response".to_string())?;
    if !resp.ok() {
        return Err(format!("{url}: HTTP {}", resp.status()));
    }
    let buf = JsFuture::from(resp.array_buffer().map_err(|e| format!("{e:?}"))?)
        .await
        .map_err(|e| format!("cannot read {url}: {e:?}"))?;
    Ok(js_sys::Uint8Array::new(&buf).to_vec())
}

async fn fetch_text(url: &str) -> Result<String, String> {
    let b = fetch_bytes(url).await?;
    String::from_utf8(b).map_err(|_| format!("{url} is not text"))
}

/// Reads a user's file, refusing absurd sizes before touching the bytes.
pub async fn read_file(file: &web_sys::File) -> Result<Vec<u8>, String> {
    if file.size() > MAX_FILE_BYTES {
        return Err(format!(
            "the file is {:.0} MB; siftlab reads images up to {:.0} MB (and {} pixels)",
            file.size() / 1048576.0,
            MAX_FILE_BYTES / 1048576.0,
            siftlab_core::image::MAX_PIXELS
        ));
    }
    let buf = JsFuture::from(file.array_buffer()).await.map_err(|e| format!("cannot read the file: {e:?}"))?;
    Ok(js_sys::Uint8Array::new(&buf).to_vec())
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
                Source::Demo(_) => fetch_bytes(&format!("demo/{path}")).await,
                _ => match folder_file(id) {
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
        let index = fetch_text("demo/index.txt").await;
        if let Ok(a) = fetch_text("demo/ATTRIBUTION.txt").await {
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
        LABELS.with(|s| *s.borrow_mut() = SequenceLayout::lab());
        lab.sequence.set(SequenceInfo::demo());
        lab.source.set(Source::Demo(ids));
        load_pair_from(lab, fid, true);
    });
}

/// The files of a directory picker: finds the KITTI sequences in them (the
/// lab's layout or KITTI's) and opens one ([`use_sequence`]).
pub fn open_folder(lab: Lab, files: web_sys::FileList, frame_id: Option<u32>) {
    let mut all = Vec::new();
    let mut paths = Vec::new();
    for i in 0..files.length() {
        if let Some(f) = files.get(i) {
            let path = js_sys::Reflect::get(&f, &"webkitRelativePath".into())
                .ok()
                .and_then(|v| v.as_string())
                .filter(|p| !p.is_empty())
                .unwrap_or_else(|| f.name());
            paths.push(path);
            all.push(f);
        }
    }
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
    PICKED.with(|p| *p.borrow_mut() = Some(Picked { files: all, scan }));
    use_sequence(lab, key, frame_id);
}

/// Opens sequence `key` of the picked folder: reads its camera (its
/// `calib.txt`, or the lab's 00 camera in the lab's layout without one) and
/// shows its pair FRAME_ID (or its first). A camera that cannot be read
/// leaves what was shown and says why.
pub fn use_sequence(lab: Lab, key: SequenceLayout, frame_id: Option<u32>) {
    let picked = PICKED.with(|p| {
        p.borrow().as_ref().and_then(|p| {
            let files = p.scan.get(&key)?;
            let file = |i: usize| p.files[i].clone();
            let frames: BTreeMap<u32, web_sys::File> = files.frames.iter().map(|(&id, &i)| (id, file(i))).collect();
            Some((frames, files.poses.map(file), files.calib.map(file)))
        })
    });
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
        FOLDER.with(|f| *f.borrow_mut() = Some(Folder { seq: key.clone(), frames, poses, camera }));
        LABELS.with(|s| *s.borrow_mut() = key);
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

/// Frame `id`'s file of the current source (the demo or a folder's sequence).
pub async fn frame_bytes(source: &Source, id: u32) -> Result<Vec<u8>, String> {
    match source {
        Source::Demo(_) => fetch_bytes(&format!("demo/{}", frame_path(id))).await,
        Source::Folder(_) => {
            let file = folder_file(id).ok_or("open the folder again")?;
            read_file(&file).await.map_err(|e| format!("{}: {e}", frame_path(id)))
        }
        Source::Files => Err("marking needs the demo or a MyKITTI folder (frame pairs by FRAME_ID)".into()),
    }
}

/// Where an odometry run reads its frames, one at a time when it needs
/// them: the demo's files (fetched from our origin) or a picked folder's
/// `File`s. A long sequence is never held in memory: a run keeps only the
/// frames within its look-ahead (issue 44: 4541 KITTI frames are 1.7 GB).
#[derive(Clone)]
pub enum FrameSource {
    Demo(usize),
    Folder(std::rc::Rc<Vec<web_sys::File>>),
}

impl FrameSource {
    /// The number of frames, 0 … len − 1.
    pub fn frame_count(&self) -> usize {
        match self {
            FrameSource::Demo(n) => *n,
            FrameSource::Folder(files) => files.len(),
        }
    }

    /// Frame `i`'s file.
    pub async fn bytes(&self, i: usize) -> Result<Vec<u8>, String> {
        match self {
            FrameSource::Demo(_) => fetch_bytes(&format!("demo/{}", frame_path(i as u32))).await,
            FrameSource::Folder(files) => {
                let file = files.get(i).ok_or("open the folder again")?;
                read_file(file).await.map_err(|e| format!("{}: {e}", frame_path(i as u32)))
            }
        }
    }

    /// An address the page can show frame `i` from, and whether it is an
    /// object URL to revoke when done (a folder's file: the browser reads it
    /// from disk, no copy in the page's memory).
    pub fn url(&self, i: usize) -> Option<(String, bool)> {
        match self {
            FrameSource::Demo(n) => (i < *n).then(|| (format!("demo/{}", frame_path(i as u32)), false)),
            FrameSource::Folder(files) => {
                web_sys::Url::create_object_url_with_blob(files.get(i)?).ok().map(|u| (u, true))
            }
        }
    }
}

/// What the odometry runs on: frames 0..n (read as the run goes), the
/// ground-truth poses (the lab's loop takes each frame's scale from them),
/// the sequence's camera, and frame 0's size (from its PNG header; `None`
/// for another format).
#[derive(Clone)]
pub struct VoInputs {
    pub frames: FrameSource,
    pub poses: String,
    pub camera: Camera,
    pub size: Option<(u32, u32)>,
}

/// Frames 0..n, the ground-truth poses and the camera of the current source,
/// for the odometry view (the lab's `view_trajectory FRAME_ID` runs frames
/// 0 … FRAME_ID, so n = FRAME_ID + 1). Only frame 0 is read here; the run
/// checks each later frame's size against it as it reads it.
pub async fn vo_inputs(source: &Source, n: u32) -> Result<VoInputs, String> {
    if let Some(missing) = (0..n).find(|i| !source.frames().contains(i)) {
        return Err(format!(
            "{} is missing: the odometry needs frames 0 … {}",
            frame_path(missing),
            n.saturating_sub(1)
        ));
    }
    let (frames, poses, camera, seq) = match source {
        Source::Demo(_) => (
            FrameSource::Demo(n as usize),
            fetch_text("demo/poses/00.txt").await?,
            Camera::default(),
            SequenceLayout::lab(),
        ),
        Source::Folder(_) => {
            let (seq, poses, camera) = FOLDER
                .with(|f| f.borrow().as_ref().map(|f| (f.seq.clone(), f.poses.clone(), f.camera)))
                .ok_or("open the folder again")?;
            let poses = poses.ok_or_else(|| {
                format!(
                    "the folder has no {}: the odometry needs the ground-truth poses (the lab's loop takes each \
                     frame's scale from them; KITTI publishes poses for sequences 00 to 10 only)",
                    seq.poses_file()
                )
            })?;
            let files = (0..n).map(|i| folder_file(i).ok_or("open the folder again")).collect::<Result<Vec<_>, _>>()?;
            let bytes = read_file(&poses).await?;
            let text = String::from_utf8(bytes).map_err(|_| format!("{} is not text", seq.poses_file()))?;
            (FrameSource::Folder(std::rc::Rc::new(files)), text, camera, seq)
        }
        Source::Files => return Err("the odometry needs the demo or a MyKITTI folder (frames 0, 1, 2, …)".into()),
    };
    // The poses are read here, where the file's name is known, so that a
    // malformed or short file is named (the workers only see its text).
    let file = seq.poses_file();
    let rows = siftlab_core::dataset::parse_poses_in(&poses, &file).map_err(|e| e.to_string())?;
    if rows.len() < n as usize {
        return Err(format!(
            "{file} has {} poses but the odometry needs {n} (frames 0 … {}): the lab takes each frame's scale from them",
            rows.len(),
            n - 1
        ));
    }
    let size = crate::model::odometry::frame::png_size(&frames.bytes(0).await?);
    Ok(VoInputs { frames, poses, camera, size })
}

/// The ground-truth poses of frames FRAME_ID-1 and FRAME_ID when the source
/// has them (the demo, a folder with poses/NN.txt); `None` for files picked
/// one by one or a sequence without poses, which the whole-frame view then
/// counts without judging.
pub async fn pair_poses(source: &Source, frame_id: u32) -> Result<Option<[siftlab_core::dataset::PoseRow; 2]>, String> {
    let (text, file) = match source {
        Source::Demo(_) => (fetch_text("demo/poses/00.txt").await?, siftlab_core::dataset::POSES_FILE.to_string()),
        Source::Folder(_) => {
            let Some((seq, poses)) = FOLDER.with(|f| f.borrow().as_ref().map(|f| (f.seq.clone(), f.poses.clone())))
            else {
                return Ok(None);
            };
            let Some(file) = poses else { return Ok(None) };
            let name = seq.poses_file();
            (String::from_utf8(read_file(&file).await?).map_err(|_| format!("{name} is not text"))?, name)
        }
        Source::Files => return Ok(None),
    };
    let poses = siftlab_core::dataset::parse_poses_in(&text, &file).map_err(|e| e.to_string())?;
    let i = frame_id as usize;
    match (i.checked_sub(1).and_then(|p| poses.get(p)), poses.get(i)) {
        (Some(a), Some(b)) => Ok(Some([*a, *b])),
        _ => Err(format!("{file} has {} poses: frame {frame_id} has none", poses.len())),
    }
}
