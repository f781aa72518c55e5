//! The scan's x86 kernel: the DoG rows of six Gaussian rows at once (AVX2),
//! docs/fidelity.md §SIFT-5.

use std::arch::x86_64::*;

/// [`super::differences`] for six Gaussian rows, eight columns at a
/// time (a last block overlapping the one before).
///
/// # Safety
/// Each `g[k]` points to `w` readable floats and each `d[k]` to `w` writable
/// floats of its own, apart from the others and from the `g` rows.
#[target_feature(enable = "avx2")]
pub unsafe fn differences6_avx2(g: [*const f32; 6], d: [*mut f32; 5], w: usize) {
    // Called with x + 8 <= w.
    let block = |x: usize| {
        let v: [__m256; 6] = std::array::from_fn(|k| {
            // SAFETY: x + 8 <= w, inside every row (the caller's promise).
            unsafe { _mm256_loadu_ps(g[k].add(x)) }
        });
        for k in 0..5 {
            // SAFETY: as above.
            unsafe { _mm256_storeu_ps(d[k].add(x), _mm256_sub_ps(v[k + 1], v[k])) };
        }
    };
    if w < 8 {
        for x in 0..w {
            for k in 0..5 {
                // SAFETY: x < w, inside every row (the caller's promise).
                unsafe { *d[k].add(x) = *g[k + 1].add(x) - *g[k].add(x) };
            }
        }
        return;
    }
    let mut x = 0;
    while x + 8 <= w {
        block(x);
        x += 8;
    }
    if x < w {
        block(w - 8);
    }
}
