//! `hypot` as the wheel's Jacobi SVD gets it: glibc's (2.35 and later) on
//! x86-64, Borges' "improved algorithm for hypot(a, b)" in its form without
//! FMA (docs/fidelity.md §VO-3.5). Written out here, not taken from the
//! platform's C library, so that every build — the CLI on glibc, musl or
//! macOS, and the app in WebAssembly, whose `f64::hypot` is a port of musl's
//! — rounds exactly as OpenCV does on Linux, and the CLI and the app pick the
//! same RANSAC models.

/// Inputs above this are scaled down by [`SCALE`] before the kernel.
pub(super) const LARGE: f64 = f64::from_bits(0x5fe0_0000_0000_0000); // 2^511
/// Smaller inputs below this are scaled up by 1/[`SCALE`].
pub(super) const TINY: f64 = f64::from_bits(0x2340_0000_0000_0000); // 2^-459
/// A power of two, so the scaling itself is exact.
const SCALE: f64 = f64::from_bits(0x1a70_0000_0000_0000); // 2^-600
/// Below `ax·EPS` the smaller input is under half an ulp of the larger.
pub(super) const EPS: f64 = f64::from_bits(0x3c90_0000_0000_0000); // 2^-54

/// √(ax² + ay²) for `ax ≥ ay ≥ 0` in range: the rounded root, then one
/// correction step from the exact residual, computed without FMA by splitting
/// the square differently when the two inputs are close (`h ≤ 2·ay`).
#[inline(always)]
fn kernel(ax: f64, ay: f64) -> f64 {
    let h = (ax * ax + ay * ay).sqrt();
    let (t1, t2);
    if h <= 2.0 * ay {
        let delta = h - ay;
        t1 = ax * (2.0 * delta - ax);
        t2 = (delta - 2.0 * (ax - ay)) * delta;
    } else {
        let delta = h - ax;
        t1 = 2.0 * delta * (ax - 2.0 * ay);
        t2 = (4.0 * delta - ay) * ay + delta * delta;
    }
    h - (t1 + t2) / (2.0 * h)
}

/// glibc's `hypot(x, y)`, bit for bit: +∞ if either input is infinite (even
/// beside a NaN), NaN for a NaN, `ax + ay` when the smaller input cannot
/// change the larger, and the kernel otherwise, on inputs scaled by a power
/// of two when they would overflow or underflow.
pub fn hypot(x: f64, y: f64) -> f64 {
    if !x.is_finite() || !y.is_finite() {
        return if x.is_infinite() || y.is_infinite() { f64::INFINITY } else { x + y };
    }
    let (x, y) = (x.abs(), y.abs());
    let (ax, ay) = if x < y { (y, x) } else { (x, y) };
    if ax > LARGE {
        if ay <= ax * EPS {
            return ax + ay;
        }
        return kernel(ax * SCALE, ay * SCALE) / SCALE;
    }
    if ay < TINY {
        if ax >= ay / EPS {
            return ax + ay;
        }
        return kernel(ax / SCALE, ay / SCALE) * SCALE;
    }
    if ay <= ax * EPS {
        return ax + ay;
    }
    kernel(ax, ay)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Values that reach every branch: exact squares, close and distant
    /// pairs, both scaling ranges, subnormals, zeros, infinities and NaN.
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    fn cases() -> Vec<(f64, f64)> {
        let mut rng = crate::testutil::XorShift64::new(0x2545_f491_4f6c_dd1d);
        let mut next = move || rng.next_u64();
        let mut v = vec![
            (3.0, 4.0),
            (0.0, 0.0),
            (-0.0, 5.0),
            (f64::INFINITY, f64::NAN),
            (f64::NAN, f64::NEG_INFINITY),
            (f64::NAN, 1.0),
            (f64::MAX, f64::MAX),
            (f64::MIN_POSITIVE, 5e-324),
            (1e300, 1e-300),
        ];
        for _ in 0..200_000 {
            let r = next();
            // Any finite exponent for x; y within 2^±70 of it, or anywhere.
            let x = f64::from_bits(r & 0x7fef_ffff_ffff_ffff) * if r >> 63 == 1 { -1.0 } else { 1.0 };
            let k = next();
            let y = if k & 1 == 0 {
                x * f64::from_bits(0x3ff0_0000_0000_0000 | (k >> 12)) * 2f64.powi((k >> 1 & 127) as i32 - 70)
            } else {
                f64::from_bits(k & 0x7fef_ffff_ffff_ffff)
            };
            v.push((x, y));
        }
        v
    }

    /// On glibc (the C library the wheel calls), `f64::hypot` is the
    /// reference; elsewhere the platform's hypot is not glibc's, and the
    /// figures below still pin the algorithm.
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    #[test]
    fn equals_glibc_bit_for_bit() {
        for (x, y) in cases() {
            let (got, want) = (hypot(x, y), x.hypot(y));
            assert!(
                got.to_bits() == want.to_bits() || (got.is_nan() && want.is_nan()),
                "hypot({x:e}, {y:e}) = {got:e}, glibc {want:e}"
            );
        }
    }

    #[test]
    fn literal_values() {
        assert_eq!(hypot(3.0, -4.0), 5.0);
        assert_eq!(hypot(f64::NAN, f64::INFINITY), f64::INFINITY);
        assert!(hypot(f64::NAN, 0.0).is_nan());
        assert_eq!(hypot(f64::MAX, 0.0), f64::MAX);
        assert_eq!(hypot(5e-324, 0.0), 5e-324);
        // glibc rounds these down where musl's hypot (Rust's `f64::hypot` in
        // WebAssembly) rounds up, as it does on 14 % of random pairs in [0.5, 2):
        // the last bit is the point of this module.
        assert_eq!(hypot(1.062503875709812, 0.9424562645852748), 1.4202599397837006);
        assert_eq!(hypot(1.9362395387648645, 0.9061816171387203), 2.137799961342623);
    }
}
