//! Getting frame bytes to the SIFT worker: the demo (fetched from our own
//! origin), single files (picker or drop), or a MyKITTI folder (directory
//! picker). Failures become an inline message; what was loaded stays.

use crate::model::frame::FrameData;
use crate::model::frameset::{first_pair, has_pair, missing_pair_message};
use crate::model::lab::{Job, Lab, Source, Which};
use crate::platform::now_ms;
use crate::services::sift_pool;
use leptos::prelude::*;
use std::cell::RefCell;
use std::collections::BTreeMap;
use std::sync::Arc;
use wasm_bindgen::JsCast;
use wasm_bindgen_futures::JsFuture;

/// Files larger than this are refused before reading: no PNG/JPEG below the
/// core's pixel limit is anywhere near it.
pub const MAX_FILE_BYTES: f64 = 200.0 * 1024.0 * 1024.0;

/// The lab's layout inside a MyKITTI folder (the core's `gray/00/image_0/%06d.png`).
pub fn frame_path(id: u32) -> String {
    siftlab_core::dataset::frame_relative_path(id as usize)
}

/// The frame id of a path inside a MyKITTI folder, if it is one of its frames.
pub fn frame_id_of(path: &str) -> Option<u32> {
    let dir = format!("{}/", siftlab_core::dataset::FRAME_DIR);
    let rest = path.rsplit_once(dir.as_str())?.1;
    let digits = rest.strip_suffix(".png")?;
    if digits.len() == 6 && digits.bytes().all(|b| b.is_ascii_digit()) {
        digits.parse().ok()
    } else {
        None
    }
}

thread_local! {
    static FOLDER: RefCell<BTreeMap<u32, web_sys::File>> = const { RefCell::new(BTreeMap::new()) };
    static FOLDER_POSES: RefCell<Option<web_sys::File>> = const { RefCell::new(None) };
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
                _ => match FOLDER.with(|f| f.borrow().get(&id).cloned()) {
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
        lab.source.set(Source::Demo(ids));
        load_pair_from(lab, fid, true);
    });
}

/// The files of a directory picker: keeps the frames in the lab's layout.
pub fn open_folder(lab: Lab, files: web_sys::FileList, frame_id: Option<u32>) {
    let mut frames = BTreeMap::new();
    let mut poses = None;
    let mut any = false;
    for i in 0..files.length() {
        if let Some(f) = files.get(i) {
            any = true;
            let path = js_sys::Reflect::get(&f, &"webkitRelativePath".into())
                .ok()
                .and_then(|v| v.as_string())
                .filter(|p| !p.is_empty())
                .unwrap_or_else(|| f.name());
            if let Some(id) = frame_id_of(&path) {
                frames.insert(id, f);
            } else if path.ends_with("poses/00.txt") {
                poses = Some(f);
            }
        }
    }
    if !any {
        return;
    }
    if frames.is_empty() {
        lab.load_error.set(Some(
            "this folder is not in the MyKITTI layout: no gray/00/image_0/NNNNNN.png frames found \
             (open the folder that contains gray/ and poses/)"
                .into(),
        ));
        return;
    }
    let ids: Vec<u32> = frames.keys().copied().collect();
    FOLDER.with(|f| *f.borrow_mut() = frames);
    FOLDER_POSES.with(|p| *p.borrow_mut() = poses);
    // A folder in the right layout settles any earlier loading error.
    lab.load_error.set(None);
    let fid = frame_id.or_else(|| first_pair(&ids)).unwrap_or(1);
    lab.source.set(Source::Folder(ids));
    load_pair_from(lab, fid, true);
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

/// Frame `id`'s file of the current source (the demo or a MyKITTI folder).
pub async fn frame_bytes(source: &Source, id: u32) -> Result<Vec<u8>, String> {
    match source {
        Source::Demo(_) => fetch_bytes(&format!("demo/{}", frame_path(id))).await,
        Source::Folder(_) => {
            let file = FOLDER.with(|f| f.borrow().get(&id).cloned()).ok_or("open the folder again")?;
            read_file(&file).await.map_err(|e| format!("{}: {e}", frame_path(id)))
        }
        Source::Files => Err("marking needs the demo or a MyKITTI folder (frame pairs by FRAME_ID)".into()),
    }
}

/// Frames 0..n and the ground-truth poses of the current source, for the
/// odometry view (the lab's `view_trajectory FRAME_ID` runs frames 0 … FRAME_ID,
/// so n = FRAME_ID + 1).
pub async fn vo_inputs(source: &Source, n: u32) -> Result<(Vec<Vec<u8>>, String), String> {
    if let Some(missing) = (0..n).find(|i| !source.frames().contains(i)) {
        return Err(format!(
            "{} is missing: the odometry needs frames 0 … {}",
            frame_path(missing),
            n.saturating_sub(1)
        ));
    }
    let mut frames = Vec::with_capacity(n as usize);
    let poses = match source {
        Source::Demo(_) => {
            for i in 0..n {
                frames.push(fetch_bytes(&format!("demo/{}", frame_path(i))).await?);
            }
            fetch_text("demo/poses/00.txt").await?
        }
        Source::Folder(_) => {
            for i in 0..n {
                let file = FOLDER.with(|f| f.borrow().get(&i).cloned()).ok_or("open the folder again")?;
                frames.push(read_file(&file).await.map_err(|e| format!("{}: {e}", frame_path(i)))?);
            }
            let file = FOLDER_POSES
                .with(|p| p.borrow().clone())
                .ok_or("the folder has no poses/00.txt: the lab takes the scale from the ground-truth poses")?;
            let bytes = read_file(&file).await?;
            String::from_utf8(bytes).map_err(|_| "poses/00.txt is not text".to_string())?
        }
        Source::Files => return Err("the odometry needs the demo or a MyKITTI folder (frames 0, 1, 2, …)".into()),
    };
    Ok((frames, poses))
}

/// The ground-truth poses of frames FRAME_ID-1 and FRAME_ID when the source
/// has them (the demo, a folder with poses/00.txt); `None` for files picked
/// one by one, which the whole-frame view then counts without judging.
pub async fn pair_poses(source: &Source, frame_id: u32) -> Result<Option<[siftlab_core::dataset::PoseRow; 2]>, String> {
    let text = match source {
        Source::Demo(_) => fetch_text("demo/poses/00.txt").await?,
        Source::Folder(_) => match FOLDER_POSES.with(|p| p.borrow().clone()) {
            Some(file) => String::from_utf8(read_file(&file).await?).map_err(|_| "poses/00.txt is not text")?,
            None => return Ok(None),
        },
        Source::Files => return Ok(None),
    };
    let poses = siftlab_core::dataset::parse_poses(&text).map_err(|e| format!("poses/00.txt: {e}"))?;
    let i = frame_id as usize;
    match (i.checked_sub(1).and_then(|p| poses.get(p)), poses.get(i)) {
        (Some(a), Some(b)) => Ok(Some([*a, *b])),
        _ => Err(format!("poses/00.txt has {} poses: frame {frame_id} has none", poses.len())),
    }
}
