//! The orientation histogram's binning of OpenCV's SIMD body with AVX2: the
//! rounded products of docs/fidelity.md §SIFT-8, added in sample order.

use std::arch::x86_64::*;

/// Bin b's masks for the five vectors: all ones in lane b % 8 of
/// vector b / 8, zeros elsewhere, each vector on its own 32 bytes.
#[repr(C, align(64))]
struct Masks([[[u32; 8]; 5]; 36]);
static ONE_HOT: Masks = {
    let mut a = [[[0u32; 8]; 5]; 36];
    let mut b = 0;
    while b < 36 {
        a[b][b / 8][b % 8] = u32::MAX;
        b += 1;
    }
    Masks(a)
};
const MASKS_BYTES: i32 = 5 * 32;

/// The histogram's first `n` samples (those OpenCV's SIMD loop takes:
/// a rounded product, then an add) into `t[2..38]`, with all 36 bins in
/// five vectors and each sample added to every bin, masked to 0.0 in
/// all but its own. x + 0.0 = x for every x here (sums of non-negative
/// products start at +0.0), so each bin sees exactly its samples' adds
/// in sample order, as in the scalar loop. That loop's read-add-write of
/// `t[bin]` made consecutive samples of one bin — the usual case, as
/// neighbouring gradients point alike — a chain through memory (about
/// 9 cycles a sample); here the chain is one vector add.
///
/// Two passes: the bins and products of eight samples at a time go to
/// `offsets` and `prods`, then each sample's masks and product are
/// plain loads (a broadcast load for the product). Taken from the
/// vectors in one pass, every sample cost two lane shuffles and five
/// compares on the vector pipes the adds need: 2.6–2.7 against
/// 1.7–2.0 ns a sample on this machine (same process, interleaved).
#[target_feature(enable = "avx2,fma")]
pub fn bin_products(
    wts: &[f32],
    oris: &[f32],
    mags: &[f32],
    n: usize,
    offsets: &mut Vec<u32>,
    prods: &mut Vec<f32>,
    t: &mut [f32; 40],
) {
    assert!(n <= wts.len() && n <= oris.len() && n <= mags.len());
    let room = n.div_ceil(8) * 8;
    offsets.resize(room.max(offsets.len()), 0);
    prods.resize(room.max(prods.len()), 0.0);
    let scale = _mm256_set1_ps(super::bins::ORI_HIST_BINS as f32 / 360.0);
    let (n36, zero) = (_mm256_set1_epi32(36), _mm256_setzero_si256());
    let bytes = _mm256_set1_epi32(MASKS_BYTES);
    let mut k = 0;
    while k < n {
        let m = (n - k).min(8);
        // Eight samples' bins and products at once (a partial group
        // computes lanes past n from zeros, never read).
        let (o, wt, mg) = if m == 8 {
            // SAFETY: k + 8 <= n, within all three slices (asserted above).
            unsafe {
                (
                    _mm256_loadu_ps(oris.as_ptr().add(k)),
                    _mm256_loadu_ps(wts.as_ptr().add(k)),
                    _mm256_loadu_ps(mags.as_ptr().add(k)),
                )
            }
        } else {
            let mut a = [[0f32; 8]; 3];
            a[0][..m].copy_from_slice(&oris[k..k + m]);
            a[1][..m].copy_from_slice(&wts[k..k + m]);
            a[2][..m].copy_from_slice(&mags[k..k + m]);
            // SAFETY: each row of `a` holds eight f32, one vector.
            unsafe { (_mm256_loadu_ps(a[0].as_ptr()), _mm256_loadu_ps(a[1].as_ptr()), _mm256_loadu_ps(a[2].as_ptr())) }
        };
        // cvRound((n/360)·ori), then into 0..36 as the scalar loop does.
        let mut b = _mm256_cvtps_epi32(_mm256_round_ps::<{ _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC }>(
            _mm256_mul_ps(scale, o),
        ));
        b = _mm256_sub_epi32(
            b,
            _mm256_and_si256(_mm256_cmpgt_epi32(b, _mm256_sub_epi32(n36, _mm256_set1_epi32(1))), n36),
        );
        b = _mm256_add_epi32(b, _mm256_and_si256(_mm256_cmpgt_epi32(zero, b), n36));
        // Already 0..36 for every finite orientation; the unsigned
        // clamp only keeps a NaN's bin from addressing outside ONE_HOT.
        b = _mm256_min_epu32(b, _mm256_set1_epi32(35));
        // SAFETY: k + 8 <= room, and both buffers hold at least room values.
        unsafe {
            _mm256_storeu_si256(offsets.as_mut_ptr().add(k) as *mut __m256i, _mm256_mullo_epi32(b, bytes));
            _mm256_storeu_ps(prods.as_mut_ptr().add(k), _mm256_mul_ps(wt, mg));
        }
        k += m;
    }
    let masks = ONE_HOT.0.as_ptr() as *const u8;
    let mut h = [_mm256_setzero_ps(); 5];
    for (&off, p) in offsets[..n].iter().zip(&prods[..n]) {
        // SAFETY: bins are 0..36 (clamped above), so the offset is a bin's
        // start inside ONE_HOT, and its five vectors follow it there, each
        // 32-byte aligned (the table is 64-byte aligned, a bin 160 bytes).
        let m = unsafe { masks.add(off as usize) as *const f32 };
        let pj = _mm256_set1_ps(*p);
        for (v, hv) in h.iter_mut().enumerate() {
            // SAFETY: as above, v < 5.
            *hv = _mm256_add_ps(*hv, _mm256_and_ps(unsafe { _mm256_load_ps(m.add(8 * v)) }, pj));
        }
    }
    let mut out = [0f32; 40];
    for (v, hv) in h.iter().enumerate() {
        // SAFETY: 8·v + 8 <= 40 for v < 5.
        unsafe { _mm256_storeu_ps(out.as_mut_ptr().add(8 * v), *hv) };
    }
    t[2..38].copy_from_slice(&out[..36]);
}
