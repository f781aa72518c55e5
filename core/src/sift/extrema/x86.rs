//! The scan's x86 kernels: the DoG rows of six Gaussian rows at once (AVX2)
//! and the 26-neighbour test against the separable 3×3×3 maximum and
//! minimum (AVX-512 and AVX2): docs/fidelity.md §SIFT-5 and §SIFT-6.

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

/// Returns the first column not examined (the scalar tail starts there).
///
/// v ≥ all 26 neighbours ⟺ v ≥ the maximum of the 3×3×3 block (v itself
/// included), and that maximum is separable: first per column over the
/// nine rows (three layers × three rows), then over three columns. That
/// is 10 max and 10 min per pixel instead of 26 of each.
///
/// # Safety
/// Every row extends one pixel past `cols.end`, and `cols.start >= 1`.
#[target_feature(enable = "avx512f")]
pub unsafe fn row_extrema_avx512(
    rows: &[&[f32]; 9],
    thr: f32,
    cols: std::ops::Range<usize>,
    out: &mut Vec<usize>,
    col_max: &mut Vec<f32>,
    col_min: &mut Vec<f32>,
) -> usize {
    let p: [*const f32; 9] = std::array::from_fn(|i| rows[i].as_ptr());
    let w = cols.end + 1;
    col_max.resize(w + 16, 0.0);
    col_min.resize(w + 16, 0.0);
    let (cmax, cmin) = (col_max.as_mut_ptr(), col_min.as_mut_ptr());
    let mut x = cols.start - 1;
    while x < w {
        let valid: __mmask16 = if w - x >= 16 { 0xFFFF } else { (1u16 << (w - x)) - 1 };
        // SAFETY: the valid lanes are columns x..min(x + 16, w), which every
        // row holds (the caller's promise) and the scratch rows too (w + 16).
        unsafe {
            let first = _mm512_maskz_loadu_ps(valid, p[0].add(x));
            let (mut mx, mut mn) = (first, first);
            for &row in &p[1..] {
                let s = _mm512_maskz_loadu_ps(valid, row.add(x));
                mx = _mm512_max_ps(mx, s);
                mn = _mm512_min_ps(mn, s);
            }
            _mm512_mask_storeu_ps(cmax.add(x), valid, mx);
            _mm512_mask_storeu_ps(cmin.add(x), valid, mn);
        }
        x += 16;
    }
    let (hi, lo) = (_mm512_set1_ps(thr), _mm512_set1_ps(-thr));
    let mut x = cols.start;
    while x + 16 <= cols.end {
        // SAFETY: columns x..x + 16 <= cols.end of the centre row exist.
        let v = unsafe { _mm512_loadu_ps(p[4].add(x)) };
        let (pos, neg) = (_mm512_cmp_ps_mask::<_CMP_GT_OQ>(v, hi), _mm512_cmp_ps_mask::<_CMP_LT_OQ>(v, lo));
        if pos | neg != 0 {
            // SAFETY: columns x − 1 ..= x + 16 <= w of the scratch rows
            // (w + 16 floats each, written up to w above).
            let (mx, mn) = unsafe {
                (
                    _mm512_max_ps(
                        _mm512_max_ps(_mm512_loadu_ps(cmax.add(x - 1)), _mm512_loadu_ps(cmax.add(x))),
                        _mm512_loadu_ps(cmax.add(x + 1)),
                    ),
                    _mm512_min_ps(
                        _mm512_min_ps(_mm512_loadu_ps(cmin.add(x - 1)), _mm512_loadu_ps(cmin.add(x))),
                        _mm512_loadu_ps(cmin.add(x + 1)),
                    ),
                )
            };
            let hit = (pos & _mm512_cmp_ps_mask::<_CMP_GE_OQ>(v, mx)) | (neg & _mm512_cmp_ps_mask::<_CMP_LE_OQ>(v, mn));
            let mut mask = hit as u32;
            while mask != 0 {
                out.push(x + mask.trailing_zeros() as usize);
                mask &= mask - 1;
            }
        }
        x += 16;
    }
    x
}

