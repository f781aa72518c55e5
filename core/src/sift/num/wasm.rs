//! WebAssembly has no autovectorised FMA (and [`fma`](super::fma) there
//! branches per call), so the gradient kernels of orientation and descriptors
//! get four lanes by hand: [`fast_atan2_deg`](super::fast_atan2_deg),
//! [`magnitude`](super::magnitude) and [`exp32f`](super::exp32f) with the
//! same operations in the same order per lane, so the same bits (§SIFT-12). Each runs
//! with the engine's fused `relaxed_madd` where the relaxed build found it
//! fused, else with [`fma_emulated_x4`]; the caller finishes the last
//! `len % 4` samples with the scalar kernels. Also the bounds-checked vector
//! loads and stores every wasm kernel of SIFT uses.

use super::atan::{ATAN_EPS, ATAN_P1, ATAN_P3, ATAN_P5, ATAN_P7};
use super::exp::{EXP_A1, EXP_A2, EXP_A3, EXP_A4, EXP_TAB};
use super::fma_emulated_x4;
use core::arch::wasm32::*;

/// Four f32 from `s[i..i + 4]` as one v128 (bounds-checked), for the wasm
/// kernels of the blur and the extremum scan.
#[inline(always)]
pub(crate) fn load4(s: &[f32], i: usize) -> v128 {
    let s = &s[i..i + 4];
    // SAFETY: `s` holds exactly four f32; v128_load needs no alignment.
    unsafe { v128_load(s.as_ptr().cast()) }
}

/// Stores one v128 as the four f32 of `d[i..i + 4]` (bounds-checked).
#[inline(always)]
pub(crate) fn store4(d: &mut [f32], i: usize, v: v128) {
    let d = &mut d[i..i + 4];
    // SAFETY: `d` holds exactly four f32; v128_store needs no alignment.
    unsafe { v128_store(d.as_mut_ptr().cast(), v) }
}

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
                    $kernel($($arg,)* $crate::sift::num::wasm::Fused::new())
                }
                return fused($($arg),*);
            }
            $kernel($($arg,)* $crate::sift::num::wasm::Emulated)
        }
    };
}

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
        let (x, y) = (load4(dxs, k), load4(dys, k));
        store4(oris, k, atan2_deg(y, x, f));
        store4(mags, k, f32x4_sqrt(f.fma(x, x, f32x4_mul(y, y))));
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
        store4(out, k, exp(load4(args, k), f));
        k += 4;
    }
    k
}

dispatch_fma4! {
    /// `exp32f` of `args[0..]` (a multiple of 4) into `out`; returns how many.
    pub fn exp32f(args: &[f32], out: &mut [f32]) -> usize = exp_with
}
