//! Where frames and poses come from: the demo (fetched from our own origin),
//! a user's files, or the sequence in use of a picked MyKITTI folder (kept
//! here between requests, with the layout frame labels follow). The
//! explorer's jobs ([`super::loading`]), the odometry, the whole-frame view
//! and the marking read their bytes through this module only.

use crate::model::lab::Source;
use siftlab_core::dataset::{SequenceFiles, SequenceLayout};
use siftlab_core::vo::Camera;
use std::cell::RefCell;
use std::collections::BTreeMap;
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

/// A picked folder's sequence: its frames by id, its poses file and its
/// calib.txt.
pub type SequenceFileSet = (BTreeMap<u32, web_sys::File>, Option<web_sys::File>, Option<web_sys::File>);

/// Keeps a directory picker's files and the sequences found among their paths.
pub fn keep_picked(files: Vec<web_sys::File>, scan: BTreeMap<SequenceLayout, SequenceFiles>) {
    PICKED.with(|p| *p.borrow_mut() = Some(Picked { files, scan }));
}

/// The picked folder's sequence `key`, if the folder has it.
pub fn picked_sequence(key: &SequenceLayout) -> Option<SequenceFileSet> {
    PICKED.with(|p| {
        p.borrow().as_ref().and_then(|p| {
            let files = p.scan.get(key)?;
            let file = |i: usize| p.files[i].clone();
            let frames = files.frames.iter().map(|(&id, &i)| (id, file(i))).collect();
            Some((frames, files.poses.map(file), files.calib.map(file)))
        })
    })
}

/// Makes `seq` of the picked folder the source of frames and poses.
pub fn use_folder(
    seq: SequenceLayout,
    frames: BTreeMap<u32, web_sys::File>,
    poses: Option<web_sys::File>,
    camera: Camera,
) {
    FOLDER.with(|f| *f.borrow_mut() = Some(Folder { seq, frames, poses, camera }));
}

/// Makes frame labels ([`frame_path`]) follow `layout`.
pub fn use_labels(layout: SequenceLayout) {
    LABELS.with(|s| *s.borrow_mut() = layout);
}

/// A file's path inside the folder a directory picker opened
/// (`webkitRelativePath`: "MyKITTI/gray/00/image_0/000000.png"), or its name
/// for a file picked alone.
pub fn relative_path(f: &web_sys::File) -> String {
    js_sys::Reflect::get(f, &"webkitRelativePath".into())
        .ok()
        .and_then(|v| v.as_string())
        .filter(|p| !p.is_empty())
        .unwrap_or_else(|| f.name())
}

/// Frame `id`'s file in the folder's sequence in use.
pub fn folder_file(id: u32) -> Option<web_sys::File> {
    FOLDER.with(|f| f.borrow().as_ref().and_then(|f| f.frames.get(&id).cloned()))
}

/// A file of our own origin (the demo's frames, index and poses).
pub async fn fetch_bytes(url: &str) -> Result<Vec<u8>, String> {
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

/// [`fetch_bytes`] as UTF-8 text.
pub async fn fetch_text(url: &str) -> Result<String, String> {
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
    siftlab_core::dataset::check_pose_count(&file, rows.len(), n as usize).map_err(|e| e.to_string())?;
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
