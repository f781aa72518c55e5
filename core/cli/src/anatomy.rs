//! `siftlab anatomy IMAGE`: SIFT's funnel on one image (how many points each
//! stage keeps, why the refinement dropped the others) and, with `--out`,
//! the Gaussian and DoG pyramid as PNGs.

use siftlab_core::error::{Error, Result};
use siftlab_core::image::GrayImage;
use siftlab_core::sift::anatomy::{anatomy, level_to_gray, Anatomy};
use siftlab_core::sift::SiftParams;
use std::io::Write;
use std::path::Path;

/// Runs the anatomy of the image at `path`, prints it (JSON or text) and
/// writes the pyramid into `out` if given.
pub fn run(path: &Path, params: &SiftParams, json: bool, out: Option<&Path>) -> Result<()> {
    let bytes = std::fs::read(path).map_err(|e| Error::Dataset(format!("cannot read {}: {e}", path.display())))?;
    let img = GrayImage::decode(&bytes)?;
    let a = anatomy(&img, params);
    let text = if json { to_json(&a) } else { to_text(&a) };
    let mut so = std::io::stdout().lock();
    let _ = writeln!(so, "{text}");
    let _ = so.flush();
    if let Some(dir) = out {
        let n = write_pyramid(&a, dir)?;
        eprintln!("wrote {n} PNGs to {}", dir.display());
    }
    Ok(())
}

/// `{"octaves": N, "stages": [{"stage": NAME, "count": C}, …]}`: the refined
/// stage also carries its drops per reason, the kept one the response cut-off.
pub fn to_json(a: &Anatomy) -> String {
    let stages: Vec<String> = a
        .stages()
        .iter()
        .map(|s| {
            let extra = match s.name {
                "refined" => {
                    let d: Vec<String> = a.drops().iter().map(|(r, n)| format!("\"{}\": {n}", r.name())).collect();
                    format!(", \"dropped\": {{{}}}", d.join(", "))
                }
                "kept" => match a.response_cutoff() {
                    Some(c) => format!(", \"response_cutoff\": {c:?}"),
                    None => ", \"response_cutoff\": null".into(),
                },
                _ => String::new(),
            };
            format!("{{\"stage\": \"{}\", \"count\": {}{extra}}}", s.name, s.count)
        })
        .collect();
    format!("{{\"octaves\": {}, \"stages\": [{}]}}", a.octaves, stages.join(", "))
}

fn to_text(a: &Anatomy) -> String {
    let mut lines = vec![format!("{} octaves of {} Gaussian levels", a.octaves, a.levels_per_octave)];
    for s in a.stages() {
        lines.push(format!("{:>13}: {}", s.name, s.count));
        if s.name == "refined" {
            for (r, n) in a.drops() {
                lines.push(format!("{:>13}  dropped {n} ({})", "", r.name()));
            }
        }
    }
    if let Some(c) = a.response_cutoff() {
        lines.push(format!("response cut-off: {c:?}"));
    }
    lines.join("\n")
}

/// `gauss_oO_lI.png` and `dog_oO_lJ.png` for every level (octave 0 is the
/// doubled base); returns how many files were written.
fn write_pyramid(a: &Anatomy, dir: &Path) -> Result<usize> {
    std::fs::create_dir_all(dir).map_err(|e| Error::Dataset(format!("cannot create {}: {e}", dir.display())))?;
    let mut n = 0;
    for o in 0..a.octaves {
        for i in 0..a.levels_per_octave {
            let levels = [
                ("gauss", a.gaussian(o, i).map(|g| (level_to_gray(g, false), g.width, g.height))),
                ("dog", { a.dog(o, i).map(|d| (level_to_gray(&d, true), d.width, d.height)) }),
            ];
            for (kind, level) in levels {
                let Some((px, w, h)) = level else { continue };
                let img = image::GrayImage::from_raw(w as u32, h as u32, px)
                    .ok_or_else(|| Error::Decode("pyramid level size mismatch".into()))?;
                let path = dir.join(format!("{kind}_o{o}_l{i}.png"));
                img.save(&path).map_err(|e| Error::Dataset(format!("cannot write {}: {e}", path.display())))?;
                n += 1;
            }
        }
    }
    Ok(n)
}
