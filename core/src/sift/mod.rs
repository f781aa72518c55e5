//! SIFT exactly as OpenCV 4.8.0 computes it
//! (`cv2.SIFT_create(nfeatures=1500).detectAndCompute(gray, None)`), stage by
//! stage as `docs/fidelity.md` describes it:
//!
//! 1. [`initial`] — float, ×2 bilinear upsample, blur to σ = 1.6 (§SIFT-2)
//! 2. [`blur`] — the bit-exact Gaussian kernel and separable filter (§SIFT-3)
//! 3. [`pyramid`] — the Gaussian pyramid (§SIFT-4); DoG rows are taken in the scan (§SIFT-5)
//! 4. [`extrema`] — DoG rows, 26-neighbour scan and sub-pixel refinement (§SIFT-5 to §SIFT-7)
//! 5. [`orientation`] — 36-bin orientation histogram peaks (§SIFT-8)
//! 6. [`order`] — dedup, `retainBest` via libstdc++ introselect, rescale (§SIFT-10)
//! 7. [`descriptor`] — 4×4×8 histograms, clipped, scaled to 0..255 (§SIFT-11)
//!
//! [`num`] holds the exact math kernels (§SIFT-12) and the FMA used throughout.

pub mod blur;
pub mod descriptor;
pub mod extrema;
pub mod image;
pub mod initial;
pub mod num;
pub mod order;
pub mod orientation;
pub mod par;
pub mod pyramid;

use crate::image::GrayImage;
use image::Plane;

/// A keypoint with OpenCV's fields (`class_id` is always −1 and omitted).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KeyPoint {
    pub x: f32,
    pub y: f32,
    pub size: f32,
    pub angle: f32,
    pub response: f32,
    /// Packed as OpenCV packs it: `(xi_code << 16) | (layer << 8) | (octave & 255)`.
    pub octave: i32,
}

impl KeyPoint {
    /// The reported octave (−1 for the doubled base), as `unpackOctave` reads it.
    pub fn octave_index(&self) -> i32 {
        let o = self.octave & 255;
        if o >= 128 {
            o - 256
        } else {
            o
        }
    }

    /// The DoG layer (1..=3) within the octave.
    pub fn layer(&self) -> i32 {
        (self.octave >> 8) & 255
    }
}

/// The keypoints of an image and their descriptors, in OpenCV's order.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Features {
    pub keypoints: Vec<KeyPoint>,
    /// One row per keypoint; OpenCV stores these integers 0..255 as float32.
    pub descriptors: Vec<[u8; 128]>,
}

/// `cv2.SIFT_create` parameters. `opencv_lanes` is the SIMD width OpenCV's
/// dispatched SIFT kernels ran with on the reference machine (8 on AVX2, 16
/// on AVX-512 CPUs, docs/fidelity.md §SIFT-13); it changes angles and descriptors at the ulp
/// level only.
#[derive(Clone, Debug, PartialEq)]
pub struct SiftParams {
    pub nfeatures: usize,
    pub n_octave_layers: usize,
    pub contrast_threshold: f64,
    pub edge_threshold: f64,
    pub sigma: f64,
    pub opencv_lanes: usize,
}

impl Default for SiftParams {
    /// The lab's `cv2.SIFT_create(nfeatures=1500)` as run on an AVX2 CPU.
    fn default() -> Self {
        SiftParams {
            nfeatures: 1500,
            n_octave_layers: 3,
            contrast_threshold: 0.04,
            edge_threshold: 10.0,
            sigma: 1.6,
            opencv_lanes: 8,
        }
    }
}

impl SiftParams {
    /// The lab's parameters with OpenCV's SIMD width as it would be on the
    /// CPU this runs on, so results equal OpenCV's on the same machine.
    pub fn for_host() -> Self {
        SiftParams { opencv_lanes: host_opencv_lanes(), ..Self::default() }
    }
}

/// OpenCV 4.8 dispatches its SIFT kernels to AVX512_SKX when the CPU has
/// AVX-512 F, CD, BW, DQ and VL, else to AVX2.
pub fn host_opencv_lanes() -> usize {
    #[cfg(target_arch = "x86_64")]
    {
        if std::is_x86_feature_detected!("avx512f")
            && std::is_x86_feature_detected!("avx512cd")
            && std::is_x86_feature_detected!("avx512bw")
            && std::is_x86_feature_detected!("avx512dq")
            && std::is_x86_feature_detected!("avx512vl")
        {
            return 16;
        }
    }
    8
}

/// The Gaussian pyramid and octave count of one image.
struct ScaleSpace {
    gauss: Vec<Plane>,
    octaves: usize,
}

fn scale_space(img: &GrayImage, p: &SiftParams) -> ScaleSpace {
    let base = initial::initial_image(img, p.sigma);
    let octaves = pyramid::octave_count(base.width, base.height);
    let gauss = pyramid::gaussian_pyramid(base, octaves, p.sigma, p.n_octave_layers);
    ScaleSpace { gauss, octaves }
}

