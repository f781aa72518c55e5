//! The exact scalar kernels OpenCV's SIFT is built from (docs/fidelity.md
//! §SIFT-12), and the one fused multiply-add every stage uses.

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
    let hard = |s: v128| {
        let midpoint = i64x2_eq(v128_and(s, i64x2_splat(0x1FFF_FFFF)), i64x2_splat(0x1000_0000));
        let tiny =
            v128_and(f64x2_lt(f64x2_abs(s), f64x2_splat(f32::MIN_POSITIVE as f64)), f64x2_ne(s, f64x2_splat(0.0)));
        v128_or(midpoint, tiny)
    };
    if v128_any_true(v128_or(hard(lo), hard(hi))) {
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

/// Four f32 from `s[i..i + 4]` as one v128 (bounds-checked), for the wasm
/// kernels of the blur and the extremum scan.
#[cfg(target_arch = "wasm32")]
#[inline(always)]
pub(crate) fn load4(s: &[f32], i: usize) -> core::arch::wasm32::v128 {
    let s = &s[i..i + 4];
    // SAFETY: `s` holds exactly four f32; v128_load needs no alignment.
    unsafe { core::arch::wasm32::v128_load(s.as_ptr().cast()) }
}

/// Stores one v128 as the four f32 of `d[i..i + 4]` (bounds-checked).
#[cfg(target_arch = "wasm32")]
#[inline(always)]
pub(crate) fn store4(d: &mut [f32], i: usize, v: core::arch::wasm32::v128) {
    let d = &mut d[i..i + 4];
    // SAFETY: `d` holds exactly four f32; v128_store needs no alignment.
    unsafe { core::arch::wasm32::v128_store(d.as_mut_ptr().cast(), v) }
}

/// `cvRound` on floats: `lrintf` in the default rounding mode.
#[inline(always)]
pub fn rne(x: f32) -> i32 {
    x.round_ties_even() as i32
}

/// `cvRound` on doubles.
#[inline(always)]
pub fn rne64(x: f64) -> i32 {
    x.round_ties_even() as i32
}

/// `cvFloor`.
#[inline(always)]
pub fn floor(x: f32) -> i32 {
    x.floor() as i32
}

pub const FLT_EPSILON: f32 = f32::EPSILON;

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
            unsafe fn fast<F: FnOnce() -> $ret>(f: F) -> $ret {
                f()
            }
            if $crate::simd::avx2_fma() {
                // SAFETY: the CPU supports the features `fast` is compiled for.
                unsafe { fast(|| $body) }
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

/// Orientation (degrees), magnitude and Gaussian weight of every gradient
/// sample, each kernel run over the whole array as OpenCV's `hal` calls do,
/// so the loops vectorise (inlined into the FMA-enabled callers).
#[inline(always)]
pub fn gradient_samples(dxs: &[f32], dys: &[f32], w_args: &[f32]) -> (Vec<f32>, Vec<f32>, Vec<f32>) {
    let (oris, mags) = gradient_directions(dxs, dys);
    let mut wts = vec![0f32; w_args.len()];
    #[cfg(target_arch = "wasm32")]
    let done = x4::exp32f(w_args, &mut wts);
    #[cfg(not(target_arch = "wasm32"))]
    let done = 0;
    for (w, &a) in wts.iter_mut().zip(w_args).skip(done) {
        *w = exp32f(a);
    }
    (oris, mags, wts)
}

/// [`exp32f`] of every argument into `out` (as long), eight or four lanes
/// at a time where the CPU has them.
#[inline(always)]
pub fn exp32f_into(args: &[f32], out: &mut [f32]) {
    #[cfg(target_arch = "x86_64")]
    let done = if crate::simd::avx2_fma() {
        // SAFETY: the CPU has AVX2 and FMA.
        unsafe { x8::exp32f(args, out) }
    } else {
        0
    };
    #[cfg(target_arch = "wasm32")]
    let done = x4::exp32f(args, out);
    #[cfg(not(any(target_arch = "x86_64", target_arch = "wasm32")))]
    let done = 0;
    for (w, &a) in out.iter_mut().zip(args).skip(done) {
        *w = exp32f(a);
    }
}

/// The orientation (degrees) and magnitude of every gradient sample.
#[inline(always)]
pub fn gradient_directions(dxs: &[f32], dys: &[f32]) -> (Vec<f32>, Vec<f32>) {
    let (mut oris, mut mags) = (Vec::new(), Vec::new());
    gradient_directions_into(dxs, dys, &mut oris, &mut mags);
    (oris, mags)
}

/// [`gradient_directions`] into buffers the caller reuses.
#[inline(always)]
pub fn gradient_directions_into(dxs: &[f32], dys: &[f32], oris: &mut Vec<f32>, mags: &mut Vec<f32>) {
    let len = dxs.len();
    oris.clear();
    oris.resize(len, 0.0);
    mags.clear();
    mags.resize(len, 0.0);
    // Slices, so the loops below vectorise (through `&mut Vec` each store
    // might move the buffer pointer, which is then reloaded every sample).
    let (oris, mags) = (&mut oris[..], &mut mags[..]);
    #[cfg(target_arch = "wasm32")]
    let done = x4::gradient_directions(dxs, dys, oris, mags);
    #[cfg(not(target_arch = "wasm32"))]
    let done = 0;
    for k in done..len {
        oris[k] = fast_atan2_deg(dys[k], dxs[k]);
    }
    for k in done..len {
        mags[k] = magnitude(dxs[k], dys[k]);
    }
}

/// WebAssembly has no autovectorised FMA (and [`fma`] there branches per
/// call), so the gradient kernels of orientation and descriptors get four
/// lanes by hand: [`fast_atan2_deg`], [`magnitude`] and [`exp32f`] with the
/// same operations in the same order per lane, so the same bits. Each runs
/// with the engine's fused `relaxed_madd` where the relaxed build found it
/// fused, else with [`fma_emulated_x4`]; the caller finishes the last
/// `len % 4` samples with the scalar kernels.
#[cfg(target_arch = "wasm32")]
pub(crate) mod x4 {
    use super::{fma_emulated_x4, load4 as load, store4 as store};
    use super::{ATAN_EPS, ATAN_P1, ATAN_P3, ATAN_P5, ATAN_P7, EXP_A1, EXP_A2, EXP_A3, EXP_A4, EXP_TAB};
    use core::arch::wasm32::*;

    /// A four-lane multiply-add with one rounding.
    pub trait Fma4: Copy {
        fn fma(self, a: v128, b: v128, c: v128) -> v128;
    }

    /// [`fma_emulated_x4`]: every engine.
    #[derive(Clone, Copy)]
    pub struct Emulated;

    impl Fma4 for Emulated {
        #[inline(always)]
        fn fma(self, a: v128, b: v128, c: v128) -> v128 {
            fma_emulated_x4(a, b, c)
        }
    }

    /// The engine's `relaxed_madd`, only handed out by `dispatch_fma4!`
    /// after the probe found it fused.
    #[cfg(feature = "relaxed-simd")]
    #[derive(Clone, Copy)]
    pub struct Fused(());

    #[cfg(feature = "relaxed-simd")]
    impl Fma4 for Fused {
        #[inline(always)]
        fn fma(self, a: v128, b: v128, c: v128) -> v128 {
            relaxed_madd(a, b, c)
        }
    }

    #[cfg(feature = "relaxed-simd")]
    #[target_feature(enable = "relaxed-simd")]
    #[inline]
    fn relaxed_madd(a: v128, b: v128, c: v128) -> v128 {
        f32x4_relaxed_madd(a, b, c)
    }

    #[cfg(feature = "relaxed-simd")]
    impl Fused {
        /// Only after [`super::relaxed_madd_is_fused`] said so.
        #[inline(always)]
        pub(crate) fn new() -> Fused {
            Fused(())
        }
    }

    /// Defines `fn $name(args) -> R` that runs `$kernel(args, fma)` with the
    /// engine's fused FMA where this build and engine have it, else with the
    /// emulation. The fused call is compiled with relaxed SIMD so that each
    /// `relaxed_madd` inlines into the kernel's loop.
    macro_rules! dispatch_fma4 {
        ($(#[$m:meta])* $vis:vis fn $name:ident($($arg:ident: $ty:ty),*) -> $ret:ty = $kernel:path) => {
            $(#[$m])*
            $vis fn $name($($arg: $ty),*) -> $ret {
                #[cfg(feature = "relaxed-simd")]
                if $crate::sift::num::relaxed_madd_is_fused() {
                    #[target_feature(enable = "relaxed-simd")]
                    fn fused($($arg: $ty),*) -> $ret {
                        $kernel($($arg,)* $crate::sift::num::x4::Fused::new())
                    }
                    return fused($($arg),*);
                }
                $kernel($($arg,)* $crate::sift::num::x4::Emulated)
            }
        };
    }
    pub(crate) use dispatch_fma4;

    /// `fast_atan2_deg` lane by lane; the three branches become selects.
    #[inline(always)]
    pub fn atan2_deg(y: v128, x: v128, f: impl Fma4) -> v128 {
        let fma = |a, b, c| f.fma(a, b, c);
        let k = f32x4_splat;
        let (ax, ay) = (f32x4_abs(x), f32x4_abs(y));
        let c = f32x4_div(f32x4_min(ax, ay), f32x4_add(f32x4_max(ax, ay), k(ATAN_EPS)));
        let c2 = f32x4_mul(c, c);
        let a = f32x4_mul(fma(fma(fma(c2, k(ATAN_P7), k(ATAN_P5)), c2, k(ATAN_P3)), c2, k(ATAN_P1)), c);
        let a = v128_bitselect(a, f32x4_sub(k(90.0), a), f32x4_ge(ax, ay));
        let a = v128_bitselect(f32x4_sub(k(180.0), a), a, f32x4_lt(x, k(0.0)));
        v128_bitselect(f32x4_sub(k(360.0), a), a, f32x4_lt(y, k(0.0)))
    }

    /// `exp32f` lane by lane; the table lookup is four scalar loads.
    #[inline(always)]
    pub fn exp(x: v128, f: impl Fma4) -> v128 {
        let fma = |a, b, c| f.fma(a, b, c);
        let k = f32x4_splat;
        let x = f32x4_mul(f32x4_min(f32x4_max(x, k(-2079.4417)), k(2079.4417)), k(f32::from_bits(0x42B8AA3B)));
        let xi = i32x4_trunc_sat_f32x4(f32x4_nearest(x));
        let xf = f32x4_mul(f32x4_sub(x, f32x4_convert_i32x4(xi)), k(0.015625));
        let e = i32x4_min(i32x4_max(i32x4_add(i32x4_shr(xi, 6), i32x4_splat(127)), i32x4_splat(0)), i32x4_splat(255));
        let t = |i: u32| f32::from_bits(EXP_TAB[(i & 63) as usize]);
        let tab = f32x4(
            t(u32x4_extract_lane::<0>(xi)),
            t(u32x4_extract_lane::<1>(xi)),
            t(u32x4_extract_lane::<2>(xi)),
            t(u32x4_extract_lane::<3>(xi)),
        );
        let tab = f32x4_mul(tab, i32x4_shl(e, 23));
        let mut z = f32x4_add(xf, k(EXP_A1));
        z = fma(z, xf, k(EXP_A2));
        z = fma(z, xf, k(EXP_A3));
        z = fma(z, xf, k(EXP_A4));
        f32x4_mul(z, tab)
    }

    #[inline(always)]
    fn directions_with(dxs: &[f32], dys: &[f32], oris: &mut [f32], mags: &mut [f32], f: impl Fma4) -> usize {
        let n = dxs.len().min(dys.len()).min(oris.len()).min(mags.len());
        let mut k = 0;
        while k + 4 <= n {
            let (x, y) = (load(dxs, k), load(dys, k));
            store(oris, k, atan2_deg(y, x, f));
            store(mags, k, f32x4_sqrt(f.fma(x, x, f32x4_mul(y, y))));
            k += 4;
        }
        k
    }

    dispatch_fma4! {
        /// Orientations and magnitudes of samples `0..` (a multiple of 4); returns how many.
        pub fn gradient_directions(dxs: &[f32], dys: &[f32], oris: &mut [f32], mags: &mut [f32]) -> usize = directions_with
    }

    #[inline(always)]
    fn exp_with(args: &[f32], out: &mut [f32], f: impl Fma4) -> usize {
        let n = args.len().min(out.len());
        let mut k = 0;
        while k + 4 <= n {
            store(out, k, exp(load(args, k), f));
            k += 4;
        }
        k
    }

    dispatch_fma4! {
        /// `exp32f` of `args[0..]` (a multiple of 4) into `out`; returns how many.
        pub fn exp32f(args: &[f32], out: &mut [f32]) -> usize = exp_with
    }
}

// fastAtan2 coefficients: the f32 product of each coefficient and (f32)(180/pi).
const ATAN_P1: f32 = f32::from_bits(0x4265226F);
const ATAN_P3: f32 = f32::from_bits(0xC19556EE);
const ATAN_P5: f32 = f32::from_bits(0x410E9FBF);
const ATAN_P7: f32 = f32::from_bits(0xC0228AD9);
const ATAN_EPS: f32 = f32::from_bits(0x25800000); // 2^-52 as f32

/// OpenCV's `fastAtan2` in degrees, [0, 360) (docs/fidelity.md §SIFT-12; no IPP, fully exact).
#[inline(always)]
pub fn fast_atan2_deg(y: f32, x: f32) -> f32 {
    let ax = x.abs();
    let ay = y.abs();
    let c = ax.min(ay) / (ax.max(ay) + ATAN_EPS);
    let c2 = c * c;
    let mut a = fma(fma(fma(c2, ATAN_P7, ATAN_P5), c2, ATAN_P3), c2, ATAN_P1) * c;
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

/// `cv::hal::magnitude32f` with IPP disabled: `sqrtf(fma(x, x, y*y))`.
#[inline(always)]
pub fn magnitude(x: f32, y: f32) -> f32 {
    fma(x, x, y * y).sqrt()
}

const EXP_TAB: [u32; 64] = [
    0x3c1e707a, 0x3c202a27, 0x3c21e8a3, 0x3c23abfb, 0x3c25743e, 0x3c274179, 0x3c2913b9, 0x3c2aeb0d, 0x3c2cc783,
    0x3c2ea92a, 0x3c30900f, 0x3c327c41, 0x3c346dcf, 0x3c3664c9, 0x3c38613c, 0x3c3a6339, 0x3c3c6acf, 0x3c3e780d,
    0x3c408b03, 0x3c42a3c1, 0x3c44c258, 0x3c46e6d7, 0x3c491150, 0x3c4b41d2, 0x3c4d786e, 0x3c4fb536, 0x3c51f83b,
    0x3c54418e, 0x3c569140, 0x3c58e764, 0x3c5b440b, 0x3c5da748, 0x3c60112d, 0x3c6281cc, 0x3c64f939, 0x3c677786,
    0x3c69fcc6, 0x3c6c890c, 0x3c6f1c6e, 0x3c71b6fd, 0x3c7458ce, 0x3c7701f6, 0x3c79b289, 0x3c7c6a9b, 0x3c7f2a41,
    0x3c80f8c9, 0x3c826050, 0x3c83cbc2, 0x3c853b29, 0x3c86ae90, 0x3c882602, 0x3c89a18b, 0x3c8b2136, 0x3c8ca50f,
    0x3c8e2d21, 0x3c8fb977, 0x3c914a1f, 0x3c92df23, 0x3c947891, 0x3c961674, 0x3c97b8d8, 0x3c995fcb, 0x3c9b0b59,
    0x3c9cbb8f,
];
const EXP_A1: f32 = f32::from_bits(0x40B7AA3D);
const EXP_A2: f32 = f32::from_bits(0x41C6BB64);
const EXP_A3: f32 = f32::from_bits(0x428F5AD6);
const EXP_A4: f32 = f32::from_bits(0x42CED13A);

/// `cv::hal::exp32f` with IPP disabled (docs/fidelity.md §SIFT-12). The default wheel uses
/// IPP's closed-source exp instead, which no formula reproduces; this is the
/// reason angles can differ from that wheel at the 1e-5 degree level.
#[inline(always)]
pub fn exp32f(x: f32) -> f32 {
    let x = x.clamp(-2079.4417, 2079.4417) * f32::from_bits(0x42B8AA3B);
    let xi = rne(x);
    let xf = (x - xi as f32) * 0.015625;
    let e = ((xi >> 6) + 127).clamp(0, 255) as u32;
    let tab = f32::from_bits(EXP_TAB[(xi & 63) as usize]) * f32::from_bits(e << 23);
    let mut z = xf + EXP_A1;
    z = fma(z, xf, EXP_A2);
    z = fma(z, xf, EXP_A3);
    z = fma(z, xf, EXP_A4);
    z * tab
}

/// [`exp32f`] eight lanes at a time with AVX2: the same operations in the
/// same order per lane (the table read by a gather), so the same bits.
#[cfg(target_arch = "x86_64")]
pub(crate) mod x8 {
    use super::{EXP_A1, EXP_A2, EXP_A3, EXP_A4, EXP_TAB};
    use std::arch::x86_64::*;

    /// `exp32f` of `args[0..]` (whole groups of eight) into `out`; returns
    /// how many.
    ///
    /// # Safety
    /// The CPU must have AVX2 and FMA.
    #[target_feature(enable = "avx2,fma")]
    pub unsafe fn exp32f(args: &[f32], out: &mut [f32]) -> usize {
        let n = args.len().min(out.len()) / 8 * 8;
        let k = _mm256_set1_ps;
        let ki = _mm256_set1_epi32;
        let mut i = 0;
        while i < n {
            let x = _mm256_loadu_ps(args.as_ptr().add(i));
            let x = _mm256_mul_ps(
                _mm256_min_ps(_mm256_max_ps(x, k(-2079.4417)), k(2079.4417)),
                k(f32::from_bits(0x42B8AA3B)),
            );
            // rne: ties to even, as the current rounding mode does.
            let xi = _mm256_cvtps_epi32(_mm256_round_ps::<{ _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC }>(x));
            let xf = _mm256_mul_ps(_mm256_sub_ps(x, _mm256_cvtepi32_ps(xi)), k(0.015625));
            let e = _mm256_min_epi32(
                _mm256_max_epi32(_mm256_add_epi32(_mm256_srai_epi32::<6>(xi), ki(127)), ki(0)),
                ki(255),
            );
            let t = _mm256_i32gather_ps::<4>(EXP_TAB.as_ptr() as *const f32, _mm256_and_si256(xi, ki(63)));
            let tab = _mm256_mul_ps(t, _mm256_castsi256_ps(_mm256_slli_epi32::<23>(e)));
            let mut z = _mm256_add_ps(xf, k(EXP_A1));
            z = _mm256_fmadd_ps(z, xf, k(EXP_A2));
            z = _mm256_fmadd_ps(z, xf, k(EXP_A3));
            z = _mm256_fmadd_ps(z, xf, k(EXP_A4));
            _mm256_storeu_ps(out.as_mut_ptr().add(i), _mm256_mul_ps(z, tab));
            i += 8;
        }
        n
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The AVX2 `exp32f` against the scalar one, bit for bit, over the
    /// arguments the orientation weights take (−d²/(2σ²), down to about −9)
    /// and far beyond, both clamps included.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn vector_exp32f_is_the_scalar_one() {
        if !crate::simd::avx2_fma() {
            return;
        }
        let args: Vec<f32> = (0..40_000)
            .map(|i| -2500.0 + i as f32 * 0.0625 + (i % 7) as f32 * 1e-3)
            .chain([0.0, -0.0, 3000.0, -3000.0])
            .collect();
        let mut out = vec![0f32; args.len()];
        // SAFETY: the CPU has AVX2 and FMA (checked above).
        let done = unsafe { x8::exp32f(&args, &mut out) };
        assert_eq!(done, args.len() / 8 * 8);
        for (k, (&a, &o)) in args.iter().zip(&out).enumerate().take(done) {
            assert_eq!(o.to_bits(), crate::with_hw_fma!(f32, exp32f(a)).to_bits(), "exp32f({a}) at {k}");
        }
    }

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

    #[test]
    fn fast_atan2_quadrants() {
        assert_eq!(fast_atan2_deg(0.0, 1.0), 0.0);
        assert!((fast_atan2_deg(1.0, 1.0) - 45.0).abs() < 0.01);
        assert!((fast_atan2_deg(1.0, -1.0) - 135.0).abs() < 0.01);
        assert!((fast_atan2_deg(-1.0, -1.0) - 225.0).abs() < 0.01);
        assert!((fast_atan2_deg(-1.0, 1.0) - 315.0).abs() < 0.01);
    }

    #[test]
    fn exp32f_is_close_to_exp() {
        for &x in &[0.0f32, -0.5, -1.0, -3.25, -10.0, -20.0] {
            let r = exp32f(x);
            assert!(((r - x.exp()) / x.exp()).abs() < 1e-6, "{x}: {r} vs {}", x.exp());
        }
        assert_eq!(exp32f(0.0), 1.0);
    }
}
