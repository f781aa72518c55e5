//! OpenCV's f32 accumulation orders replayed with AVX2, for the windows where
//! an exactness bound fails and the exact integer sums may differ from
//! OpenCV's f32 ones (docs/fidelity.md §VO-2.4; the bounds are in `wide`).

use super::super::wide::{Patch, Win16};
use super::super::WIN;
use super::rows::{load, load8};
use std::arch::x86_64::*;

/// OpenCV's tensor lanes L0..L3 and tail sums S of ΣX², ΣXY and ΣY² (in
/// that order), in OpenCV's order (`wide::tensor_lanes_replay`,
/// `wide::tail_replay`), the three sums at once: each row's block products
/// as i32, converted to f32 (rounding as OpenCV's conversion does), split
/// into columns B..B+3 and B+4..B+7 and added to the lanes in column order;
/// the tail's five columns as vectors (X², XY, Y², 0) added in order.
#[target_feature(enable = "avx2")]
pub(super) fn tensor_sums_replay(x: &Win16, y: &Win16) -> ([[f32; 4]; 3], [f32; 3]) {
    // Row layout positions B, B+1, .. hold columns B, B+4, B+1, B+5, ...
    let split = _mm256_setr_epi32(0, 2, 4, 6, 1, 3, 5, 7);
    let (mut lxx, mut lxy, mut lyy) = (_mm_setzero_ps(), _mm_setzero_ps(), _mm_setzero_ps());
    let mut tail = _mm_setzero_ps();
    let products =
        |a: __m256i, b: __m256i| _mm256_permutevar8x32_ps(_mm256_cvtepi32_ps(_mm256_mullo_epi32(a, b)), split);
    for (xr, yr) in x.iter().zip(y) {
        for block in [0, 8] {
            let xv = _mm256_cvtepi16_epi32(load8(xr, block));
            let yv = _mm256_cvtepi16_epi32(load8(yr, block));
            let (pxx, pxy, pyy) = (products(xv, xv), products(xv, yv), products(yv, yv));
            lxx = _mm_add_ps(_mm_add_ps(lxx, _mm256_castps256_ps128(pxx)), _mm256_extractf128_ps::<1>(pxx));
            lxy = _mm_add_ps(_mm_add_ps(lxy, _mm256_castps256_ps128(pxy)), _mm256_extractf128_ps::<1>(pxy));
            lyy = _mm_add_ps(_mm_add_ps(lyy, _mm256_castps256_ps128(pyy)), _mm256_extractf128_ps::<1>(pyy));
        }
        // Columns 16..23 (21..23 are scratch, never added).
        let xv = _mm256_cvtepi16_epi32(load8(xr, 16));
        let yv = _mm256_cvtepi16_epi32(load8(yr, 16));
        let f = |a: __m256i, b: __m256i| _mm256_cvtepi32_ps(_mm256_mullo_epi32(a, b));
        let (fxx, fxy, fyy) = (f(xv, xv), f(xv, yv), f(yv, yv));
        // Transposed: term vector c = (X²(c), XY(c), Y²(c), 0).
        let zero = _mm256_setzero_ps();
        let a = _mm256_unpacklo_ps(fxx, fxy); // xx0 xy0 xx1 xy1 | xx4 xy4 ..
        let b = _mm256_unpacklo_ps(fyy, zero); // yy0 0 yy1 0 | yy4 0 ..
        let c = _mm256_unpackhi_ps(fxx, fxy); // xx2 xy2 xx3 xy3 | ..
        let d = _mm256_unpackhi_ps(fyy, zero);
        let t0 = _mm256_shuffle_ps::<0b01_00_01_00>(a, b);
        let t1 = _mm256_shuffle_ps::<0b11_10_11_10>(a, b);
        let t2 = _mm256_shuffle_ps::<0b01_00_01_00>(c, d);
        let t3 = _mm256_shuffle_ps::<0b11_10_11_10>(c, d);
        for t in [t0, t1, t2, t3] {
            tail = _mm_add_ps(tail, _mm256_castps256_ps128(t));
        }
        tail = _mm_add_ps(tail, _mm256_extractf128_ps::<1>(t0));
    }
    let (mut out, mut t) = ([[0f32; 4]; 3], [0f32; 4]);
    // SAFETY: each store writes 4 f32 into a [f32; 4]; unaligned stores.
    unsafe {
        for (o, l) in out.iter_mut().zip([lxx, lxy, lyy]) {
            _mm_storeu_ps(o.as_mut_ptr(), l);
        }
        _mm_storeu_ps(t.as_mut_ptr(), tail);
    }
    (out, [t[0], t[1], t[2]])
}

/// OpenCV's T0..T3 (= P + Q: X of groups 0+2, Y of 0+2, X of 1+3, Y of
/// 1+3) replayed from the stored J − T, for when a lanes bound fails.
#[target_feature(enable = "avx2")]
pub(in crate::vo::lk::window) fn mismatch_lanes_replay(p: &Patch) -> [f32; 4] {
    let (mut acc_p, mut acc_q) = (_mm_setzero_ps(), _mm_setzero_ps());
    for y in 0..WIN {
        let (d, _) = load(&p.d[y]);
        let (x, _) = load(&p.x[y]);
        let (g, _) = load(&p.y[y]);
        let ux = _mm256_madd_epi16(d, x);
        let uy = _mm256_madd_epi16(d, g);
        // Per block: P += (uX(B), uY(B), uX(B+1), uY(B+1)), Q += the next two.
        let pv = _mm256_cvtepi32_ps(_mm256_unpacklo_epi32(ux, uy));
        let qv = _mm256_cvtepi32_ps(_mm256_unpackhi_epi32(ux, uy));
        acc_p = _mm_add_ps(acc_p, _mm256_castps256_ps128(pv));
        acc_q = _mm_add_ps(acc_q, _mm256_castps256_ps128(qv));
        acc_p = _mm_add_ps(acc_p, _mm256_extractf128_ps::<1>(pv));
        acc_q = _mm_add_ps(acc_q, _mm256_extractf128_ps::<1>(qv));
    }
    let mut t = [0f32; 4];
    // SAFETY: 4 f32 into a [f32; 4]; an unaligned store.
    unsafe { _mm_storeu_ps(t.as_mut_ptr(), _mm_add_ps(acc_p, acc_q)) };
    t
}
