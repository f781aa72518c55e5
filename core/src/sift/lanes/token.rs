//! The [`Lanes`] token trait, the [`Kernel`]s written over it, and the
//! macro that fills in a width's one-intrinsic methods; shared by the
//! dispatch in `lanes` and the ISA files beside it.

/// The width, the vector types and the [`Lanes`] methods that are one
/// intrinsic each, from a table that names the intrinsic per method: `ff`
/// for (F, F) → F, `fff` for the FMA, `cmp` for (F, F) → M, `mm` for
/// (M, M) → M, `ii` for (I, I) → I, then the loads, stores, splats and the
/// i32 → f32 conversion.
macro_rules! one_intrinsic_each {
    (N = $n:expr, F = $f:ty, I = $i:ty, M = $m:ty; ff: $($ff:ident = $ffi:expr),*; fff: $($fff:ident = $fffi:expr),*;
     cmp: $($cmp:ident = $cmpi:expr),*; mm: $($mm:ident = $mmi:expr),*; ii: $($ii:ident = $iii:expr),*;
     load = $load:expr, store = $store:expr, store_i = $store_i:expr, splat = $splat:expr, splat_i = $splat_i:expr,
     to_f = $to_f:expr;) => {
        const N: usize = $n;
        type F = $f;
        type I = $i;
        type M = $m;
        $(#[inline(always)] #[allow(unused_unsafe)] fn $ff(self, a: Self::F, b: Self::F) -> Self::F {
            // SAFETY: a token exists only where the CPU has its instructions.
            unsafe { $ffi(a, b) }
        })*
        $(#[inline(always)] #[allow(unused_unsafe)] fn $fff(self, a: Self::F, b: Self::F, c: Self::F) -> Self::F {
            // SAFETY: as above.
            unsafe { $fffi(a, b, c) }
        })*
        $(#[inline(always)] #[allow(unused_unsafe)] fn $cmp(self, a: Self::F, b: Self::F) -> Self::M {
            // SAFETY: as above.
            unsafe { $cmpi(a, b) }
        })*
        $(#[inline(always)] #[allow(unused_unsafe)] fn $mm(self, a: Self::M, b: Self::M) -> Self::M {
            // SAFETY: as above.
            unsafe { $mmi(a, b) }
        })*
        $(#[inline(always)] #[allow(unused_unsafe)] fn $ii(self, a: Self::I, b: Self::I) -> Self::I {
            // SAFETY: as above.
            unsafe { $iii(a, b) }
        })*
        #[inline(always)]
        unsafe fn load(self, p: *const f32) -> Self::F {
            // SAFETY: the token's instructions; p..p + N readable (the caller's promise).
            unsafe { $load(p.cast()) }
        }
        #[inline(always)]
        unsafe fn store(self, p: *mut f32, v: Self::F) {
            // SAFETY: the token's instructions; p..p + N writable (the caller's promise).
            unsafe { $store(p.cast(), v) }
        }
        #[inline(always)]
        unsafe fn store_i(self, p: *mut i32, v: Self::I) {
            // SAFETY: as `store`.
            unsafe { $store_i(p.cast(), v) }
        }
        #[inline(always)]
        #[allow(unused_unsafe)]
        fn splat(self, v: f32) -> Self::F {
            // SAFETY: the token's instructions.
            unsafe { $splat(v) }
        }
        #[inline(always)]
        #[allow(unused_unsafe)]
        fn splat_i(self, v: i32) -> Self::I {
            // SAFETY: the token's instructions.
            unsafe { $splat_i(v) }
        }
        #[inline(always)]
        #[allow(unused_unsafe)]
        fn to_f(self, v: Self::I) -> Self::F {
            // SAFETY: the token's instructions.
            unsafe { $to_f(v) }
        }
    };
}

/// The vector operations of the SIFT kernels.
pub(crate) trait Lanes: Copy {
    /// Lanes per vector.
    const N: usize;
    /// N f32.
    type F: Copy;
    /// N i32.
    type I: Copy;
    /// The lanes a comparison holds for.
    type M: Copy;

    fn splat(self, v: f32) -> Self::F;
    /// # Safety
    /// `p..p + N` is readable.
    unsafe fn load(self, p: *const f32) -> Self::F;
    /// # Safety
    /// `p..p + N` is writable.
    unsafe fn store(self, p: *mut f32, v: Self::F);
    fn add(self, a: Self::F, b: Self::F) -> Self::F;
    fn sub(self, a: Self::F, b: Self::F) -> Self::F;
    fn mul(self, a: Self::F, b: Self::F) -> Self::F;
    /// `a·b + c` with one rounding (OpenCV's `v_fma` in the AVX2 and
    /// AVX-512 builds).
    fn fma(self, a: Self::F, b: Self::F, c: Self::F) -> Self::F;
    /// The larger of `a` and `b`; the inputs are never NaN.
    fn max(self, a: Self::F, b: Self::F) -> Self::F;
    fn min(self, a: Self::F, b: Self::F) -> Self::F;

    fn gt(self, a: Self::F, b: Self::F) -> Self::M;
    fn lt(self, a: Self::F, b: Self::F) -> Self::M;
    fn ge(self, a: Self::F, b: Self::F) -> Self::M;
    fn le(self, a: Self::F, b: Self::F) -> Self::M;
    fn and(self, a: Self::M, b: Self::M) -> Self::M;
    fn or(self, a: Self::M, b: Self::M) -> Self::M;
    /// Bit l set where lane l holds.
    fn bits(self, m: Self::M) -> u32;

    fn splat_i(self, v: i32) -> Self::I;
    /// `floor(v)` as i32 (`cvFloor`; v is in range).
    fn floor(self, v: Self::F) -> Self::I;
    /// i32 → f32, exact for the small values here.
    fn to_f(self, v: Self::I) -> Self::F;
    fn add_i(self, a: Self::I, b: Self::I) -> Self::I;
    fn mul_i(self, a: Self::I, b: Self::I) -> Self::I;
    /// `o + n` where `o < 0`, `o − n` where `o ≥ n`: the orientation bin
    /// wrapped into `0..n`.
    fn wrap(self, o: Self::I, n: Self::I) -> Self::I;
    /// # Safety
    /// `p..p + N` is writable.
    unsafe fn store_i(self, p: *mut i32, v: Self::I);
    /// Stores the lanes set in `keep`, in lane order, from `p` on.
    ///
    /// # Safety
    /// `p..p + N` is writable (only the first `keep.count_ones()` values
    /// are meant; the rest may be overwritten).
    unsafe fn compress_store(self, p: *mut f32, keep: u32, v: Self::F);
}

/// A kernel generic over the vector width, working in blocks of `L::N`.
/// `apply` must be `#[inline(always)]`, so that [`run`] compiles it inside
/// each ISA's `#[target_feature]` function.
pub(crate) trait Kernel {
    /// Whole blocks from `start` on; returns where it stopped (the next
    /// narrower width, then the caller's scalar loop, go on from there).
    fn apply<L: Lanes>(&mut self, l: L, start: usize) -> usize;
}
