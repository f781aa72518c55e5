//! The descriptor's vector kernels for x86-64: a window row's samples and
//! OpenCV's SIMD histogram body, 16 lanes with AVX-512 and 8 with AVX2, the
//! same operations per lane as the scalar loops of `mod.rs`, so the same
//! samples in the same order and the same histogram (docs/fidelity.md
//! §SIFT-11: the SIMD body rounds every product and difference).

use super::{cell_offsets, Rows, Samples, BINS_PER_DEG, D, HIST_LEN, N};
use std::arch::x86_64::*;

/// One row of the window, 16 columns at a time: the same operations as
/// the scalar loop, lanes kept by compress-store so the order is unchanged.
///
/// # Safety
/// Columns `c0 − 1 ..= c0 + n` of `row`, `up` and `down` exist, and each
/// vector of `s` has room for `n` more samples.
#[target_feature(enable = "avx512f")]
pub unsafe fn sample_row(
    s: &mut Samples,
    [row, up, down]: [&[f32]; 3],
    c0: usize,
    n: usize,
    j0: f32,
    [cos_t, sin_t, a, b]: [f32; 4],
    exp_scale: f32,
) {
    let lane = _mm512_setr_ps(0., 1., 2., 3., 4., 5., 6., 7., 8., 9., 10., 11., 12., 13., 14., 15.);
    let (cos_v, sin_v, a_v, b_v) = (_mm512_set1_ps(cos_t), _mm512_set1_ps(sin_t), _mm512_set1_ps(a), _mm512_set1_ps(b));
    let (half, point5, lo, hi) =
        (_mm512_set1_ps(D as f32 / 2.0), _mm512_set1_ps(0.5), _mm512_set1_ps(-1.0), _mm512_set1_ps(D as f32));
    let mut t = 0;
    while t < n {
        let valid: __mmask16 = if n - t >= 16 { 0xFFFF } else { (1u16 << (n - t)) - 1 };
        let fj = _mm512_add_ps(_mm512_set1_ps(j0 + t as f32), lane);
        let c_rot = _mm512_fmadd_ps(fj, cos_v, a_v);
        let r_rot = _mm512_fmadd_ps(fj, sin_v, b_v);
        let rbin = _mm512_sub_ps(_mm512_add_ps(r_rot, half), point5);
        let cbin = _mm512_sub_ps(_mm512_add_ps(c_rot, half), point5);
        let m = valid
            & _mm512_cmp_ps_mask::<_CMP_GT_OQ>(rbin, lo)
            & _mm512_cmp_ps_mask::<_CMP_LT_OQ>(rbin, hi)
            & _mm512_cmp_ps_mask::<_CMP_GT_OQ>(cbin, lo)
            & _mm512_cmp_ps_mask::<_CMP_LT_OQ>(cbin, hi);
        if m != 0 {
            let c = c0 + t;
            // SAFETY: the valid lanes are columns c − 1 ..= c0 + n, which
            // exist (the caller's promise); masked-off lanes are not read.
            let (dx, dy) = unsafe {
                (
                    _mm512_sub_ps(
                        _mm512_maskz_loadu_ps(valid, row.as_ptr().add(c + 1)),
                        _mm512_maskz_loadu_ps(valid, row.as_ptr().add(c - 1)),
                    ),
                    _mm512_sub_ps(
                        _mm512_maskz_loadu_ps(valid, up.as_ptr().add(c)),
                        _mm512_maskz_loadu_ps(valid, down.as_ptr().add(c)),
                    ),
                )
            };
            let w =
                _mm512_mul_ps(_mm512_fmadd_ps(c_rot, c_rot, _mm512_mul_ps(r_rot, r_rot)), _mm512_set1_ps(exp_scale));
            let len = s.dx.len();
            let k = m.count_ones() as usize;
            for (v, x) in [(&mut s.dx, dx), (&mut s.dy, dy), (&mut s.w, w), (&mut s.rbin, rbin), (&mut s.cbin, cbin)] {
                debug_assert!(v.capacity() >= len + k);
                // SAFETY: the vector has room for k more (the caller's
                // promise), and the store writes exactly its first k.
                unsafe {
                    _mm512_mask_compressstoreu_ps(v.as_mut_ptr().add(len).cast(), m, x);
                    v.set_len(len + k);
                }
            }
        }
        t += 16;
    }
}

