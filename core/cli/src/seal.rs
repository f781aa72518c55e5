//! What `--resume` trusts (docs/marking.md, "A whole class"): a student's
//! report.json is kept only if it carries a seal, an HMAC-SHA256 over the
//! student's id and the report's bytes, keyed by a secret that siftlab made
//! in `--out` (0600, its own user's) and that no submission can reach,
//! since `--out` and the submissions are kept apart.

use crate::submissions::{read_submission, shown};
use sha2::{Digest, Sha256};
use siftlab_core::error::{Error, Result};
use std::io::{Read, Write};
use std::path::{Component, Path, PathBuf};

/// The key's file in `--out`.
pub const KEY_FILE: &str = ".siftlab-key";
/// A student's seal, beside its report.json.
pub const SEAL_FILE: &str = "report.seal";
/// The largest report.json `--resume` reads (one of n = 25 is tens of KB).
const REPORT_LIMIT: usize = 64 << 20;

/// The key that seals this `--out`'s records.
pub struct Seal {
    key: [u8; 32],
}

impl Seal {
    /// The key of `out`, made (32 bytes from the kernel's random source,
    /// mode 0600, linked into place whole) if there is none yet. A key that
    /// is a link, another user's, readable by others or of the wrong size is
    /// an error: records sealed with it could be anyone's.
    pub fn open(out: &Path) -> Result<Seal> {
        let path = out.join(KEY_FILE);
        let bad = |why: String| {
            Error::InvalidArgument(format!(
                "{}: {why}; siftlab makes this file itself (0600) to seal its records: remove it, or use a fresh --out",
                path.display()
            ))
        };
        if std::fs::symlink_metadata(&path).is_err() {
            let mut key = [0u8; 32];
            std::fs::File::open("/dev/urandom")
                .and_then(|mut r| r.read_exact(&mut key))
                .map_err(|e| bad(format!("no random key: {e}")))?;
            let tmp = out.join(format!(".siftlab-key.tmp-{}", std::process::id()));
            let made = write_new(&tmp, &key).and_then(|_| std::fs::hard_link(&tmp, &path));
            let _ = std::fs::remove_file(&tmp);
            // Another run made it first: use theirs, checked as below.
            if let Err(e) = made {
                if e.kind() != std::io::ErrorKind::AlreadyExists {
                    return Err(bad(format!("cannot make it: {e}")));
                }
            }
        }
        use std::os::unix::fs::MetadataExt;
        let meta = std::fs::symlink_metadata(&path).map_err(|e| bad(e.to_string()))?;
        // SAFETY: geteuid has no preconditions and cannot fail.
        let me = unsafe { libc::geteuid() };
        if !meta.file_type().is_file() {
            return Err(bad("not a regular file".into()));
        }
        if meta.uid() != me || meta.mode() & 0o077 != 0 {
            return Err(bad(format!(
                "owned by uid {} with mode {:o}, not yours with 0600",
                meta.uid(),
                meta.mode() & 0o777
            )));
        }
        let src = read_submission(&path, 32, false).map_err(bad)?;
        let key: [u8; 32] = src.bytes.try_into().map_err(|_| bad("not 32 bytes".into()))?;
        Ok(Seal { key })
    }

    /// The seal of student `id`'s report: hex HMAC-SHA256, ending in a newline.
    pub fn tag(&self, id: &str, report: &[u8]) -> String {
        let mut msg = format!("siftlab report v1\0{id}\0").into_bytes();
        msg.extend_from_slice(report);
        let mac = hmac_sha256(&self.key, &msg);
        format!("{}\n", mac.iter().map(|b| format!("{b:02x}")).collect::<String>())
    }

    /// Student `id`'s report.json in `dir`, if its seal is this key's.
    pub fn verified(&self, id: &str, dir: &Path) -> Option<Vec<u8>> {
        let report = read_submission(&dir.join("report.json"), REPORT_LIMIT, false).ok()?.bytes;
        let seal = read_submission(&dir.join(SEAL_FILE), 65, false).ok()?.bytes;
        let want = self.tag(id, &report);
        // Compared in time independent of where they differ.
        let same = seal.len() == want.len() && seal.iter().zip(want.as_bytes()).fold(0u8, |d, (a, b)| d | (a ^ b)) == 0;
        (report.len() <= REPORT_LIMIT && same).then_some(report)
    }
}

