//! Who is who in a class folder (docs/marking.md, "A whole class"): the
//! students SUBMISSIONS name, and the file of each that is marked, found as
//! the lab's marker finds it.

use siftlab_mark::escaped;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// One student of the class: an id and the file that is marked.
#[derive(Clone, Debug)]
pub struct Student {
    pub id: String,
    /// `None`: a folder without a vision_tasks.py (scores 0, "none found").
    pub file: Option<PathBuf>,
}

/// The students SUBMISSIONS name, sorted by id (bytes), and the names refused with why.
pub fn discover(args: &[PathBuf]) -> (Vec<Student>, Vec<(String, String)>) {
    let mut found: Vec<(Student, PathBuf)> = Vec::new();
    let mut refused: Vec<(String, String)> = Vec::new();
    for arg in args {
        let name = |p: &Path| p.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        if arg.is_file() {
            let id = if name(arg) == "vision_tasks.py" {
                arg.canonicalize().ok().and_then(|p| p.parent().map(name)).unwrap_or_default()
            } else {
                arg.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default()
            };
            found.push((Student { id, file: Some(arg.clone()) }, arg.clone()));
        } else if arg.join("vision_tasks.py").is_file() {
            let id = arg.canonicalize().map(|p| name(&p)).unwrap_or_else(|_| name(arg));
            found.push((Student { id, file: Some(arg.join("vision_tasks.py")) }, arg.clone()));
        } else if let Ok(rd) = std::fs::read_dir(arg) {
            let mut entries: Vec<PathBuf> = rd.flatten().map(|e| e.path()).collect();
            entries.sort_by(|a, b| a.as_os_str().as_encoded_bytes().cmp(b.as_os_str().as_encoded_bytes()));
            for p in entries {
                let n = name(&p);
                if ignored(&n) {
                    continue;
                }
                if p.is_dir() {
                    found.push((Student { id: n, file: first_found(&p) }, p.clone()));
                } else if let Some(id) = n.strip_suffix(".py") {
                    found.push((Student { id: id.to_string(), file: Some(p.clone()) }, p.clone()));
                } else {
                    refused.push((n, "neither a folder nor a .py file".into()));
                }
            }
        } else {
            refused.push((arg.display().to_string(), "no such file or folder".into()));
        }
    }
    let mut by_id: BTreeMap<String, Vec<(Student, PathBuf)>> = BTreeMap::new();
    for (s, from) in found {
        by_id.entry(s.id.clone()).or_default().push((s, from));
    }
    let mut students = Vec::new();
    for (id, mut list) in by_id {
        if let Some(why) = odd_id(&id) {
            refused.push((escaped(&id, 80), why));
        } else if list.len() > 1 {
            let places: Vec<String> = list.iter().map(|(_, p)| p.display().to_string()).collect();
            refused.push((id, format!("duplicate student id: {}", places.join(" and "))));
        } else if let Some((s, _)) = list.pop() {
            students.push(s);
        }
    }
    (students, refused)
}

/// Names the lab's marker passes over: dot-entries and macOS's archive folders.
fn ignored(name: &str) -> bool {
    name.starts_with('.') || name == "__MACOSX"
}

/// Why `id` cannot name a student's folder and row, if it cannot.
fn odd_id(id: &str) -> Option<String> {
    let ok_char = |c: char| c.is_ascii_alphanumeric() || "._-@+".contains(c);
    if id.is_empty()
        || id.len() > 128
        || !id.chars().all(ok_char)
        || !id.starts_with(|c: char| c.is_ascii_alphanumeric())
    {
        return Some("odd characters in the student id (letters, digits and . _ - @ + only, a letter or digit first, at most 128)".into());
    }
    None
}

/// The first vision_tasks.py under `dir`, as the lab's marker takes it:
/// shallowest first, then by byte-sorted path; dot-entries and __MACOSX skipped.
pub fn first_found(dir: &Path) -> Option<PathBuf> {
    let mut level = vec![dir.to_path_buf()];
    for _ in 0..16 {
        let mut files = Vec::new();
        let mut next = Vec::new();
        for d in &level {
            let Ok(rd) = std::fs::read_dir(d) else { continue };
            for e in rd.flatten() {
                let n = e.file_name().to_string_lossy().into_owned();
                if ignored(&n) {
                    continue;
                }
                let p = e.path();
                if p.is_dir() {
                    next.push(p);
                } else if n == "vision_tasks.py" {
                    files.push(p);
                }
            }
        }
        let bytes = |p: &PathBuf| p.as_os_str().as_encoded_bytes().to_vec();
        if let Some(f) = files.into_iter().min_by_key(bytes) {
            return Some(f);
        }
        if next.is_empty() {
            return None;
        }
        level = next;
    }
    None
}
