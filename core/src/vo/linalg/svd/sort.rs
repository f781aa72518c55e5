//! The singular values' order, shared by the plain SVD and its AVX2 lanes.

/// JacobiSVD's selection sort of the singular values, descending (§VO-3.5
/// step 4): only a strictly greater value moves the pick, so the first of
/// equal maxima wins. `swap(i, j)` moves what goes with values i and j.
#[inline(always)]
pub(super) fn sort_descending(w: &mut [f64], mut swap: impl FnMut(usize, usize)) {
    let n = w.len();
    for i in 0..n.saturating_sub(1) {
        let mut j = i;
        for k in i + 1..n {
            if w[j] < w[k] {
                j = k;
            }
        }
        if i != j {
            w.swap(i, j);
            swap(i, j);
        }
    }
}
