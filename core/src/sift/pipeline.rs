//! The pipeline: `detectAndCompute` as one driver calling the stages in
//! OpenCV's order (docs/fidelity.md §SIFT-2 to §SIFT-11). No stage calls a
//! later one; the driver wires each stage's output into the next.

use super::image::Plane;
use super::keypoint::{Features, KeyPoint};
use super::observer::Observer;
use super::params::SiftParams;
use super::{descriptor, extrema, initial, order, orientation, pyramid};
use crate::image::GrayImage;
use crate::par;

/// `detect`: the keypoints only, in OpenCV's order.
pub fn detect(img: &GrayImage, p: &SiftParams) -> Vec<KeyPoint> {
    if img.width() == 0 || img.height() == 0 {
        return Vec::new();
    }
    find_keypoints(img, p, Pyramid::Drop, &()).0
}

/// `detectAndCompute(img, None)`: keypoints in OpenCV's order and one
/// descriptor row per keypoint.
pub fn detect_and_compute(img: &GrayImage, p: &SiftParams) -> Features {
    if img.width() == 0 || img.height() == 0 {
        return Features::default();
    }
    let (keypoints, gauss) = find_keypoints(img, p, Pyramid::Keep, &());
    let descriptors = descriptors(&gauss, &keypoints, p);
    Features { keypoints, descriptors }
}

/// Whether the caller needs the Gaussian pyramid after the keypoints are
/// found (the descriptors read it).
#[derive(Clone, Copy, PartialEq)]
pub(super) enum Pyramid {
    Keep,
    Drop,
}

/// Rows per scan job: bands, so the first octave spreads over all threads;
/// OpenCV splits its scan by rows the same way.
const BAND: usize = 32;

/// The keypoints in OpenCV's order, and the Gaussian pyramid (its levels
/// indexed `o * (layers + 3) + i`) if `keep` asks for it (else empty).
///
/// On one thread (an odometry detection worker) without the pyramid kept,
/// each octave is scanned as soon as it is blurred, and its planes go back
/// to the pool before the next octave's are taken, so a worker holds one
/// octave instead of the whole pyramid (docs/performance.md, Memory). Otherwise the
/// whole pyramid is built first and all octaves' scans share out over the
/// threads at once. Same keypoints either way: §SIFT-10 sorts them all.
///
/// `obs` sees each stage's output (the anatomy view's recorder); the plain
/// path passes `&()`, whose empty methods the optimiser removes.
pub(super) fn find_keypoints<O: Observer>(
    img: &GrayImage,
    p: &SiftParams,
    keep: Pyramid,
    obs: &O,
) -> (Vec<KeyPoint>, Vec<Plane>) {
    let stream = keep == Pyramid::Drop && par::threads() == 1;
    let base = initial::initial_image(img, p.sigma);
    let octaves = pyramid::octave_count(base.width, base.height);
    let sig = pyramid::level_sigmas(p.sigma, p.n_octave_layers);
    let per = p.n_octave_layers + 3;
    let mut gauss: Vec<Plane> = Vec::with_capacity(if stream { 0 } else { octaves * per });
    let mut kps = Vec::new();
    let mut first = base;
    for o in 0..octaves {
        let levels = pyramid::octave_levels(first, &sig);
        if stream {
            scan(&[(o, &levels)], p, obs, &mut kps);
        }
        // Taken before `levels` goes back to the pool at the end of the loop
        // body (streaming), so the next octave's planes reuse this one's
        // buffers.
        let next = (o + 1 < octaves).then(|| pyramid::next_octave_base(&levels, p.n_octave_layers));
        if !stream {
            gauss.extend(levels);
        }
        let Some(next) = next else { break };
        first = next;
    }
    if !stream {
        let all: Vec<(usize, &[Plane])> = gauss.chunks(per).enumerate().collect();
        scan(&all, p, obs, &mut kps);
    }
    (in_opencv_order(kps, p, obs), gauss)
}

/// The extremum scan of the given octaves (number, Gaussian levels) in row
/// bands shared over the threads (§SIFT-6, §SIFT-7), each refined extremum
/// handed to the orientation histogram (§SIFT-8), the keypoints appended to
/// `out` (in whatever order the threads finish, §SIFT-9).
fn scan<O: Observer>(octaves: &[(usize, &[Plane])], p: &SiftParams, obs: &O, out: &mut Vec<KeyPoint>) {
    let jobs: Vec<(usize, usize)> = octaves
        .iter()
        .enumerate()
        .flat_map(|(i, (_, levels))| (0..levels[0].height).step_by(BAND).map(move |r0| (i, r0)))
        .collect();
    par::collect_jobs(
        &jobs,
        |&(i, r0), out| {
            let (o, levels) = octaves[i];
            let mut orienter = orientation::Orienter::new(levels, p, out);
            extrema::scan_octave(levels, o, r0..r0 + BAND, p, obs, |refined| {
                obs.refined(&refined);
                orienter.push(refined)
            });
            orienter.finish();
        },
        out,
    );
}

/// §SIFT-10: duplicates removed from the sorted keypoints, the best `nfeatures`
/// kept, first-octave coordinates halved.
fn in_opencv_order<O: Observer>(mut kps: Vec<KeyPoint>, p: &SiftParams, obs: &O) -> Vec<KeyPoint> {
    obs.oriented(&kps);
    order::remove_duplicated_sorted(&mut kps);
    obs.deduplicated(&kps);
    if p.nfeatures > 0 {
        order::retain_best(&mut kps, p.nfeatures);
    }
    order::rescale_first_octave(&mut kps);
    kps
}

/// §SIFT-11: one descriptor row per keypoint, in the keypoints' order.
fn descriptors(gauss: &[Plane], keypoints: &[KeyPoint], p: &SiftParams) -> Vec<[u8; 128]> {
    // Visit the keypoints level by level, top to bottom, so neighbouring
    // windows share cached rows (in OpenCV's response order, each window is
    // a fresh set of cache and TLB misses); each row goes back to its slot.
    let mut visit: Vec<usize> = (0..keypoints.len()).collect();
    visit.sort_by(|&a, &b| {
        let (ka, kb) = (&keypoints[a], &keypoints[b]);
        (ka.octave & 0xffff).cmp(&(kb.octave & 0xffff)).then(ka.y.total_cmp(&kb.y))
    });
    let mut computed = vec![[0u8; 128]; keypoints.len()];
    par::for_each_chunk_dynamic(&mut computed, 16, |first, rows| {
        for (i, row) in rows.iter_mut().enumerate() {
            *row = descriptor::descriptor(gauss, &keypoints[visit[first + i]], p);
        }
    });
    let mut descriptors = vec![[0u8; 128]; keypoints.len()];
    for (&k, row) in visit.iter().zip(computed) {
        descriptors[k] = row;
    }
    descriptors
}