/// The histogram update of OpenCV's SIMD body: bin indices and the eight
/// weights of 16 samples computed in vectors (every product and
/// difference rounded separately, as there), then added to the bins
/// sample by sample so each bin sees its contributions in order.
///
/// # Safety
/// Every row of `s` holds at least `simd_len` values.
#[target_feature(enable = "avx512f")]
pub unsafe fn accumulate(s: &Rows, simd_len: usize, ori: f32, hist: &mut [f32; HIST_LEN]) -> usize {
    const FLOOR: i32 = _MM_FROUND_TO_NEG_INF | _MM_FROUND_NO_EXC;
    let (ori_v, bpd) = (_mm512_set1_ps(ori), _mm512_set1_ps(BINS_PER_DEG));
    let (zero, n_v) = (_mm512_setzero_si512(), _mm512_set1_epi32(N as i32));
    let offs = cell_offsets();
    let mut k = 0;
    while k < simd_len {
        let count = (simd_len - k).min(16);
        let valid: __mmask16 = if count == 16 { 0xFFFF } else { (1u16 << count) - 1 };
        // SAFETY: the valid lanes are k..k + count <= simd_len, inside every
        // row (the caller's promise); masked-off lanes are not read.
        let load = |v: &[f32]| unsafe { _mm512_maskz_loadu_ps(valid, v.as_ptr().add(k)) };
        let (mut rbin, mut cbin) = (load(s.rbin), load(s.cbin));
        let mut obin = _mm512_mul_ps(_mm512_sub_ps(load(s.ori), ori_v), bpd);
        let mag = _mm512_mul_ps(load(s.mag), load(s.wt));
        let r0 = _mm512_cvt_roundps_epi32::<FLOOR>(rbin);
        let c0 = _mm512_cvt_roundps_epi32::<FLOOR>(cbin);
        let mut o0 = _mm512_cvt_roundps_epi32::<FLOOR>(obin);
        rbin = _mm512_sub_ps(rbin, _mm512_cvtepi32_ps(r0));
        cbin = _mm512_sub_ps(cbin, _mm512_cvtepi32_ps(c0));
        obin = _mm512_sub_ps(obin, _mm512_cvtepi32_ps(o0));
        o0 = _mm512_mask_add_epi32(o0, _mm512_cmplt_epi32_mask(o0, zero), o0, n_v);
        o0 = _mm512_mask_sub_epi32(o0, _mm512_cmpge_epi32_mask(o0, n_v), o0, n_v);
        let v_r1 = _mm512_mul_ps(mag, rbin);
        let v_r0 = _mm512_sub_ps(mag, v_r1);
        let v_rc11 = _mm512_mul_ps(v_r1, cbin);
        let v_rc10 = _mm512_sub_ps(v_r1, v_rc11);
        let v_rc01 = _mm512_mul_ps(v_r0, cbin);
        let v_rc00 = _mm512_sub_ps(v_r0, v_rc01);
        let idx = _mm512_add_epi32(
            _mm512_mullo_epi32(
                _mm512_add_epi32(
                    _mm512_mullo_epi32(_mm512_add_epi32(r0, _mm512_set1_epi32(1)), _mm512_set1_epi32(D as i32 + 2)),
                    _mm512_add_epi32(c0, _mm512_set1_epi32(1)),
                ),
                _mm512_set1_epi32(N as i32 + 2),
            ),
            o0,
        );
        let mut idx_a = [0i32; 16];
        // SAFETY: idx_a holds 16 i32, one vector.
        unsafe { _mm512_storeu_si512(idx_a.as_mut_ptr().cast(), idx) };
        let mut w = [[0f32; 16]; 8];
        for (c, rc) in [v_rc00, v_rc01, v_rc10, v_rc11].into_iter().enumerate() {
            let rco1 = _mm512_mul_ps(rc, obin);
            // SAFETY: each row of w holds 16 f32, one vector.
            unsafe {
                _mm512_storeu_ps(w[2 * c].as_mut_ptr(), _mm512_sub_ps(rc, rco1));
                _mm512_storeu_ps(w[2 * c + 1].as_mut_ptr(), rco1);
            }
        }
        for l in 0..count {
            // r0, c0 in [-1, 3] and o0 in [0, 7] keep idx in 0..=287; the
            // clamp only tells the compiler so (no bounds checks below).
            let idx = idx_a[l].clamp(0, 287) as usize;
            for (c, off) in offs.into_iter().enumerate() {
                hist[idx + off] += w[2 * c][l];
                hist[idx + off + 1] += w[2 * c + 1][l];
            }
        }
        k += count;
    }
    k
}

