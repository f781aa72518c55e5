//! `siftlab autograder {gradescope,prairielearn} --out DIR [--seed S] [-n N]
//! [--binary PATH]`: writes a course platform's autograder for the lab
//! (docs/marking.md, "Gradescope", "PrairieLearn"). Both hold the siftlab
//! binary and the frames the marker draws its cases from (with their
//! licence). Gradescope: `setup.sh` (python3 and numpy from the image's
//! packages), `run_autograder` (marks /autograder/submission in the container
//! sandbox tier, writes /autograder/results/results.json) and all of it as
//! `autograder.zip`, ready to upload. PrairieLearn: the grader image's
//! `Dockerfile`, its entrypoint `run_grader` (marks /grade/student, writes
//! /grade/results/results.json), and the question's `info.json` options and
//! `question.html`.

use crate::args::{AutograderArgs, Cli};
use siftlab_core::error::{Error, Result};
use std::path::{Path, PathBuf};

const SETUP: &str = r#"#!/usr/bin/env bash
# Gradescope runs this once, as root, when it builds the autograder's image (Ubuntu 22.04):
# the interpreter the students' files run in, and numpy, from the image's own packages.
set -euo pipefail
apt-get update
DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends python3 python3-numpy
"#;

/// `run_autograder`, with the run's seed and count filled in.
fn run_script(seed: u64, n: u32, sequence: &str) -> String {
    format!(
        r#"#!/usr/bin/env bash
# Gradescope runs this as root for each submission. siftlab marks /autograder/submission
# with seed {seed}, {n} calls per task: the student's code runs as a uid of its own (the
# container tier: no new privileges, seccomp, no sockets; every process of that uid killed
# before the mark is written), so it can neither write results.json nor touch this folder.
# No results.json (siftlab failed) shows on Gradescope as a failed run, never as a mark.
set -u
SRC=/autograder/source
RES=/autograder/results
mkdir -p "$RES"
chown root:root "$RES" && chmod 0755 "$RES"
rm -f "$RES/results.json"
export SIFTLAB_PYTHON="${{SIFTLAB_PYTHON:-/usr/bin/python3}}"
exec "$SRC/siftlab" -d "$SRC/MyKITTI" -s {sequence} mark /autograder/submission -n {n} --seed {seed} \
    --gradescope "$RES/results.json"
"#
    )
}

