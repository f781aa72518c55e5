//! Who is who in a class folder (docs/marking.md, "A whole class"): the
//! entries SUBMISSIONS name, and the file of each that is marked, found as
//! the lab's marker finds it. The tree is a student's input: no link is
//! followed, nothing but a regular file is opened, every entry found becomes
//! a student or a refusal (a row of grades.csv either way).

use siftlab_mark::escaped;
use std::collections::BTreeMap;
use std::ffi::OsStr;
use std::fs::FileType;
use std::path::{Component, Path, PathBuf};

/// Folder levels searched for vision_tasks.py below a submission's top.
pub const MAX_DEPTH: usize = 16;
/// Entries (files, folders, links) one submission's search may list; past
/// it the submission is refused rather than searched on.
pub const MAX_ENTRIES: usize = 10_000;

/// One student of the class: an id and the file that is marked.
#[derive(Clone, Debug)]
pub struct Student {
    pub id: String,
    /// `None`: a folder without a vision_tasks.py (scores 0, "none found").
    pub file: Option<PathBuf>,
}

/// An entry that is not marked: the name its row shows (an id, or the
/// escaped name when it is no id) and why, a fixed label first.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Refused {
    pub name: String,
    pub reason: String,
}

/// Every entry SUBMISSIONS name, each once.
#[derive(Clone, Debug)]
pub enum Entry {
    Student(Student),
    Refused(Refused),
}

impl Entry {
    /// The order of grades.csv: by id (bytes), then by reason.
    pub fn key(&self) -> (String, String) {
        match self {
            Entry::Student(s) => (s.id.clone(), String::new()),
            Entry::Refused(r) => (r.name.clone(), r.reason.clone()),
        }
    }
}

/// The fixed labels a refusal's reason starts with.
pub mod why {
    pub const DUPLICATE: &str = "duplicate id";
    pub const ODD_NAME: &str = "odd name";
    pub const SYMLINK: &str = "symlink";
    pub const SPECIAL: &str = "special file";
    pub const NOT_PY: &str = "neither a folder nor a .py file";
    pub const MISSING: &str = "no such file or folder";
    pub const TOO_MANY: &str = "too many entries";
    pub const UNREADABLE: &str = "unreadable";
}

/// What a submission's search found.
#[derive(Clone, Debug)]
enum Found {
    File(PathBuf),
    None,
    Refused(String),
}

/// `path` as it can be shown: invalid UTF-8 as `\xNN`, a backslash doubled,
/// control and invisible characters escaped (no name repaints a terminal or
/// two names show alike).
pub fn shown(path: &Path) -> String {
    shown_os(path.as_os_str())
}

fn shown_os(name: &OsStr) -> String {
    let mut s = String::new();
    for chunk in name.as_encoded_bytes().utf8_chunks() {
        s.push_str(&chunk.valid().replace('\\', "\\\\"));
        for b in chunk.invalid() {
            s.push_str(&format!("\\x{b:02x}"));
        }
    }
    escaped(&s, 200)
}

