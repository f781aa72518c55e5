//! glibc's `powf(2, y)` for the keypoint size (docs/fidelity.md §SIFT-7).

/// `powf(2.0f, y)` bit for bit as glibc computes it for the keypoint size
/// (docs/fidelity.md §SIFT-7 asks for glibc's powf). Natively we call it; WebAssembly's libm
/// powf is another algorithm (1-ulp differences), so there we evaluate
/// glibc's own method: for x = 2 its log2 step is exactly 1.0 (table entry
/// invc = 1, logc = 0), leaving `exp2_inline(y)`: a 32-entry table of
/// 2^(j/32) and a cubic, in doubles, with the FMAs of glibc's FMA variant.
#[inline]
pub fn pow2f(y: f32) -> f32 {
    #[cfg(not(target_arch = "wasm32"))]
    {
        2f32.powf(y)
    }
    #[cfg(target_arch = "wasm32")]
    {
        pow2f_glibc(y)
    }
}

/// Correctly rounded 2^(j/32) with j<<47 subtracted (so the exponent can be
/// added back as an integer), the table of glibc's exp2f/powf.
#[cfg(any(target_arch = "wasm32", test))]
const EXP2F_TAB: [u64; 32] = [
    0x3ff0000000000000,
    0x3fefd9b0d3158574,
    0x3fefb5586cf9890f,
    0x3fef9301d0125b51,
    0x3fef72b83c7d517b,
    0x3fef54873168b9aa,
    0x3fef387a6e756238,
    0x3fef1e9df51fdee1,
    0x3fef06fe0a31b715,
    0x3feef1a7373aa9cb,
    0x3feedea64c123422,
    0x3feece086061892d,
    0x3feebfdad5362a27,
    0x3feeb42b569d4f82,
    0x3feeab07dd485429,
    0x3feea47eb03a5585,
    0x3feea09e667f3bcd,
    0x3fee9f75e8ec5f74,
    0x3feea11473eb0187,
    0x3feea589994cce13,
    0x3feeace5422aa0db,
    0x3feeb737b0cdc5e5,
    0x3feec49182a3f090,
    0x3feed503b23e255d,
    0x3feee89f995ad3ad,
    0x3feeff76f2fb5e47,
    0x3fef199bdd85529c,
    0x3fef3720dcef9069,
    0x3fef5818dcfba487,
    0x3fef7c97337b9b5f,
    0x3fefa4afa2a490da,
    0x3fefd0765b6e4540,
];

/// glibc's `powf(2.0f, y)` for the finite, moderate y SIFT uses.
#[cfg(any(target_arch = "wasm32", test))]
pub fn pow2f_glibc(y: f32) -> f32 {
    const SHIFT: f64 = 211106232532992.0; // 0x1.8p52 / 32: rounds to multiples of 1/32
    const C0: f64 = f64::from_bits(0x3fac6af84b912394); // 0x1.c6af84b912394p-5
    const C1: f64 = f64::from_bits(0x3fcebfce50fac4f3); // 0x1.ebfce50fac4f3p-3
    const C2: f64 = f64::from_bits(0x3fe62e42ff0c52d6); // 0x1.62e42ff0c52d6p-1
    let xd = y as f64; // y * log2(2), and log2_inline(2) is exactly 1.0
    let kd = xd + SHIFT;
    let ki = kd.to_bits();
    let kd = kd - SHIFT;
    let r = xd - kd;
    let t = EXP2F_TAB[(ki % 32) as usize].wrapping_add(ki << 47);
    let s = f64::from_bits(t);
    let z = C0.mul_add(r, C1);
    let r2 = r * r;
    let yv = C2.mul_add(r, 1.0);
    let yv = z.mul_add(r2, yv);
    (yv * s) as f32
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn glibc_powf_port_matches_glibc_over_sifts_range() {
        // Every y = (layer + xi) / 3 SIFT can produce: layer 1..=3, |xi| < 0.5.
        let (lo, hi) = (0.15f32.to_bits(), 1.2f32.to_bits());
        let mut differ = 0u32;
        for b in lo..=hi {
            let y = f32::from_bits(b);
            if 2f32.powf(y).to_bits() != pow2f_glibc(y).to_bits() {
                differ += 1;
            }
        }
        assert_eq!(differ, 0, "of {} values", hi - lo + 1);
    }
}
