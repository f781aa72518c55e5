//! The wasm Gaussian blur against a plain separable filter on the exact scalar
//! FMA.

use wasm_bindgen_test::*;

/// A plain separable Gaussian filter on the exact scalar FMA, as docs/fidelity.md §SIFT-3 states it: row
/// pass (first tap a product, then one FMA per tap, BORDER_REFLECT_101), then the
/// symmetric column pass (centre product, then one FMA per pair of rows).
fn reference_blur(src: &siftlab_core::internals::Plane, sigma: f64) -> Vec<f32> {
    use siftlab_core::internals::gaussian_kernel;
    use siftlab_core::internals::num::fma_emulated;
    let (w, h) = (src.width, src.height);
    let k = gaussian_kernel(sigma);
    let r = k.len() / 2;
    let reflect = |mut p: isize, len: usize| {
        let len = len as isize;
        while p < 0 || p >= len {
            p = if p < 0 { -p } else { 2 * (len - 1) - p };
        }
        p as usize
    };
    let mut tmp = vec![0f32; w * h];
    for y in 0..h {
        for x in 0..w {
            let at = |t: usize| src.data[y * w + reflect(x as isize + t as isize - r as isize, w)];
            let mut a = at(0) * k[0];
            for (t, &kt) in k.iter().enumerate().skip(1) {
                a = fma_emulated(at(t), kt, a);
            }
            tmp[y * w + x] = a;
        }
    }
    let mut out = vec![0f32; w * h];
    for y in 0..h {
        for x in 0..w {
            let at = |dy: isize| tmp[reflect(y as isize + dy, h) * w + x];
            let mut a = at(0) * k[r];
            for t in 1..=r {
                a = fma_emulated(at(t as isize) + at(-(t as isize)), k[r + t], a);
            }
            out[y * w + x] = a;
        }
    }
    out
}

/// The wasm Gaussian blur equals [`reference_blur`] bit for bit, on both of its paths:
/// tame data (every value 0 or in [2^-100, 2^100]), where the FMA check is ORed over a
/// 16-pixel block and a flagged block is redone with the scalar FMA, and other data
/// (negative values, values near 2^-110), where every FMA is checked as it is made.
/// Each image is blurred three times in a row at the pyramid's sigmas, as SIFT chains
/// its levels.
#[wasm_bindgen_test]
fn blur_in_the_browser_equals_the_scalar_filter() {
    use siftlab_core::internals::gaussian_blur;
    use siftlab_core::internals::Plane;
    let mut state = 0x2545_F491_4F6C_DD1Du64;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    /// (name, width, height, pixel from a random draw)
    type Case = (&'static str, usize, usize, fn(u64) -> f32);
    let cases: [Case; 4] = [
        ("8-bit image", 203, 61, |r| (r % 256) as f32),
        ("8-bit image with black areas", 97, 40, |r| if r % 3 == 0 { 0.0 } else { (r % 256) as f32 }),
        ("negative values", 131, 37, |r| (r % 512) as f32 - 255.5),
        ("values near 2^-110", 77, 29, |r| if r % 2 == 0 { 0.0 } else { (r % 1000) as f32 * 7.7e-34 }),
    ];
    let mut checked = 0;
    for (name, w, h, value) in cases {
        let mut img = Plane::new(w, h);
        for v in img.data.iter_mut() {
            *v = value(next() >> 11);
        }
        for sigma in [1.2262734984654078, 1.9465878414647133, 3.090015587289591] {
            let want = reference_blur(&img, sigma);
            let got = gaussian_blur(&img, sigma);
            for (i, (g, e)) in got.data.iter().zip(&want).enumerate() {
                assert_eq!(g.to_bits(), e.to_bits(), "{name}, sigma {sigma}: pixel ({}, {}): {g} vs {e}", i % w, i / w);
            }
            checked += want.len();
            img = got;
        }
    }
    assert_eq!(checked, 3 * (203 * 61 + 97 * 40 + 131 * 37 + 77 * 29));
}