/// For each 8-bit mask of kept lanes, the lanes to move to the front (in
/// order): AVX2 has no compress-store, `vpermps` by this table does it.
static COMPRESS: [[u32; 8]; 256] = {
    let mut t = [[0u32; 8]; 256];
    let mut m = 0;
    while m < 256 {
        let (mut k, mut l) = (0, 0);
        while l < 8 {
            if m & (1 << l) != 0 {
                t[m][k] = l as u32;
                k += 1;
            }
            l += 1;
        }
        m += 1;
    }
    t
};

/// [`sample_row`] for AVX2, 8 columns at a time: the kept lanes are
/// moved to the front by [`COMPRESS`] and stored with a mask of as many
/// lanes, so the order is the scalar loop's. Only whole blocks of 8; the
/// scalar loop does the rest. Returns the columns examined.
///
/// # Safety
/// As [`sample_row`].
#[target_feature(enable = "avx2,fma")]
pub unsafe fn sample_row_avx2(
    s: &mut Samples,
    [row, up, down]: [&[f32]; 3],
    c0: usize,
    n: usize,
    j0: f32,
    [cos_t, sin_t, a, b]: [f32; 4],
    exp_scale: f32,
) -> usize {
    let lane = _mm256_setr_ps(0., 1., 2., 3., 4., 5., 6., 7.);
    let lane_i = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
    let (cos_v, sin_v, a_v, b_v) = (_mm256_set1_ps(cos_t), _mm256_set1_ps(sin_t), _mm256_set1_ps(a), _mm256_set1_ps(b));
    let (half, point5, lo, hi) =
        (_mm256_set1_ps(D as f32 / 2.0), _mm256_set1_ps(0.5), _mm256_set1_ps(-1.0), _mm256_set1_ps(D as f32));
    let mut t = 0;
    while t + 8 <= n {
        let fj = _mm256_add_ps(_mm256_set1_ps(j0 + t as f32), lane);
        let c_rot = _mm256_fmadd_ps(fj, cos_v, a_v);
        let r_rot = _mm256_fmadd_ps(fj, sin_v, b_v);
        let rbin = _mm256_sub_ps(_mm256_add_ps(r_rot, half), point5);
        let cbin = _mm256_sub_ps(_mm256_add_ps(c_rot, half), point5);
        let keep = _mm256_and_ps(
            _mm256_and_ps(_mm256_cmp_ps::<_CMP_GT_OQ>(rbin, lo), _mm256_cmp_ps::<_CMP_LT_OQ>(rbin, hi)),
            _mm256_and_ps(_mm256_cmp_ps::<_CMP_GT_OQ>(cbin, lo), _mm256_cmp_ps::<_CMP_LT_OQ>(cbin, hi)),
        );
        let m = _mm256_movemask_ps(keep) as usize;
        if m != 0 {
            let c = c0 + t;
            // SAFETY: columns c − 1 ..= c + 8 <= c0 + n exist (t + 8 <= n and
            // the caller's promise).
            let (dx, dy) = unsafe {
                (
                    _mm256_sub_ps(_mm256_loadu_ps(row.as_ptr().add(c + 1)), _mm256_loadu_ps(row.as_ptr().add(c - 1))),
                    _mm256_sub_ps(_mm256_loadu_ps(up.as_ptr().add(c)), _mm256_loadu_ps(down.as_ptr().add(c))),
                )
            };
            let w =
                _mm256_mul_ps(_mm256_fmadd_ps(c_rot, c_rot, _mm256_mul_ps(r_rot, r_rot)), _mm256_set1_ps(exp_scale));
            // SAFETY: a COMPRESS entry is eight u32, one vector.
            let perm = unsafe { _mm256_loadu_si256(COMPRESS[m].as_ptr().cast()) };
            let k = m.count_ones() as usize;
            let first_k = _mm256_cmpgt_epi32(_mm256_set1_epi32(k as i32), lane_i);
            let len = s.dx.len();
            for (v, x) in [(&mut s.dx, dx), (&mut s.dy, dy), (&mut s.w, w), (&mut s.rbin, rbin), (&mut s.cbin, cbin)] {
                debug_assert!(v.capacity() >= len + k);
                // SAFETY: the vector has room for k more (the caller's
                // promise), and the mask stores exactly the first k lanes.
                unsafe {
                    _mm256_maskstore_ps(v.as_mut_ptr().add(len), first_k, _mm256_permutevar8x32_ps(x, perm));
                    v.set_len(len + k);
                }
            }
        }
        t += 8;
    }
    t
}

