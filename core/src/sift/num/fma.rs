//! The fused multiply-add with a single rounding that OpenCV's AVX2 kernels
//! and GCC's contraction use (docs/fidelity.md §SIFT-0, §SIFT-15): natively
//! the hardware instruction; on WebAssembly, which has none, an exact
//! emulation, or the engine's `relaxed_madd` where it proves fused.

/// A fused multiply-add with a single rounding: `a * b + c`.
///
/// OpenCV's AVX2 kernels and GCC's contraction fuse exactly where docs/fidelity.md says
/// `fma`, so a separate multiply and add would be off by an ulp there.
/// On x86-64 with FMA compiled in this is one instruction; elsewhere native
/// targets call the C library's `fmaf` (hardware via ifunc on glibc).
#[cfg(not(target_arch = "wasm32"))]
#[inline(always)]
pub fn fma(a: f32, b: f32, c: f32) -> f32 {
    a.mul_add(b, c)
}

/// WebAssembly has no fused multiply-add, and `mul_add` there is a slow
/// software routine. The product of two f32 is exact in f64 (48-bit
/// significand), so only the final addition rounds: we add in f64 with
/// round-to-odd (TwoSum gives the exact error) and then round once to f32.
/// Round-to-odd in a format with >= 2 extra bits makes the double rounding
/// equal to a single correct rounding.
///
/// The relaxed-SIMD build uses the engine's `relaxed_madd` instead where it
/// is fused ([`relaxed_madd_is_fused`]): the same single rounding.
#[cfg(target_arch = "wasm32")]
#[inline(always)]
pub fn fma(a: f32, b: f32, c: f32) -> f32 {
    #[cfg(feature = "relaxed-simd")]
    if relaxed_madd_is_fused() {
        return fused_madd(a, b, c);
    }
    fma_emulated(a, b, c)
}

/// One lane of `f32x4.relaxed_madd`. Inlined into the callers compiled with
/// relaxed SIMD (`with_hw_fma!`), a call elsewhere.
#[cfg(all(target_arch = "wasm32", feature = "relaxed-simd"))]
#[target_feature(enable = "relaxed-simd")]
#[inline]
pub fn fused_madd(a: f32, b: f32, c: f32) -> f32 {
    use core::arch::wasm32::*;
    f32x4_extract_lane::<0>(f32x4_relaxed_madd(f32x4_splat(a), f32x4_splat(b), f32x4_splat(c)))
}

/// The f64 round-to-odd emulation of [`fma`], exposed so native tests can
/// check it against the hardware instruction.
#[inline(always)]
pub fn fma_emulated(a: f32, b: f32, c: f32) -> f32 {
    let p = a as f64 * b as f64;
    let c = c as f64;
    let s = p + c;
    // Rounding the f64 sum to f32 can only differ from rounding the exact
    // value when the sum landed exactly on an f32 halfway point (the low 29
    // significand bits are 1000...0) — f32 midpoints are f64 values, so
    // rounding to f64 can reach one but never cross it. Only then (and for
    // f32-subnormal magnitudes, where the mask does not apply) is the exact
    // error needed. This keeps the common path at five f64 operations. A zero
    // sum is exact (two floats cannot cancel to below the f64 subnormals),
    // so it takes the common path too: black image areas blur to zeros.
    if s.to_bits() & 0x1FFF_FFFF != 0x1000_0000 && (s.abs() >= f32::MIN_POSITIVE as f64 || s == 0.0) {
        return s as f32;
    }
    // TwoSum: err is the exact rounding error of s = p + c.
    let bb = s - p;
    let err = (p - (s - bb)) + (c - bb);
    let mut bits = s.to_bits();
    if err != 0.0 && bits & 1 == 0 && s.is_finite() {
        // s was rounded; move it one ulp towards the exact value and make it odd.
        if (err > 0.0) == (s > 0.0) {
            bits += 1;
        } else {
            bits -= 1;
        }
    }
    f64::from_bits(bits) as f32
}

