// throwaway A/B harness (not committed)
use siftlab_core::sift::{detect, detect_and_compute, SiftParams};
use siftlab_core::GrayImage;
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let ds = &args[1];
    let n: usize = args[2].parse().unwrap();
    let full = args.get(3).map(|s| s == "full").unwrap_or(false);
    let imgs: Vec<GrayImage> = (0..n).map(|i| {
        let p = format!("{ds}/gray/00/image_0/{i:06}.png");
        GrayImage::decode(&std::fs::read(&p).unwrap()).unwrap()
    }).collect();
    let p = SiftParams::for_host();
    let mut h = 0u64;
    let t = std::time::Instant::now();
    for im in &imgs {
        if full {
            let f = detect_and_compute(im, &p);
            for (k, d) in f.keypoints.iter().zip(&f.descriptors) { h = h.wrapping_mul(31).wrapping_add(k.x.to_bits() as u64 ^ k.angle.to_bits() as u64 ^ d[5] as u64); }
        } else {
            for k in detect(im, &p) { h = h.wrapping_mul(31).wrapping_add(k.x.to_bits() as u64 ^ k.y.to_bits() as u64 ^ k.octave as u64 ^ k.angle.to_bits() as u64); }
        }
    }
    println!("{:.1} ms/frame hash {h:x}", t.elapsed().as_secs_f64() * 1000.0 / n as f64);
}
