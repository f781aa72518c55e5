//! The plain integer sum every distance kernel reproduces, and the
//! portable kernels built on it (docs/fidelity.md §SIFT-16).

/// The exact sum of squared differences of two descriptors.
#[inline(always)]
pub fn distance_sq(a: &[u8; 128], b: &[u8; 128]) -> u32 {
    let mut s = 0u32;
    for (&x, &y) in a.iter().zip(b.iter()) {
        let d = x as i32 - y as i32;
        s += (d * d) as u32;
    }
    s
}

/// `sqrtf` of the exact sum, as BFMatcher reports it.
#[inline(always)]
pub fn distance(a: &[u8; 128], b: &[u8; 128]) -> f32 {
    (distance_sq(a, b) as f32).sqrt()
}

/// The portable kernel (auto-vectorised where the target allows).
pub(super) fn row_generic(q: &[u8; 128], train: &[[u8; 128]], out: &mut [f32]) {
    for (o, t) in out.iter_mut().zip(train) {
        *o = distance(q, t);
    }
}

/// |t|^2 = the sum of squares of the bytes, at most 128 * 255^2.
pub(super) fn norm_sq(t: &[u8; 128]) -> i32 {
    t.iter().map(|&x| x as i32 * x as i32).sum()
}