fn write_new(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    use std::os::unix::fs::OpenOptionsExt;
    let mut f = std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .mode(0o600)
        .custom_flags(libc::O_NOFOLLOW)
        .open(path)?;
    f.write_all(bytes)?;
    f.sync_all()
}

/// HMAC-SHA256 (RFC 2104) of `msg` under a key of at most 64 bytes.
fn hmac_sha256(key: &[u8; 32], msg: &[u8]) -> [u8; 32] {
    let mut block = [0u8; 64];
    block[..32].copy_from_slice(key);
    let pad = |x: u8| block.map(|b| b ^ x);
    let inner = Sha256::new().chain_update(pad(0x36)).chain_update(msg).finalize();
    Sha256::new().chain_update(pad(0x5c)).chain_update(inner).finalize().into()
}

/// `--out` and the submissions share no folder: no student's file can be
/// taken for an output (a planted report.json, a key) nor an output be
/// found as a submission.
pub fn check_apart(out: &Path, submissions: &[PathBuf]) -> Result<()> {
    let o = resolved(out)?;
    for s in submissions {
        let Ok(real) = std::fs::canonicalize(s) else { continue };
        let clash = if o.starts_with(&real) {
            "--out is inside the submission"
        } else if real.starts_with(&o) {
            "the submission is inside --out"
        } else {
            continue;
        };
        return Err(Error::InvalidArgument(format!(
            "{clash} ({} and {}): a student's files could pass for siftlab's outputs; \
             choose an --out folder outside every submission",
            shown(out),
            shown(s)
        )));
    }
    Ok(())
}

/// `p` made absolute (`..` taken lexically) with its existing part's links resolved.
fn resolved(p: &Path) -> Result<PathBuf> {
    let abs = std::path::absolute(p).map_err(|e| Error::InvalidArgument(format!("--out {}: {e}", shown(p))))?;
    let mut lexical = PathBuf::new();
    for c in abs.components() {
        match c {
            Component::ParentDir => {
                lexical.pop();
            }
            Component::CurDir => {}
            c => lexical.push(c),
        }
    }
    let mut rest = Vec::new();
    let mut base = lexical.as_path();
    let mut out = loop {
        if let Ok(r) = std::fs::canonicalize(base) {
            break r;
        }
        match (base.parent(), base.file_name()) {
            (Some(parent), Some(name)) => {
                rest.push(name.to_os_string());
                base = parent;
            }
            _ => break base.to_path_buf(),
        }
    };
    out.extend(rest.iter().rev());
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hmac_matches_rfc_4231() {
        // RFC 4231 test case 2's message under a 32-byte key checked with
        // Python's hmac module: hmac.new(b"Jefe" + bytes(28), b"what do ya want for nothing?", "sha256").
        let mut key = [0u8; 32];
        key[..4].copy_from_slice(b"Jefe");
        let mac = hmac_sha256(&key, b"what do ya want for nothing?");
        let hex: String = mac.iter().map(|b| format!("{b:02x}")).collect();
        // Zero-padding a short key is HMAC's own rule, so this is also RFC 4231's value.
        assert_eq!(hex, "5bdcc146bf60754e6a042426089575c75a003f089d2739839dec58b964ec3843");
    }

    #[test]
    fn out_and_submissions_apart() {
        let root =
            std::env::temp_dir().join(format!("siftlab-seal-{}-{:?}", std::process::id(), std::thread::current().id()));
        let class = root.join("class");
        std::fs::create_dir_all(class.join("bob")).unwrap();
        assert!(check_apart(&root.join("out"), std::slice::from_ref(&class)).is_ok());
        let e = check_apart(&class.join("bob/new/out"), std::slice::from_ref(&class)).unwrap_err();
        assert!(e.to_string().contains("--out is inside the submission"), "{e}");
        let e = check_apart(&root, std::slice::from_ref(&class)).unwrap_err();
        assert!(e.to_string().contains("inside --out"), "{e}");
        let e = check_apart(&class.join("x/../bob/out"), &[class.join("bob")]).unwrap_err();
        assert!(e.to_string().contains("--out is inside"), "{e}");
        let _ = std::fs::remove_dir_all(&root);
    }
}
