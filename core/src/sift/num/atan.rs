//! OpenCV's `fastAtan2` in degrees (docs/fidelity.md §SIFT-12): OpenCV's own
//! polynomial, the same in every lane and in the scalar fallback.

use super::fma;

// fastAtan2 coefficients: the f32 product of each coefficient and (f32)(180/pi).
pub(super) const ATAN_P1: f32 = f32::from_bits(0x4265226F);
pub(super) const ATAN_P3: f32 = f32::from_bits(0xC19556EE);
pub(super) const ATAN_P5: f32 = f32::from_bits(0x410E9FBF);
pub(super) const ATAN_P7: f32 = f32::from_bits(0xC0228AD9);
pub(super) const ATAN_EPS: f32 = f32::from_bits(0x25800000); // 2^-52 as f32

/// OpenCV's `fastAtan2` in degrees, [0, 360) (docs/fidelity.md §SIFT-12; no IPP, fully exact).
#[inline(always)]
pub fn fast_atan2_deg(y: f32, x: f32) -> f32 {
    let ax = x.abs();
    let ay = y.abs();
    let c = ax.min(ay) / (ax.max(ay) + ATAN_EPS);
    let c2 = c * c;
    let mut a = fma(fma(fma(c2, ATAN_P7, ATAN_P5), c2, ATAN_P3), c2, ATAN_P1) * c;
    // "90 − a unless ax ≥ ay" (§SIFT-12), negated as written: OpenCV's
    // `ax >= ay` test, whose else branch a NaN would take too.
    #[allow(clippy::neg_cmp_op_on_partial_ord)]
    if !(ax >= ay) {
        a = 90.0 - a;
    }
    if x < 0.0 {
        a = 180.0 - a;
    }
    if y < 0.0 {
        a = 360.0 - a;
    }
    a
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fast_atan2_quadrants() {
        assert_eq!(fast_atan2_deg(0.0, 1.0), 0.0);
        assert!((fast_atan2_deg(1.0, 1.0) - 45.0).abs() < 0.01);
        assert!((fast_atan2_deg(1.0, -1.0) - 135.0).abs() < 0.01);
        assert!((fast_atan2_deg(-1.0, -1.0) - 225.0).abs() < 0.01);
        assert!((fast_atan2_deg(-1.0, 1.0) - 315.0).abs() < 0.01);
    }
}
