//! Where wasm SIFT's time goes, stage by stage, in the browser: the base image (upsampling
//! and its blur), the pyramid's level blurs, the scan with refinement and orientation, and
//! the descriptors, on the demo frames 0–5, best of three per stage (`ROUNDS`). Run it in both worker
//! builds (docs/performance.md, "The SIMD128 path") to see what the FMA emulation costs:
//! `cargo test --release --target wasm32-unknown-unknown -p siftlab-core --no-default-features [--features relaxed-simd] --test wasm_stages -- --nocapture`
//! It prints one `WASM_STAGES` line per frame (timings are printed, never asserted: the
//! machine may be busy), and checks what the app's odometry relies on: `detect` gives
//! exactly the keypoints of `detect_and_compute`, so a tracker may take its points from
//! the shared features.

#![cfg(target_arch = "wasm32")]

use siftlab_core::internals::{gaussian_blur, initial_image, level_sigmas, Plane};
use siftlab_core::sift::{detect, detect_and_compute, fma_engine, SiftParams};
use siftlab_core::GrayImage;
use wasm_bindgen::prelude::*;
use wasm_bindgen_test::*;

wasm_bindgen_test_configure!(run_in_browser);

#[wasm_bindgen]
extern "C" {
    #[wasm_bindgen(js_namespace = performance, js_name = now)]
    fn performance_now() -> f64;
}

const FRAMES: [&[u8]; 6] = [
    include_bytes!("../../www/demo/MyKITTI/gray/00/image_0/000000.png"),
    include_bytes!("../../www/demo/MyKITTI/gray/00/image_0/000001.png"),
    include_bytes!("../../www/demo/MyKITTI/gray/00/image_0/000002.png"),
    include_bytes!("../../www/demo/MyKITTI/gray/00/image_0/000003.png"),
    include_bytes!("../../www/demo/MyKITTI/gray/00/image_0/000004.png"),
    include_bytes!("../../www/demo/MyKITTI/gray/00/image_0/000005.png"),
];

/// Rounds per frame, the best of which is printed: 3 for the timings;
/// `tests/run` builds it with `SIFTLAB_WASM_STAGES_ROUNDS=1` (it checks the
/// keypoints, which one round does as well, in three builds and engines).
const ROUNDS: usize = match option_env!("SIFTLAB_WASM_STAGES_ROUNDS") {
    Some(s) if s.len() == 1 && s.as_bytes()[0] == b'1' => 1,
    _ => 3,
};

fn timed<T>(f: impl FnOnce() -> T) -> (T, f64) {
    let t0 = performance_now();
    let v = f();
    (v, performance_now() - t0)
}

/// The octave's first level, halved as the pyramid does (§SIFT-4).
fn downsample(src: &Plane) -> Plane {
    let (w, h) = (src.width / 2, src.height / 2);
    let mut out = Plane::new(w, h);
    for y in 0..h {
        for x in 0..w {
            out.data[y * w + x] = src.data[2 * y * src.width + 2 * x];
        }
    }
    out
}

#[wasm_bindgen_test]
fn sift_stages_in_the_browser() {
    let p = SiftParams::default();
    let sig = level_sigmas(p.sigma, p.n_octave_layers);
    console_log!("WASM_STAGES engine: {}", fma_engine());
    let mut totals = [0f64; 6];
    for (i, bytes) in FRAMES.iter().enumerate() {
        let img = GrayImage::decode(bytes).expect("demo frame decodes");
        // [base, base blur alone, level blurs, detect, detect_and_compute]
        let mut best = [f64::INFINITY; 5];
        for _ in 0..ROUNDS {
            let (base, t_base) = timed(|| initial_image(&img, p.sigma));
            // The base's blur alone, on a plane of the base's size.
            let (_, t_base_blur) = timed(|| gaussian_blur(&base, sig[0]));
            let (_, t_levels) = timed(|| {
                let mut first = base;
                let octaves =
                    ((first.width.min(first.height) as f64).ln() / 2f64.ln() - 2.0).round_ties_even() as usize + 1;
                for _ in 0..octaves {
                    let mut levels = vec![first];
                    for &s in &sig[1..] {
                        let l = gaussian_blur(levels.last().unwrap(), s);
                        levels.push(l);
                    }
                    first = downsample(&levels[p.n_octave_layers]);
                    if first.width == 0 || first.height == 0 {
                        break;
                    }
                }
            });
            let (kps, t_detect) = timed(|| detect(&img, &p));
            let (features, t_all) = timed(|| detect_and_compute(&img, &p));
            let bits = |k: &siftlab_core::sift::KeyPoint| {
                [k.x, k.y, k.size, k.angle, k.response].map(f32::to_bits).to_vec().into_iter().chain([k.octave as u32])
            };
            assert!(kps.len() > 1000, "frame {i}: {} keypoints", kps.len());
            assert!(
                kps.iter().flat_map(bits).eq(features.keypoints.iter().flat_map(bits)),
                "frame {i}: detect and detect_and_compute differ"
            );
            for (b, t) in best.iter_mut().zip([t_base, t_base_blur, t_levels, t_detect, t_all]) {
                *b = b.min(t);
            }
        }
        let [base, base_blur, levels, det, all] = best;
        let scan = det - base - levels;
        let desc = all - det;
        console_log!(
            "WASM_STAGES frame {i}: total {all:.1} ms = base {base:.1} (its blur {base_blur:.1}) + level blurs {levels:.1} \
             + scan/refine/orientation {scan:.1} + descriptors {desc:.1}"
        );
        for (t, v) in totals.iter_mut().zip([all, base, base_blur, levels, scan, desc]) {
            *t += v;
        }
    }
    let [all, base, base_blur, levels, scan, desc] = totals.map(|t| t / FRAMES.len() as f64);
    let pc = |v: f64| 100.0 * v / all;
    console_log!(
        "WASM_STAGES mean: total {all:.1} ms; base {base:.1} ({:.0} %, blur {base_blur:.1}), level blurs {levels:.1} ({:.0} %), \
         scan {scan:.1} ({:.0} %), descriptors {desc:.1} ({:.0} %); all blurs {:.1} ms ({:.0} %)",
        pc(base),
        pc(levels),
        pc(scan),
        pc(desc),
        base_blur + levels,
        pc(base_blur + levels)
    );
}