/// [`fma_emulated`] on four lanes with WebAssembly SIMD (`b` per lane too:
/// a splat for the blur's weights): the same f64 product and sum per lane,
/// rounded to f32 together; a lane whose sum needs the exact error (an f32
/// halfway point, an f32-subnormal magnitude) sends the four lanes through
/// the scalar function, so results are identical.
#[cfg(target_arch = "wasm32")]
#[inline(always)]
pub fn fma_emulated_x4(
    a: core::arch::wasm32::v128,
    b: core::arch::wasm32::v128,
    c: core::arch::wasm32::v128,
) -> core::arch::wasm32::v128 {
    use core::arch::wasm32::*;
    let high = |v: v128| i32x4_shuffle::<2, 3, 0, 1>(v, v);
    let lo = f64x2_add(f64x2_mul(f64x2_promote_low_f32x4(a), f64x2_promote_low_f32x4(b)), f64x2_promote_low_f32x4(c));
    let hi = f64x2_add(
        f64x2_mul(f64x2_promote_low_f32x4(high(a)), f64x2_promote_low_f32x4(high(b))),
        f64x2_promote_low_f32x4(high(c)),
    );
    // Both tests on the four sums' words at once, as integers (half the
    // operations of testing each f64 pair). Halfway: the low 29 bits are
    // 0x1000_0000, so the low word shifted left by 3 is i32::MIN.
    let halfway = i32x4_eq(i32x4_shl(i32x4_shuffle::<0, 2, 4, 6>(lo, hi), 3), i32x4_splat(i32::MIN));
    // f32-subnormal: 0 < |s| < 2^-126, that is, the high word without its
    // sign (shifted out) is below 2^-126's, 0x3810_0000 << 1, and not zero.
    // A zero high word is a zero sum: a nonzero sum of f32 products and f32
    // values is at least 2^-298, far above the f64 subnormals.
    let magnitude = i32x4_shl(i32x4_shuffle::<1, 3, 5, 7>(lo, hi), 1);
    let tiny = u32x4_lt(i32x4_sub(magnitude, i32x4_splat(1)), u32x4_splat(0x7020_0000 - 1));
    if v128_any_true(v128_or(halfway, tiny)) {
        let lanes = |v: v128| {
            [
                f32x4_extract_lane::<0>(v),
                f32x4_extract_lane::<1>(v),
                f32x4_extract_lane::<2>(v),
                f32x4_extract_lane::<3>(v),
            ]
        };
        let (a, b, c) = (lanes(a), lanes(b), lanes(c));
        return f32x4(
            fma_emulated(a[0], b[0], c[0]),
            fma_emulated(a[1], b[1], c[1]),
            fma_emulated(a[2], b[2], c[2]),
            fma_emulated(a[3], b[3], c[3]),
        );
    }
    i32x4_shuffle::<0, 1, 4, 5>(f32x4_demote_f64x2_zero(lo), f32x4_demote_f64x2_zero(hi))
}

/// How this build computes SIFT's fused multiply-adds (the blur's are most
/// of wasm SIFT's time), for the app to show next to its SIFT timings.
pub fn fma_engine() -> &'static str {
    #[cfg(all(target_arch = "wasm32", feature = "relaxed-simd"))]
    return if relaxed_madd_is_fused() {
        "relaxed SIMD: the engine's fused multiply-add"
    } else {
        "SIMD128: exact multiply-add emulation (this engine's relaxed_madd is not fused)"
    };
    #[cfg(all(target_arch = "wasm32", not(feature = "relaxed-simd")))]
    return "SIMD128: exact multiply-add emulation";
    #[cfg(not(target_arch = "wasm32"))]
    "native fused multiply-add"
}

/// Whether this engine's `f32x4.relaxed_madd` is a fused multiply-add.
///
/// Relaxed SIMD lets an engine compute `relaxed_madd(a, b, c)` either fused
/// (one rounding, OpenCV's FMA) or as a multiply then an add (two). V8
/// fuses it on CPUs with FMA, and the build with the `relaxed-simd` feature
/// then uses it as SIFT's one-instruction FMA. The probe asks a case where
/// the two differ, on every lane: (1 + 2⁻¹²)² − (1 + 2⁻¹¹) is 2⁻²⁴ fused but
/// 0 unfused (the product's 2⁻²⁴ is a tie that rounds away). Anything but
/// the fused answer keeps the exact emulation.
#[cfg(all(target_arch = "wasm32", feature = "relaxed-simd"))]
pub fn relaxed_madd_is_fused() -> bool {
    use core::sync::atomic::{AtomicU8, Ordering};
    // 0: not probed yet, 1: fused, 2: not fused.
    static FUSED: AtomicU8 = AtomicU8::new(0);
    match FUSED.load(Ordering::Relaxed) {
        1 => true,
        2 => false,
        _ => {
            // A wasm module is validated whole before it runs, so calling a
            // relaxed-simd function is safe: this build only loads where
            // relaxed SIMD validates (www/worker.js checks before choosing it).
            let fused = probe_relaxed_madd();
            FUSED.store(if fused { 1 } else { 2 }, Ordering::Relaxed);
            fused
        }
    }
}