/// PrairieLearn's grader image: Ubuntu 22.04 (the same C library as
/// Gradescope's), python3 and numpy from its packages, siftlab and the frames.
const DOCKERFILE: &str = r#"# siftlab's PrairieLearn grader image (siftlab autograder prairielearn).
#   docker build -t YOUR_DOCKERHUB_USER/siftlab-grader . && docker push YOUR_DOCKERHUB_USER/siftlab-grader
# then name that image in the question's info.json (info.json here).
FROM ubuntu:22.04
RUN apt-get update \
    && DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends python3 python3-numpy \
    && rm -rf /var/lib/apt/lists/*
COPY siftlab run_grader /siftlab/
COPY MyKITTI /siftlab/MyKITTI
"#;

const QUESTION: &str = r#"<pl-question-panel>
  <p>Upload your <code>vision_tasks.py</code>. It is marked as the lab's automarker marks it:
  each function on random valid calls, 10 s of CPU a call, 0.5 marks per task for no runtime
  error plus 4.5 &times; the share of exactly right values, 20 in all.</p>
</pl-question-panel>
<pl-file-upload file-names="vision_tasks.py"></pl-file-upload>
<pl-submission-panel>
  <pl-external-grader-results></pl-external-grader-results>
  <pl-file-preview></pl-file-preview>
</pl-submission-panel>
"#;

/// The grader's entrypoint, with the run's seed, count and sequence.
fn grader_script(seed: u64, n: u32, sequence: &str) -> String {
    format!(
        r#"#!/usr/bin/env bash
# PrairieLearn runs this as root in the grader image for each submission. siftlab marks
# /grade/student with seed {seed}, {n} calls per task: the student's code runs as a uid of its
# own (the container tier: no new privileges, seccomp, no sockets; every process of that uid
# killed before the mark is written), so it can neither write results.json nor touch /siftlab.
# No results.json (siftlab failed) shows on PrairieLearn as a grading failure, never a mark.
set -u
RES=/grade/results
mkdir -p "$RES"
chown root:root "$RES" && chmod 0755 "$RES"
rm -f "$RES/results.json"
export SIFTLAB_PYTHON="${{SIFTLAB_PYTHON:-/usr/bin/python3}}"
exec /siftlab/siftlab -d /siftlab/MyKITTI -s {sequence} mark /grade/student -n {n} --seed {seed} \
    --prairielearn "$RES/results.json"
"#
    )
}

/// The question's info.json options: an external grader with a time limit
/// that holds the slowest honest marking at half a CPU.
fn info_json(n: u32) -> String {
    let timeout = 60 + 24 * n;
    format!(
        r#"{{
  "gradingMethod": "External",
  "externalGradingOptions": {{
    "enabled": true,
    "image": "YOUR_DOCKERHUB_USER/siftlab-grader",
    "entrypoint": "/siftlab/run_grader",
    "timeout": {timeout}
  }}
}}
"#
    )
}

pub fn run(cli: &Cli, a: &AutograderArgs) -> Result<()> {
    let err = |what: String| Error::InvalidArgument(what);
    let binary = match &a.binary {
        Some(b) => b.clone(),
        None => std::env::current_exe().map_err(|e| err(format!("cannot find siftlab's own binary: {e}")))?,
    };
    let elf = std::fs::read(&binary).map_err(|e| err(format!("cannot read {}: {e}", binary.display())))?;
    let linked =
        linking(&elf).ok_or_else(|| err(format!("{} is not a Linux x86-64 or arm64 program", binary.display())))?;
    let dataset = crate::common::open_dataset(cli)?;
    let frames = crate::mark::frame_ids(&dataset)?;
    let root = dataset.root().to_path_buf();
    let out = &a.out;
    if out.exists() && std::fs::read_dir(out).map_or(true, |mut d| d.next().is_some()) {
        return Err(err(format!("{} exists and is not empty: give a new folder", out.display())));
    }
    let mut files: Vec<(PathBuf, u32)> = Vec::new();
    let write = |rel: &str, bytes: &[u8], mode: u32, files: &mut Vec<(PathBuf, u32)>| -> Result<()> {
        let path = out.join(rel);
        if let Some(parent) = path.parent() {
            std::fs::create_dir_all(parent).map_err(|e| err(format!("cannot create {}: {e}", parent.display())))?;
        }
        std::fs::write(&path, bytes).map_err(|e| err(format!("cannot write {}: {e}", path.display())))?;
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(&path, std::fs::Permissions::from_mode(mode))
            .map_err(|e| err(format!("cannot set {}'s mode: {e}", path.display())))?;
        files.push((PathBuf::from(rel), mode));
        Ok(())
    };
    let gradescope = a.platform == "gradescope";
    if gradescope {
        write("setup.sh", SETUP.as_bytes(), 0o755, &mut files)?;
        write("run_autograder", run_script(a.seed, a.n, &cli.sequence).as_bytes(), 0o755, &mut files)?;
    } else {
        write("Dockerfile", DOCKERFILE.as_bytes(), 0o644, &mut files)?;
        write("run_grader", grader_script(a.seed, a.n, &cli.sequence).as_bytes(), 0o755, &mut files)?;
        write("info.json", info_json(a.n).as_bytes(), 0o644, &mut files)?;
        write("question.html", QUESTION.as_bytes(), 0o644, &mut files)?;
    }
    write("siftlab", &elf, 0o755, &mut files)?;
    // The frames the cases are drawn from (frame_ids: 0 to the last), their poses, the licence.
    let copy = |from: &Path, rel: String, files: &mut Vec<(PathBuf, u32)>| -> Result<()> {
        let bytes = std::fs::read(from).map_err(|e| err(format!("cannot read {}: {e}", from.display())))?;
        write(&rel, &bytes, 0o644, files)
    };
    // The dataset's own layout (the lab's or KITTI's), so `-s` picks the same sequence there.
    let seq = dataset.sequence().clone();
    for id in std::iter::once(0).chain(frames.iter().copied()) {
        let id = id as usize;
        copy(&dataset.frame_path(id), format!("MyKITTI/{}", seq.frame_path(id)), &mut files)?;
    }
    for extra in ["README.md", "LICENSE", "LICENSE.txt", "ATTRIBUTION.txt"] {
        if root.join(extra).is_file() {
            copy(&root.join(extra), format!("MyKITTI/{extra}"), &mut files)?;
        }
    }
    for rel in [seq.poses_file(), seq.calib_file()] {
        if root.join(&rel).is_file() {
            copy(&root.join(&rel), format!("MyKITTI/{rel}"), &mut files)?;
        }
    }
    let last = frames.last().copied().unwrap_or(0);
    if gradescope {
        crate::zip::write_stored(&out.join("autograder.zip"), out, &files)?;
        println!(
            "{}: Gradescope's autograder (seed {}, {} calls per task, frames 0 to {last}): upload autograder.zip \
             (Configure Autograder → Zip file upload, Ubuntu 22.04 base image)",
            out.display(),
            a.seed,
            a.n
        );
    } else {
        println!(
            "{}: PrairieLearn's grader (seed {}, {} calls per task, frames 0 to {last}): build and push the image \
             from its Dockerfile, put info.json's options and question.html in the question",
            out.display(),
            a.seed,
            a.n
        );
    }
    if linked == Linking::Dynamic {
        eprintln!(
            "siftlab: warning: {} is linked against this machine's C library, which the platform's Ubuntu 22.04 \
             may not have: build a static siftlab (RUSTFLAGS=\"-C target-feature=+crt-static\" cargo build \
             --release -p siftlab-cli --target x86_64-unknown-linux-gnu) and pass it with --binary",
            binary.display()
        );
    }
    Ok(())
}

#[derive(Debug, PartialEq, Eq)]
pub enum Linking {
    /// No program interpreter: runs on any Linux of its architecture.
    Static,
    /// Needs the dynamic loader and the C library it was linked against.
    Dynamic,
}

/// Whether an ELF64 program (x86-64 or aarch64, little-endian) names a
/// program interpreter (PT_INTERP), i.e. needs a dynamic loader.
pub fn linking(elf: &[u8]) -> Option<Linking> {
    if elf.len() < 64 || &elf[..4] != b"\x7fELF" || elf[4] != 2 || elf[5] != 1 {
        return None;
    }
    let u16_at = |o: usize| elf.get(o..o + 2).map(|b| u16::from_le_bytes([b[0], b[1]]));
    let u32_at = |o: usize| elf.get(o..o + 4).map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]));
    let u64_at = |o: usize| elf.get(o..o + 8).map(|b| u64::from_le_bytes(b.try_into().unwrap_or([0; 8])));
    // e_machine: 62 x86-64, 183 aarch64.
    if !matches!(u16_at(18)?, 62 | 183) {
        return None;
    }
    let (phoff, phentsize, phnum) = (u64_at(32)? as usize, u16_at(54)? as usize, u16_at(56)? as usize);
    for i in 0..phnum {
        // p_type 3: PT_INTERP.
        if u32_at(phoff.checked_add(i.checked_mul(phentsize)?)?)? == 3 {
            return Some(Linking::Dynamic);
        }
    }
    Some(Linking::Static)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn this_test_binary_is_dynamic_and_a_text_file_is_no_program() {
        let me = std::fs::read(std::env::current_exe().unwrap()).unwrap();
        // Test binaries on a glibc target are dynamically linked.
        assert_eq!(linking(&me), Some(if cfg!(target_env = "musl") { Linking::Static } else { Linking::Dynamic }));
        assert_eq!(linking(b"#!/bin/sh\necho hi\n"), None);
        // The same header with its PT_INTERP entry's type changed to PT_NOTE (4) is static.
        let mut edited = me.clone();
        let phoff = u64::from_le_bytes(me[32..40].try_into().unwrap()) as usize;
        let (size, num) =
            (u16::from_le_bytes([me[54], me[55]]) as usize, u16::from_le_bytes([me[56], me[57]]) as usize);
        for i in 0..num {
            let o = phoff + i * size;
            if u32::from_le_bytes(me[o..o + 4].try_into().unwrap()) == 3 {
                edited[o..o + 4].copy_from_slice(&4u32.to_le_bytes());
            }
        }
        assert_eq!(linking(&edited), Some(Linking::Static));
    }

    #[test]
    fn the_run_scripts_carry_the_seed_count_and_sequence() {
        let s = run_script(7, 25, "03");
        assert!(s.contains("-s 03 mark /autograder/submission -n 25 --seed 7 \\"), "{s}");
        assert!(s.contains("--gradescope \"$RES/results.json\""));
        let s = grader_script(7, 25, "00");
        assert!(s.contains("-s 00 mark /grade/student -n 25 --seed 7 \\"), "{s}");
        assert!(s.contains("--prairielearn \"$RES/results.json\""));
        assert!(info_json(25).contains("\"timeout\": 660"), "{}", info_json(25));
    }
}