/// [`row_extrema_avx512`]'s separable test with AVX2, eight lanes,
/// without branches but the rare hit. It replaced a test that took the
/// threshold first, then the 8 neighbours in the layer, then the 18
/// around it, leaving a block as soon as no pixel could still be an
/// extremum: with the threshold at 1 most blocks went on, and those
/// data-dependent branches cost more than the max and min the separable
/// form always does (the test fell from 10.0 to 7.7 % of a
/// view_trajectory profile; CPU time −5.7 %, median of 6 rounds).
///
/// # Safety
/// As [`row_extrema_avx512`].
#[target_feature(enable = "avx2")]
pub unsafe fn row_extrema_avx2_separable(
    rows: &[&[f32]; 9],
    thr: f32,
    cols: std::ops::Range<usize>,
    out: &mut Vec<usize>,
    col_max: &mut Vec<f32>,
    col_min: &mut Vec<f32>,
) -> usize {
    let p: [*const f32; 9] = std::array::from_fn(|i| rows[i].as_ptr());
    // Columns cols.start − 1 ..= cols.end: every row holds them.
    let (x0, w) = (cols.start - 1, cols.end + 1);
    col_max.resize(w + 8, 0.0);
    col_min.resize(w + 8, 0.0);
    let (cmax, cmin) = (col_max.as_mut_ptr(), col_min.as_mut_ptr());
    // SAFETY: called with x0 <= x and x + 8 <= w: columns every row holds
    // (the caller's promise), inside the scratch rows (w + 8).
    let column = |x: usize| unsafe {
        let first = _mm256_loadu_ps(p[0].add(x));
        let (mut mx, mut mn) = (first, first);
        for &row in &p[1..] {
            let s = _mm256_loadu_ps(row.add(x));
            mx = _mm256_max_ps(mx, s);
            mn = _mm256_min_ps(mn, s);
        }
        _mm256_storeu_ps(cmax.add(x), mx);
        _mm256_storeu_ps(cmin.add(x), mn);
    };
    if w - x0 < 8 {
        return cols.start;
    }
    let mut x = x0;
    while x + 8 <= w {
        column(x);
        x += 8;
    }
    if x < w {
        column(w - 8);
    }
    let (hi, lo) = (_mm256_set1_ps(thr), _mm256_set1_ps(-thr));
    // Room for a hit in every column, so the loop writes hits through a
    // pointer: with `push` (which may call the allocator) in it, the
    // loop's pointers and thresholds were reloaded from the stack on
    // every block.
    out.reserve(cols.end - cols.start);
    let (hits, mut n) = (out.as_mut_ptr(), out.len());
    let mut x = cols.start;
    while x + 8 <= cols.end {
        // SAFETY: columns x..x + 8 <= cols.end of the centre row, and
        // x − 1 ..= x + 8 <= w of the scratch rows (w + 8 floats each,
        // written up to w above).
        let (v, mx, mn) = unsafe {
            (
                _mm256_loadu_ps(p[4].add(x)),
                _mm256_max_ps(
                    _mm256_max_ps(_mm256_loadu_ps(cmax.add(x - 1)), _mm256_loadu_ps(cmax.add(x))),
                    _mm256_loadu_ps(cmax.add(x + 1)),
                ),
                _mm256_min_ps(
                    _mm256_min_ps(_mm256_loadu_ps(cmin.add(x - 1)), _mm256_loadu_ps(cmin.add(x))),
                    _mm256_loadu_ps(cmin.add(x + 1)),
                ),
            )
        };
        let (pos, neg) = (_mm256_cmp_ps::<_CMP_GT_OQ>(v, hi), _mm256_cmp_ps::<_CMP_LT_OQ>(v, lo));
        let hit = _mm256_or_ps(
            _mm256_and_ps(pos, _mm256_cmp_ps::<_CMP_GE_OQ>(v, mx)),
            _mm256_and_ps(neg, _mm256_cmp_ps::<_CMP_LE_OQ>(v, mn)),
        );
        let mut mask = _mm256_movemask_ps(hit) as u32;
        while mask != 0 {
            // SAFETY: n − len <= the columns examined so far < the room
            // reserved, so slot n is inside the buffer.
            unsafe { hits.add(n).write(x + mask.trailing_zeros() as usize) };
            n += 1;
            mask &= mask - 1;
        }
        x += 8;
    }
    // SAFETY: the first n entries are written (n − len ≤ the columns
    // examined ≤ the room reserved).
    unsafe { out.set_len(n) };
    x
}