#[cfg(all(target_arch = "wasm32", feature = "relaxed-simd"))]
#[target_feature(enable = "relaxed-simd")]
fn probe_relaxed_madd() -> bool {
    use core::arch::wasm32::*;
    let a = 1.0 + f32::EPSILON * 2048.0; // 1 + 2^-12
    let c = -(1.0 + f32::EPSILON * 4096.0); // -(1 + 2^-11)
                                            // black_box: the answer must come from the engine, not from LLVM folding.
    let (a, c) = (core::hint::black_box(f32x4_splat(a)), core::hint::black_box(f32x4_splat(c)));
    let got = f32x4_relaxed_madd(a, a, c);
    let want = f32x4_splat(f32::EPSILON / 2.0); // 2^-24
                                                // Bitwise: all four lanes must hold exactly 2^-24.
    i32x4_all_true(i32x4_eq(got, want))
}

/// Runs `$body` (an expression whose callees are all `#[inline(always)]`)
/// compiled with AVX2+FMA when the CPU has them, so every [`fma`] inside is
/// one instruction instead of a call to the C library's `fmaf`; target
/// features do not reach functions that are not inlined, hence the macro.
/// In the wasm relaxed-SIMD build the body is compiled with relaxed SIMD,
/// so that [`fused_madd`] inlines into each [`fma`] there.
#[macro_export]
#[doc(hidden)]
macro_rules! with_hw_fma {
    ($ret:ty, $body:expr) => {{
        #[cfg(target_arch = "x86_64")]
        {
            #[target_feature(enable = "avx2,fma")]
            fn fast<F: FnOnce() -> $ret>(f: F) -> $ret {
                f()
            }
            if $crate::simd::avx2_fma() {
                // Outside the unsafe block, so the block covers only the call.
                let body = || $body;
                // SAFETY: the CPU supports the features `fast` is compiled for.
                unsafe { fast(body) }
            } else {
                $body
            }
        }
        #[cfg(all(target_arch = "wasm32", feature = "relaxed-simd"))]
        {
            // The relaxed-SIMD build: compiled with relaxed SIMD so that each
            // `fma` inside inlines to one `relaxed_madd` when the engine fuses it.
            #[target_feature(enable = "relaxed-simd")]
            fn fast<F: FnOnce() -> $ret>(f: F) -> $ret {
                f()
            }
            fast(|| $body)
        }
        #[cfg(not(any(target_arch = "x86_64", all(target_arch = "wasm32", feature = "relaxed-simd"))))]
        {
            $body
        }
    }};
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn emulated_fma_equals_hardware_fma() {
        // Hard cases: products whose f64 sum lands on an f32 rounding midpoint.
        let mut state = 0x2545F4914F6CDD1Du64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        let mut checked = 0;
        for _ in 0..2_000_000 {
            let r = next();
            let a = f32::from_bits((r as u32 & 0x807F_FFFF) | 0x3F00_0000);
            let b = f32::from_bits(((r >> 32) as u32 & 0x807F_FFFF) | 0x3F00_0000);
            let c = -(a * b) + f32::from_bits((next() as u32 & 0x807F_FFFF) | 0x3300_0000);
            assert_eq!(fma_emulated(a, b, c).to_bits(), a.mul_add(b, c).to_bits(), "{a} {b} {c}");
            checked += 1;
        }
        assert_eq!(checked, 2_000_000);
        // A midpoint case: 1 + 2^-24 + tiny must round up, double rounding would not.
        let a = 1.0f32 + f32::EPSILON;
        assert_eq!(fma_emulated(a, a, -1.0).to_bits(), a.mul_add(a, -1.0).to_bits());
        // (1 + 2^-12)^2 = 1 + 2^-11 + 2^-24 is an f32 halfway point; + 2^-80
        // vanishes in the f64 sum, so a plain f64 add would round to even
        // (down) where the fused result rounds up.
        let (h, tiny) = (1.0f32 + 2f32.powi(-12), 2f32.powi(-80));
        assert_eq!(fma_emulated(h, h, tiny).to_bits(), h.mul_add(h, tiny).to_bits());
        assert_ne!(((h as f64 * h as f64) + tiny as f64) as f32, h.mul_add(h, tiny));
    }
}
