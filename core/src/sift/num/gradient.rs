//! The gradient kernels of the orientation histogram and the descriptor over
//! whole sample arrays, as OpenCV's `hal` calls run them (docs/fidelity.md
//! §SIFT-8, §SIFT-11): direction by `fastAtan2`, [`magnitude`] and weight by
//! `exp32f`; the vector kernels do the lanes they can, the scalar ones the rest.

use super::{exp32f, fast_atan2_deg, fma};

/// `cv::hal::magnitude32f` with IPP disabled: `sqrtf(fma(x, x, y*y))`.
#[inline(always)]
pub fn magnitude(x: f32, y: f32) -> f32 {
    fma(x, x, y * y).sqrt()
}

/// Orientation (degrees), magnitude and Gaussian weight of every gradient
/// sample, each kernel run over the whole array as OpenCV's `hal` calls do,
/// so the loops vectorise (inlined into the FMA-enabled callers).
#[inline(always)]
pub fn gradient_samples(dxs: &[f32], dys: &[f32], w_args: &[f32]) -> (Vec<f32>, Vec<f32>, Vec<f32>) {
    let (oris, mags) = gradient_directions(dxs, dys);
    let mut wts = vec![0f32; w_args.len()];
    #[cfg(target_arch = "wasm32")]
    let done = super::wasm::exp32f(w_args, &mut wts);
    #[cfg(not(target_arch = "wasm32"))]
    let done = 0;
    for (w, &a) in wts.iter_mut().zip(w_args).skip(done) {
        *w = exp32f(a);
    }
    (oris, mags, wts)
}

/// [`exp32f`] of every argument into `out` (as long), eight or four lanes
/// at a time where the CPU has them.
#[inline(always)]
pub fn exp32f_into(args: &[f32], out: &mut [f32]) {
    #[cfg(target_arch = "x86_64")]
    let done = if crate::simd::avx2_fma() {
        // SAFETY: the CPU has AVX2 and FMA.
        unsafe { super::x86::exp32f(args, out) }
    } else {
        0
    };
    #[cfg(target_arch = "wasm32")]
    let done = super::wasm::exp32f(args, out);
    #[cfg(not(any(target_arch = "x86_64", target_arch = "wasm32")))]
    let done = 0;
    for (w, &a) in out.iter_mut().zip(args).skip(done) {
        *w = exp32f(a);
    }
}

/// The orientation (degrees) and magnitude of every gradient sample.
#[inline(always)]
pub fn gradient_directions(dxs: &[f32], dys: &[f32]) -> (Vec<f32>, Vec<f32>) {
    let (mut oris, mut mags) = (Vec::new(), Vec::new());
    gradient_directions_into(dxs, dys, &mut oris, &mut mags);
    (oris, mags)
}

/// [`gradient_directions`] into buffers the caller reuses.
#[inline(always)]
pub fn gradient_directions_into(dxs: &[f32], dys: &[f32], oris: &mut Vec<f32>, mags: &mut Vec<f32>) {
    let len = dxs.len();
    oris.clear();
    oris.resize(len, 0.0);
    mags.clear();
    mags.resize(len, 0.0);
    // Slices, so the loops below vectorise (through `&mut Vec` each store
    // might move the buffer pointer, which is then reloaded every sample).
    let (oris, mags) = (&mut oris[..], &mut mags[..]);
    #[cfg(target_arch = "wasm32")]
    let done = super::wasm::gradient_directions(dxs, dys, oris, mags);
    #[cfg(not(target_arch = "wasm32"))]
    let done = 0;
    for k in done..len {
        oris[k] = fast_atan2_deg(dys[k], dxs[k]);
    }
    for k in done..len {
        mags[k] = magnitude(dxs[k], dys[k]);
    }
}
