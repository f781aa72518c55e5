//! Border extrapolation shared by the SIFT blur and the Lucas-Kanade pyramid.

/// `borderInterpolate(p, len, BORDER_REFLECT_101)`: reflect without repeating
/// the edge pixel (`…, 2, 1 | 0, 1, 2, … | len−2, len−3, …`), and again until
/// the index lands inside, as OpenCV does for borders wider than the image
/// (SIFT's top octaves are narrower than the kernel radius,
/// docs/fidelity.md §SIFT-3; LK pads by 21 pixels, §VO-2.2). A one-pixel axis
/// always reads index 0.
#[inline]
pub(crate) fn reflect101(mut p: isize, len: usize) -> usize {
    if len == 1 {
        return 0;
    }
    let len = len as isize;
    while p < 0 || p >= len {
        p = if p < 0 { -p } else { 2 * (len - 1) - p };
    }
    p as usize
}

#[cfg(test)]
mod tests {
    use super::reflect101;

    #[test]
    fn reflect101_repeats_on_tiny_images() {
        assert_eq!(reflect101(-1, 5), 1);
        assert_eq!(reflect101(5, 5), 3);
        assert_eq!(reflect101(-7, 3), 1); // 7 -> 4-7=-3 -> 3 -> 1
        assert_eq!(reflect101(4, 1), 0);
    }
}