/// The entries SUBMISSIONS name, sorted as grades.csv is. One argument that
/// is a folder without vision_tasks.py at its top is a class folder (one
/// entry per student inside); with several arguments (`subs/*`) each is one
/// submission, so no folder inside one can speak for another student.
pub fn discover(args: &[PathBuf]) -> Vec<Entry> {
    let mut found: Vec<(String, PathBuf, Found)> = Vec::new();
    let mut out: Vec<Entry> = Vec::new();
    let refuse =
        |out: &mut Vec<Entry>, name: String, reason: String| out.push(Entry::Refused(Refused { name, reason }));
    for arg in args {
        let meta = match std::fs::symlink_metadata(arg) {
            Ok(m) => m,
            Err(e) => {
                refuse(&mut out, shown(arg), format!("{}: {}", why::MISSING, e.kind()));
                continue;
            }
        };
        let ft = meta.file_type();
        if ft.is_dir() {
            let id = std::fs::canonicalize(arg).ok().and_then(|p| p.file_name().map(OsStr::to_os_string));
            let id = id.unwrap_or_else(|| arg.as_os_str().to_os_string());
            let top = std::fs::symlink_metadata(arg.join("vision_tasks.py")).is_ok();
            if args.len() > 1 || top {
                found.push((shown_os(&id), arg.clone(), search(arg)));
            } else {
                class_folder(arg, &mut found, &mut out);
            }
        } else if ft.is_file() && arg.file_name() == Some(OsStr::new("vision_tasks.py")) {
            // Its folder's name, unless that folder is a link (it would
            // speak for the student it points at).
            let parent = arg.parent().unwrap_or(Path::new(""));
            match parent.components().next_back() {
                Some(Component::Normal(n)) => {
                    if std::fs::symlink_metadata(parent).is_ok_and(|m| m.file_type().is_symlink()) {
                        refuse(&mut out, shown(parent), format!("{}: {}", why::SYMLINK, shown(arg)));
                    } else {
                        found.push((shown_os(n), arg.clone(), Found::File(arg.clone())));
                    }
                }
                _ => {
                    let real =
                        std::fs::canonicalize(if parent.as_os_str().is_empty() { Path::new(".") } else { parent });
                    let id = real.ok().and_then(|p| p.file_name().map(shown_os)).unwrap_or_default();
                    found.push((id, arg.clone(), Found::File(arg.clone())));
                }
            }
        } else {
            let id = arg.file_stem().map(shown_os).unwrap_or_default();
            found.push((id, arg.clone(), kind(ft, arg)));
        }
    }
    let mut by_id: BTreeMap<String, Vec<(PathBuf, Found)>> = BTreeMap::new();
    for (id, from, f) in found {
        if odd_id(&id) {
            refuse(&mut out, id, format!("{}: {}", why::ODD_NAME, ID_RULE));
        } else {
            by_id.entry(id).or_default().push((from, f));
        }
    }
    for (id, list) in by_id {
        if list.len() > 1 {
            // Both (all) rows, each naming the others: no one is dropped,
            // and the teaching assistant sees which folders to untangle.
            for (i, (from, _)) in list.iter().enumerate() {
                let others: Vec<String> =
                    list.iter().enumerate().filter(|(j, _)| *j != i).map(|(_, (p, _))| shown(p)).collect();
                let reason = format!("{}: {} and {}", why::DUPLICATE, shown(from), others.join(" and "));
                refuse(&mut out, id.clone(), reason);
            }
            continue;
        }
        for (_, f) in list {
            match f {
                Found::File(p) => out.push(Entry::Student(Student { id: id.clone(), file: Some(p) })),
                Found::None => out.push(Entry::Student(Student { id: id.clone(), file: None })),
                Found::Refused(reason) => refuse(&mut out, id.clone(), reason),
            }
        }
    }
    out.sort_by(|a, b| {
        let (ka, kb) = (a.key(), b.key());
        (ka.0.as_bytes(), ka.1.as_bytes()).cmp(&(kb.0.as_bytes(), kb.1.as_bytes()))
    });
    out
}

/// A class folder's entries: a sub-folder or `<id>.py` per student.
fn class_folder(dir: &Path, found: &mut Vec<(String, PathBuf, Found)>, out: &mut Vec<Entry>) {
    let rd = match std::fs::read_dir(dir) {
        Ok(rd) => rd,
        Err(e) => {
            out.push(Entry::Refused(Refused { name: shown(dir), reason: format!("{}: {e}", why::UNREADABLE) }));
            return;
        }
    };
    for e in rd.flatten() {
        let name = e.file_name();
        if ignored(&name) {
            continue;
        }
        let p = e.path();
        let Ok(ft) = e.file_type() else { continue };
        if ft.is_dir() {
            found.push((shown_os(&name), p.clone(), search(&p)));
        } else if name.as_encoded_bytes().ends_with(b".py") {
            let id = Path::new(&name).file_stem().map(shown_os).unwrap_or_default();
            found.push((id, p.clone(), kind(ft, &p)));
        } else if ft.is_file() {
            out.push(Entry::Refused(Refused { name: shown_os(&name), reason: why::NOT_PY.into() }));
        } else {
            let Found::Refused(reason) = kind(ft, &p) else { continue };
            out.push(Entry::Refused(Refused { name: shown_os(&name), reason }));
        }
    }
}

/// A file entry as found: marked if regular, else refused (never opened).
fn kind(ft: FileType, p: &Path) -> Found {
    use std::os::unix::fs::FileTypeExt;
    if ft.is_file() {
        Found::File(p.to_path_buf())
    } else if ft.is_symlink() {
        Found::Refused(why::SYMLINK.into())
    } else if ft.is_dir() {
        search(p)
    } else {
        let what = if ft.is_fifo() {
            "a FIFO"
        } else if ft.is_socket() {
            "a socket"
        } else if ft.is_block_device() || ft.is_char_device() {
            "a device"
        } else {
            "not a regular file"
        };
        Found::Refused(format!("{}: {what}", why::SPECIAL))
    }
}

/// Names the lab's marker passes over: dot-entries and macOS's archive folders.
fn ignored(name: &OsStr) -> bool {
    name.as_encoded_bytes().starts_with(b".") || name == "__MACOSX"
}

const ID_RULE: &str = "letters, digits and . _ - @ + only, a letter or digit first, at most 128";

/// Whether `id` cannot name a student's folder and row.
fn odd_id(id: &str) -> bool {
    let ok_char = |c: char| c.is_ascii_alphanumeric() || "._-@+".contains(c);
    id.is_empty() || id.len() > 128 || !id.chars().all(ok_char) || !id.starts_with(|c: char| c.is_ascii_alphanumeric())
}

