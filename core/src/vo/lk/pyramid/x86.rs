//! The pyramid's AVX2 code: `pyrDown`'s horizontal pass sixteen columns at a
//! time, and both passes and the Scharr derivatives compiled for AVX2. The
//! same integers as the portable code beside it.

use super::plain::{pyr_down_columns, pyr_down_row_edges, Deriv, Level};
use std::arch::x86_64::*;

/// [`super::pyr_down`] with AVX2: each row's interior columns sixteen at
/// a time (the even and odd source pixels of 32 bytes are the low and
/// high bytes of its sixteen 16-bit lanes), the vertical pass compiled
/// for AVX2. The same integers as the portable pass. Needs w ≥ 40.
#[target_feature(enable = "avx2")]
pub(super) fn pyr_down_avx2(src: &[u8], w: usize, h: usize) -> (Vec<u8>, usize, usize) {
    assert!(w >= 40);
    let dw = w.div_ceil(2);
    // Columns 1..=last read source pixels 2x − 2 ..= 2x + 2 inside the row.
    let last = (w - 3) / 2;
    let mut hrow = vec![0u16; dw * h];
    let lo = _mm256_set1_epi16(0xff);
    for y in 0..h {
        let row = &src[y * w..(y + 1) * w];
        let out = &mut hrow[y * dw..(y + 1) * dw];
        pyr_down_row_edges(row, out, 0..1);
        pyr_down_row_edges(row, out, last + 1..dw);
        // Blocks of 16 columns from 1; the last block ends at `last`
        // and overlaps the one before (recomputing the same sums).
        let mut x = 1;
        loop {
            let x0 = x.min(last + 1 - 16);
            // Source pixels 2x0 − 2 ..= 2x0 + 32, all inside the row:
            // lane i of `a` holds pixels 2(x0 + i) − 2 and − 1, of `b`
            // 2(x0 + i) and + 1, the high byte of `c` 2(x0 + i) + 2.
            // SAFETY: 1 ≤ x0 ≤ last − 15 (w ≥ 40 makes last ≥ 18), so the
            // three 32-byte loads read bytes 2x0 − 2 ..= 2x0 + 32 ≤ 2·last + 2
            // ≤ w − 1 of `row`; unaligned loads need no alignment.
            let (a, b, c) = unsafe {
                let p = row.as_ptr().add(2 * x0 - 2);
                (
                    _mm256_loadu_si256(p as *const __m256i),
                    _mm256_loadu_si256(p.add(2) as *const __m256i),
                    _mm256_loadu_si256(p.add(3) as *const __m256i),
                )
            };
            let (em, om) = (_mm256_and_si256(a, lo), _mm256_srli_epi16::<8>(a));
            let (e0, o0) = (_mm256_and_si256(b, lo), _mm256_srli_epi16::<8>(b));
            let ep = _mm256_srli_epi16::<8>(c);
            let fours = _mm256_slli_epi16::<2>(_mm256_add_epi16(om, o0));
            let six = _mm256_add_epi16(_mm256_slli_epi16::<2>(e0), _mm256_slli_epi16::<1>(e0));
            let s = _mm256_add_epi16(_mm256_add_epi16(em, ep), _mm256_add_epi16(fours, six));
            // SAFETY: columns x0 .. x0 + 16 ≤ last + 1 ≤ dw of this output row.
            unsafe { _mm256_storeu_si256(out.as_mut_ptr().add(x0) as *mut __m256i, s) };
            if x0 + 16 > last {
                break;
            }
            x += 16;
        }
    }
    pyr_down_columns(&hrow, dw, h)
}

/// [`Deriv::compute`] compiled for AVX2, so that its 16-bit loops run
/// sixteen columns at a time.
#[target_feature(enable = "avx2")]
pub(super) fn deriv_avx2(level: &Level) -> Deriv {
    Deriv::compute(level)
}
