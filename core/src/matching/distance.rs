//! L2 distances between SIFT descriptors as `cv2.BFMatcher()` computes them
//! (spec §16): OpenCV sums float squares, but every partial sum of squared
//! 0..255 differences is an integer below 2^24, so the float sum is exact and
//! equals this integer sum; the distance is its correctly rounded f32 sqrt.

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

/// Distances from one query descriptor to every train descriptor.
pub fn distance_row(q: &[u8; 128], train: &[[u8; 128]], out: &mut Vec<f32>) {
    out.clear();
    out.reserve(train.len());
    #[cfg(target_arch = "x86_64")]
    if std::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU has AVX2, the only feature the function enables.
        unsafe { distance_row_avx2(q, train, out) };
        return;
    }
    distance_row_generic(q, train, out);
}

#[inline(always)]
fn distance_row_generic(q: &[u8; 128], train: &[[u8; 128]], out: &mut Vec<f32>) {
    out.extend(train.iter().map(|t| distance(q, t)));
}

// The same loop compiled with AVX2 so the 128 squared differences vectorise
// to 16-bit multiply-adds (vpmaddwd), chosen at run time.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn distance_row_avx2(q: &[u8; 128], train: &[[u8; 128]], out: &mut Vec<f32>) {
    distance_row_generic(q, train, out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exact_integer_distance() {
        let a = [0u8; 128];
        let mut b = [0u8; 128];
        b[0] = 3;
        b[127] = 4;
        assert_eq!(distance_sq(&a, &b), 25);
        assert_eq!(distance(&a, &b), 5.0);
        assert_eq!(distance(&[255; 128], &a), (128.0f32 * 65025.0).sqrt());
        let mut row = Vec::new();
        distance_row(&a, &[a, b, [255; 128]], &mut row);
        assert_eq!(row, vec![0.0, 5.0, 8_323_200f32.sqrt()]);
        assert_eq!(row[2], 2884.9956);
    }
}