/// The first vision_tasks.py under `dir`, as the lab's marker takes it:
/// shallowest first, then by byte-sorted path; dot-entries and __MACOSX
/// skipped; folder links never entered; at most [`MAX_DEPTH`] levels and
/// [`MAX_ENTRIES`] entries. A link or special file found there is refused.
fn search(dir: &Path) -> Found {
    let mut level = vec![dir.to_path_buf()];
    let mut listed = 0usize;
    for _ in 0..MAX_DEPTH {
        let mut files: Vec<(PathBuf, FileType)> = Vec::new();
        let mut next = Vec::new();
        for d in &level {
            let Ok(rd) = std::fs::read_dir(d) else { continue };
            for e in rd.flatten() {
                listed += 1;
                if listed > MAX_ENTRIES {
                    return Found::Refused(format!("{}: over {MAX_ENTRIES} in the submission", why::TOO_MANY));
                }
                let n = e.file_name();
                // file_type() does not follow a link: a link to a folder is no folder here.
                let (true, Ok(ft)) = (!ignored(&n), e.file_type()) else { continue };
                if ft.is_dir() {
                    next.push(e.path());
                } else if n == "vision_tasks.py" {
                    files.push((e.path(), ft));
                }
            }
        }
        if let Some((f, ft)) = files.into_iter().min_by(|a, b| a.0.as_os_str().cmp(b.0.as_os_str())) {
            return kind(ft, &f);
        }
        if next.is_empty() {
            return Found::None;
        }
        level = next;
    }
    Found::None
}

/// The file a single `siftlab mark FOLDER` marks (Gradescope's submission
/// folder): `Ok(None)` when there is none, `Err` (the reason) when the one
/// found is refused.
pub fn first_found(dir: &Path) -> Result<Option<PathBuf>, String> {
    match search(dir) {
        Found::File(p) => Ok(Some(p)),
        Found::None => Ok(None),
        Found::Refused(r) => Err(r),
    }
}

/// What reading a submission gave: its bytes (at most limit + 1) and the
/// file's size, or the refusal.
pub struct Source {
    pub bytes: Vec<u8>,
    pub size: u64,
}

/// Reads the file to mark without following a link (unless `follow`: a
/// path the user typed), without blocking on a FIFO or device
/// (`O_NONBLOCK`, and only a regular file is read) and never more than
/// `limit` + 1 bytes. `Err` is a refusal's reason.
pub fn read_submission(path: &Path, limit: usize, follow: bool) -> Result<Source, String> {
    use std::io::Read;
    use std::os::unix::fs::OpenOptionsExt;
    let nofollow = if follow { 0 } else { libc::O_NOFOLLOW };
    let f = std::fs::OpenOptions::new()
        .read(true)
        .custom_flags(nofollow | libc::O_NONBLOCK | libc::O_NOCTTY)
        .open(path)
        .map_err(|e| match e.raw_os_error() {
            Some(libc::ELOOP) => why::SYMLINK.to_string(),
            _ => format!("{}: {e}", why::UNREADABLE),
        })?;
    let meta = f.metadata().map_err(|e| format!("{}: {}", why::UNREADABLE, e.kind()))?;
    if !meta.is_file() {
        return Err(format!("{}: not a regular file", why::SPECIAL));
    }
    let mut bytes = Vec::new();
    f.take(limit as u64 + 1).read_to_end(&mut bytes).map_err(|e| format!("{}: {}", why::UNREADABLE, e.kind()))?;
    Ok(Source { size: meta.len().max(bytes.len() as u64), bytes })
}

/// The text to run, or why it scores 0: the lab's checks on the bytes read
/// (a file over the limit says its size, though only limit + 1 bytes were read).
pub fn checked(src: &Source) -> Result<&str, siftlab_mark::Rejection> {
    if src.bytes.len() > siftlab_mark::MAX_SOURCE_BYTES {
        return Err(siftlab_mark::Rejection::TooLarge { bytes: usize::try_from(src.size).unwrap_or(usize::MAX) });
    }
    siftlab_mark::check_source(&src.bytes)
}

/// The file `siftlab mark FILE|FOLDER` marks: FILE itself, or the folder's
/// first vision_tasks.py (`None`: there is none); a link or special file
/// found in the folder is an error naming it.
pub fn single(arg: &Path) -> siftlab_core::error::Result<Option<PathBuf>> {
    if !arg.is_dir() {
        return Ok(Some(arg.to_path_buf()));
    }
    first_found(arg).map_err(|why| {
        siftlab_core::error::Error::InvalidArgument(format!(
            "{}: refused ({why}): only a regular file inside the folder is marked",
            shown(arg)
        ))
    })
}

/// [`read_submission`] for `siftlab mark FILE|FOLDER`: a FILE typed by the
/// user may be a link; a file found in a FOLDER may not.
pub fn read_single(arg: &Path, file: &Path) -> siftlab_core::error::Result<Source> {
    read_submission(file, siftlab_mark::MAX_SOURCE_BYTES, !arg.is_dir())
        .map_err(|why| siftlab_core::error::Error::InvalidArgument(format!("cannot read {}: {why}", shown(file))))
}