/// [`accumulate`] for AVX2, 8 samples a step (whole blocks only; the
/// caller does the rest of the SIMD body with the same operations).
#[target_feature(enable = "avx2")]
pub fn accumulate_avx2(s: &Rows, simd_len: usize, ori: f32, hist: &mut [f32; HIST_LEN]) -> usize {
    let (ori_v, bpd) = (_mm256_set1_ps(ori), _mm256_set1_ps(BINS_PER_DEG));
    let (zero, n_v) = (_mm256_setzero_si256(), _mm256_set1_epi32(N as i32));
    let floor_i = |v: __m256| _mm256_cvttps_epi32(_mm256_floor_ps(v));
    let offs = cell_offsets();
    let mut k = 0;
    while k + 8 <= simd_len {
        // SAFETY: the slice holds eight f32, one vector.
        let load = |v: &[f32]| unsafe { _mm256_loadu_ps(v[k..k + 8].as_ptr()) };
        let (mut rbin, mut cbin) = (load(s.rbin), load(s.cbin));
        let mut obin = _mm256_mul_ps(_mm256_sub_ps(load(s.ori), ori_v), bpd);
        let mag = _mm256_mul_ps(load(s.mag), load(s.wt));
        let (r0, c0, mut o0) = (floor_i(rbin), floor_i(cbin), floor_i(obin));
        rbin = _mm256_sub_ps(rbin, _mm256_cvtepi32_ps(r0));
        cbin = _mm256_sub_ps(cbin, _mm256_cvtepi32_ps(c0));
        obin = _mm256_sub_ps(obin, _mm256_cvtepi32_ps(o0));
        o0 = _mm256_add_epi32(o0, _mm256_and_si256(_mm256_cmpgt_epi32(zero, o0), n_v));
        o0 = _mm256_sub_epi32(o0, _mm256_andnot_si256(_mm256_cmpgt_epi32(n_v, o0), n_v));
        let v_r1 = _mm256_mul_ps(mag, rbin);
        let v_r0 = _mm256_sub_ps(mag, v_r1);
        let v_rc11 = _mm256_mul_ps(v_r1, cbin);
        let v_rc10 = _mm256_sub_ps(v_r1, v_rc11);
        let v_rc01 = _mm256_mul_ps(v_r0, cbin);
        let v_rc00 = _mm256_sub_ps(v_r0, v_rc01);
        let idx = _mm256_add_epi32(
            _mm256_mullo_epi32(
                _mm256_add_epi32(
                    _mm256_mullo_epi32(_mm256_add_epi32(r0, _mm256_set1_epi32(1)), _mm256_set1_epi32(D as i32 + 2)),
                    _mm256_add_epi32(c0, _mm256_set1_epi32(1)),
                ),
                _mm256_set1_epi32(N as i32 + 2),
            ),
            o0,
        );
        let mut idx_a = [0i32; 8];
        // SAFETY: idx_a holds eight i32, one vector.
        unsafe { _mm256_storeu_si256(idx_a.as_mut_ptr().cast(), idx) };
        let mut w = [[0f32; 8]; 8];
        for (c, rc) in [v_rc00, v_rc01, v_rc10, v_rc11].into_iter().enumerate() {
            let rco1 = _mm256_mul_ps(rc, obin);
            // SAFETY: each row of w holds eight f32, one vector.
            unsafe {
                _mm256_storeu_ps(w[2 * c].as_mut_ptr(), _mm256_sub_ps(rc, rco1));
                _mm256_storeu_ps(w[2 * c + 1].as_mut_ptr(), rco1);
            }
        }
        for (l, &idx) in idx_a.iter().enumerate() {
            // As in `accumulate`: idx is in 0..=287; the clamp removes
            // the bounds checks.
            let idx = idx.clamp(0, 287) as usize;
            for (c, off) in offs.into_iter().enumerate() {
                hist[idx + off] += w[2 * c][l];
                hist[idx + off + 1] += w[2 * c + 1][l];
            }
        }
        k += 8;
    }
    k
}
