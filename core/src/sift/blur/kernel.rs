//! The Gaussian kernel the blur applies (§SIFT-3).

use super::super::num::rne64;

/// `getGaussianKernelBitExact` for an f32 image (§SIFT-3): `ksize = rne(8σ + 1) | 1`
/// (the factor 4 because the depth is not 8U), weights computed in f64 and
/// rounded once to f32.
pub fn gaussian_kernel(sigma: f64) -> Vec<f32> {
    let n = (rne64(sigma * 4.0 * 2.0 + 1.0) | 1) as usize;
    let h = (n - 1) / 2;
    let scale2x = -0.125 / (sigma * sigma);
    let v: Vec<f64> = (0..h)
        .map(|i| {
            let x = 2.0 * i as f64 - (n as f64 - 1.0);
            (x * x * scale2x).exp()
        })
        .collect();
    let mut sum = 0.0f64;
    for &vi in &v {
        sum += vi;
    }
    let mul = 1.0 / (sum * 2.0 + 1.0);
    let mut k = vec![0f32; n];
    for i in 0..h {
        k[i] = (v[i] * mul) as f32;
        k[n - 1 - i] = k[i];
    }
    k[h] = mul as f32;
    k
}