/// Rows per scan job: bands, so the first octave spreads over all threads;
/// OpenCV splits its scan by rows the same way.
const BAND: usize = 32;

fn find_keypoints(ss: &ScaleSpace, p: &SiftParams) -> Vec<KeyPoint> {
    let mut kps = Vec::new();
    let per = p.n_octave_layers + 3;
    let jobs: Vec<(usize, usize)> = (0..ss.octaves)
        .flat_map(|o| {
            let h = ss.gauss[o * per].height;
            (0..h).step_by(BAND).map(move |r0| (o, r0))
        })
        .collect();
    run_parallel(
        &jobs,
        |&(o, r0), out| extrema::scan_octave(&ss.gauss[o * per..(o + 1) * per], o, r0..r0 + BAND, p, out),
        &mut kps,
    );
    in_opencv_order(kps, p)
}

/// §SIFT-10: duplicates removed from the sorted keypoints, the best `nfeatures`
/// kept, first-octave coordinates halved.
fn in_opencv_order(mut kps: Vec<KeyPoint>, p: &SiftParams) -> Vec<KeyPoint> {
    order::remove_duplicated_sorted(&mut kps);
    if p.nfeatures > 0 {
        order::retain_best(&mut kps, p.nfeatures);
    }
    order::rescale_first_octave(&mut kps);
    kps
}

/// Runs `f` over the jobs, on scoped threads natively; results are
/// concatenated (their order does not matter: §SIFT-10 sorts everything).
fn run_parallel<J: Sync>(jobs: &[J], f: impl Fn(&J, &mut Vec<KeyPoint>) + Sync, out: &mut Vec<KeyPoint>) {
    #[cfg(not(target_arch = "wasm32"))]
    {
        // The cap of `par::with_threads`: an odometry detection worker,
        // one frame per core, scans on its own thread (before, each scan
        // started threads for every core, four busy threads on two cores).
        let threads = par::threads().min(jobs.len());
        if threads > 1 {
            let next = std::sync::atomic::AtomicUsize::new(0);
            let parts: Vec<Vec<KeyPoint>> = std::thread::scope(|s| {
                let handles: Vec<_> = (0..threads)
                    .map(|_| {
                        s.spawn(|| {
                            let mut local = Vec::new();
                            loop {
                                let i = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                                let Some(job) = jobs.get(i) else { break };
                                f(job, &mut local);
                            }
                            local
                        })
                    })
                    .collect();
                handles.into_iter().map(|h| h.join().unwrap_or_default()).collect()
            });
            for p in parts {
                out.extend(p);
            }
            return;
        }
    }
    for j in jobs {
        f(j, out);
    }
}

/// `detect`: the keypoints only, in OpenCV's order.
pub fn detect(img: &GrayImage, p: &SiftParams) -> Vec<KeyPoint> {
    if img.width() == 0 || img.height() == 0 {
        return Vec::new();
    }
    if par::threads() > 1 {
        // All octaves' scans share out over the threads at once.
        let ss = scale_space(img, p);
        return find_keypoints(&ss, p);
    }
    // On one thread (an odometry detection worker): each octave is scanned
    // as soon as it is blurred, and its planes go back to the pool before
    // the next octave's are taken, so a worker holds one octave (45 MB on
    // KITTI's first) instead of the whole pyramid (60 MB): peak RSS of a
    // 99-frame `view_trajectory` 140 → 114 MB. Without descriptors nothing
    // reads an octave after its scan. Same keypoints: §SIFT-10 sorts them all.
    let base = initial::initial_image(img, p.sigma);
    let octaves = pyramid::octave_count(base.width, base.height);
    let sig = pyramid::level_sigmas(p.sigma, p.n_octave_layers);
    let mut kps = Vec::new();
    let mut first = base;
    for o in 0..octaves {
        let levels = pyramid::octave_levels(first, &sig);
        for r0 in (0..levels[0].height).step_by(BAND) {
            extrema::scan_octave(&levels, o, r0..r0 + BAND, p, &mut kps);
        }
        if o + 1 == octaves {
            break;
        }
        // Taken before `levels` goes back to the pool at the end of the loop
        // body, so the next octave's planes reuse this one's buffers.
        first = pyramid::next_octave_base(&levels, p.n_octave_layers);
    }
    in_opencv_order(kps, p)
}

/// `detectAndCompute(img, None)`: keypoints in OpenCV's order and one
/// descriptor row per keypoint.
pub fn detect_and_compute(img: &GrayImage, p: &SiftParams) -> Features {
    if img.width() == 0 || img.height() == 0 {
        return Features::default();
    }
    let ss = scale_space(img, p);
    let keypoints = find_keypoints(&ss, p);
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
            *row = descriptor::descriptor(&ss.gauss, &keypoints[visit[first + i]], p);
        }
    });
    let mut descriptors = vec![[0u8; 128]; keypoints.len()];
    for (&k, row) in visit.iter().zip(computed) {
        descriptors[k] = row;
    }
    Features { keypoints, descriptors }
}
