//! The pipes of the native harness transport (`mark.rs`): the reader that
//! hands siftlab the harness's lines, bounded in length and in number
//! waiting, and the marking's temporary folder.

use siftlab_core::error::{Error, Result};
use siftlab_mark::MAX_LINE_BYTES;
use std::io::Read;
use std::path::PathBuf;
use std::sync::mpsc::SyncSender;

/// One line read from the harness, or why reading stopped.
pub(crate) enum FromHarness {
    Line(String),
    /// A line over MAX_LINE_BYTES, dropped unread.
    TooLong,
}

/// Lines from the harness waiting for siftlab: one. The reader then waits
/// (and the harness's writes with it): the student's output can fill the
/// pipe, never siftlab's memory (back-pressure).
pub(crate) const LINES_QUEUED: usize = 1;

/// Lines of at most MAX_LINE_BYTES, handed over one at a time (the send
/// waits while one is queued). The pipe is read in chunks: a longer line is
/// never held, its bytes are dropped as they come, up to its newline.
pub(crate) fn read_lines(mut stdout: std::process::ChildStdout, tx: SyncSender<FromHarness>) {
    let mut buf = vec![0u8; 1 << 16];
    let mut line: Vec<u8> = Vec::new();
    let mut too_long = false;
    loop {
        let k = match stdout.read(&mut buf) {
            Ok(0) => return,
            Ok(k) => k,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            Err(_) => return,
        };
        let mut rest = &buf[..k];
        loop {
            let end = rest.iter().position(|&b| b == b'\n');
            let chunk = &rest[..end.unwrap_or(rest.len())];
            if !too_long {
                if line.len() + chunk.len() > MAX_LINE_BYTES {
                    too_long = true;
                    line = Vec::new();
                } else {
                    line.extend_from_slice(chunk);
                }
            }
            let Some(end) = end else { break };
            rest = &rest[end + 1..];
            let item = if std::mem::take(&mut too_long) {
                FromHarness::TooLong
            } else {
                let bytes = std::mem::take(&mut line);
                let text =
                    String::from_utf8(bytes).unwrap_or_else(|e| String::from_utf8_lossy(e.as_bytes()).into_owned());
                FromHarness::Line(if text.ends_with('\r') { text.trim_end_matches('\r').to_string() } else { text })
            };
            if tx.send(item).is_err() {
                return;
            }
        }
    }
}

/// A folder under the system's temporary directory, removed when dropped.
pub(crate) struct TempDir(pub(crate) PathBuf);

impl TempDir {
    pub(crate) fn new() -> Result<TempDir> {
        let nanos = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0, |d| d.subsec_nanos());
        let dir = std::env::temp_dir().join(format!("siftlab-mark-{}-{nanos}", std::process::id()));
        std::fs::create_dir_all(&dir)
            .map_err(|e| Error::InvalidArgument(format!("cannot create {}: {e}", dir.display())))?;
        // Readable by the sandbox's marking uid (read-only inside it).
        use std::os::unix::fs::PermissionsExt;
        let _ = std::fs::set_permissions(&dir, std::fs::Permissions::from_mode(0o755));
        Ok(TempDir(dir))
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}
