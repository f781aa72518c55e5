//! A zip archive of stored (uncompressed) entries, as Gradescope's autograder
//! upload takes it: the PNG frames and the binary barely compress, and a
//! stored entry is a header, the bytes and a CRC-32 (PKWARE's APPNOTE 6.3.10,
//! sections 4.3.7, 4.3.12 and 4.3.16). Unix modes ride in the external
//! attributes, so `run_autograder` and `siftlab` unpack executable.

use siftlab_core::error::{Error, Result};
use std::io::Write;
use std::path::{Path, PathBuf};

/// CRC-32 (IEEE 802.3, reflected, polynomial 0xEDB88320), as zip uses it.
pub fn crc32(bytes: &[u8]) -> u32 {
    static TABLE: std::sync::OnceLock<[u32; 256]> = std::sync::OnceLock::new();
    let table = TABLE.get_or_init(|| {
        let mut t = [0u32; 256];
        for (i, e) in t.iter_mut().enumerate() {
            let mut c = i as u32;
            for _ in 0..8 {
                c = if c & 1 != 0 { 0xEDB8_8320 ^ (c >> 1) } else { c >> 1 };
            }
            *e = c;
        }
        t
    });
    !bytes.iter().fold(!0u32, |c, &b| table[((c ^ u32::from(b)) & 0xff) as usize] ^ (c >> 8))
}

/// Writes `zip` with `files` (paths relative to `dir`, and their modes).
pub fn write_stored(zip: &Path, dir: &Path, files: &[(PathBuf, u32)]) -> Result<()> {
    let err = |e: std::io::Error| Error::InvalidArgument(format!("cannot write {}: {e}", zip.display()));
    let mut out = std::io::BufWriter::new(std::fs::File::create(zip).map_err(err)?);
    let mut central = Vec::new();
    let mut offset: u64 = 0;
    for (rel, mode) in files {
        let bytes = std::fs::read(dir.join(rel)).map_err(err)?;
        let name = rel.to_string_lossy().replace('\\', "/");
        let (size, at) = (u32::try_from(bytes.len()), u32::try_from(offset));
        let (Ok(size), Ok(at)) = (size, at) else {
            return Err(Error::InvalidArgument(format!("{}: over 4 GB, too large for a plain zip", zip.display())));
        };
        let crc = crc32(&bytes);
        // Version 2.0, no flags, stored, a fixed time (1 Jan 2026: the archive does not depend on when it was made).
        let common = |h: &mut Vec<u8>| {
            h.extend_from_slice(&20u16.to_le_bytes());
            h.extend_from_slice(&0u16.to_le_bytes());
            h.extend_from_slice(&0u16.to_le_bytes());
            h.extend_from_slice(&0u16.to_le_bytes());
            h.extend_from_slice(&((46u16 << 9) | (1 << 5) | 1).to_le_bytes());
            h.extend_from_slice(&crc.to_le_bytes());
            h.extend_from_slice(&size.to_le_bytes());
            h.extend_from_slice(&size.to_le_bytes());
            h.extend_from_slice(&(name.len() as u16).to_le_bytes());
            h.extend_from_slice(&0u16.to_le_bytes());
        };
        let mut local = b"PK\x03\x04".to_vec();
        common(&mut local);
        local.extend_from_slice(name.as_bytes());
        out.write_all(&local).and_then(|_| out.write_all(&bytes)).map_err(err)?;
        // Central entry: made by Unix (3) version 2.0, then the local fields.
        central.extend_from_slice(b"PK\x01\x02");
        central.extend_from_slice(&((3u16 << 8) | 20).to_le_bytes());
        common(&mut central);
        central.extend_from_slice(&0u16.to_le_bytes()); // comment length
        central.extend_from_slice(&0u16.to_le_bytes()); // disk
        central.extend_from_slice(&0u16.to_le_bytes()); // internal attributes
        central.extend_from_slice(&((0o100_000 | mode) << 16).to_le_bytes());
        central.extend_from_slice(&at.to_le_bytes());
        central.extend_from_slice(name.as_bytes());
        offset += (local.len() + bytes.len()) as u64;
    }
    let (Ok(count), Ok(cd_at)) = (u16::try_from(files.len()), u32::try_from(offset)) else {
        return Err(Error::InvalidArgument(format!("{}: too many files or bytes for a plain zip", zip.display())));
    };
    let mut end = b"PK\x05\x06".to_vec();
    end.extend_from_slice(&[0, 0, 0, 0]);
    end.extend_from_slice(&count.to_le_bytes());
    end.extend_from_slice(&count.to_le_bytes());
    end.extend_from_slice(&(central.len() as u32).to_le_bytes());
    end.extend_from_slice(&cd_at.to_le_bytes());
    end.extend_from_slice(&0u16.to_le_bytes());
    out.write_all(&central).and_then(|_| out.write_all(&end)).and_then(|_| out.flush()).map_err(err)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crc32_of_the_standard_check_string() {
        // The check value every CRC-32/ISO-HDLC implementation gives for "123456789".
        assert_eq!(crc32(b"123456789"), 0xCBF4_3926);
        assert_eq!(crc32(b""), 0);
    }

    #[test]
    fn python_reads_the_archive_back() {
        let dir = std::env::temp_dir().join(format!("siftlab-zip-{}", std::process::id()));
        std::fs::create_dir_all(dir.join("sub")).unwrap();
        std::fs::write(dir.join("run"), b"#!/bin/sh\necho hi\n").unwrap();
        std::fs::write(dir.join("sub/data.bin"), [0u8, 1, 2, 255]).unwrap();
        let zip = dir.join("a.zip");
        write_stored(&zip, &dir, &[(PathBuf::from("run"), 0o755), (PathBuf::from("sub/data.bin"), 0o644)]).unwrap();
        // Python's zipfile checks each entry's CRC and reads the modes back.
        let check = "import sys, zipfile\nz = zipfile.ZipFile(sys.argv[1])\nassert z.testzip() is None\n\
                     print(sorted((i.filename, oct(i.external_attr >> 16), z.read(i).hex()) for i in z.infolist()))";
        let out = std::process::Command::new("python3").args(["-c", check]).arg(&zip).output().unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        assert_eq!(
            String::from_utf8_lossy(&out.stdout).trim(),
            "[('run', '0o100755', '23212f62696e2f73680a6563686f2068690a'), ('sub/data.bin', '0o100644', '000102ff')]"
        );
    }
}
