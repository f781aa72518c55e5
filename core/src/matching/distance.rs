//! L2 distances between SIFT descriptors as `cv2.BFMatcher()` computes them
//! (docs/fidelity.md §SIFT-16): OpenCV sums float squares, but every partial sum of squared
//! 0..255 differences is an integer below 2^24, so the float sum is exact and
//! equals this integer sum; the distance is its correctly rounded f32 sqrt.
//!
//! The row kernels below compute that same integer sum with SIMD: bytes are
//! zero-extended to i16, subtracted (|d| <= 255), and squared-and-paired by a
//! 16-bit multiply-add into i32 lanes (2 * 255^2 per pair, 128 * 255^2 in
//! all, far below 2^31). Integer arithmetic is exact in any order, the i32 ->
//! f32 conversion is exact below 2^24 and the vector sqrt is IEEE correctly
//! rounded like `f32::sqrt`, so every kernel returns bit-identical distances.
//! Each kernel handles four train rows per pass so their four horizontal sums
//! share one reduction and one 4-wide sqrt; a remainder of < 4 rows takes the
//! scalar path.

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
    out.resize(train.len(), 0.0);
    distance_row_into(q, train, out);
}

/// [`distance_row`] into a slice of `train.len()` distances (the fastest
/// kernel the CPU supports). Extra `out` entries are left untouched.
pub fn distance_row_into(q: &[u8; 128], train: &[[u8; 128]], out: &mut [f32]) {
    let n = train.len().min(out.len());
    let (train, out) = (&train[..n], &mut out[..n]);
    #[cfg(target_arch = "x86_64")]
    {
        if std::is_x86_feature_detected!("avx512bw") && std::is_x86_feature_detected!("avx512vnni") {
            // SAFETY: the CPU has every feature the function enables.
            unsafe { x86::row_avx512_vnni(q, train, out) };
            return;
        }
        if std::is_x86_feature_detected!("avx512bw") {
            // SAFETY: as above.
            unsafe { x86::row_avx512(q, train, out) };
            return;
        }
        if std::is_x86_feature_detected!("avx2") {
            // SAFETY: as above.
            unsafe { x86::row_avx2(q, train, out) };
            return;
        }
    }
    #[cfg(all(target_arch = "wasm32", target_feature = "simd128"))]
    {
        wasm::row_simd128(q, train, out);
        return;
    }
    #[allow(unreachable_code)]
    row_generic(q, train, out)
}

/// The portable kernel (auto-vectorised where the target allows).
fn row_generic(q: &[u8; 128], train: &[[u8; 128]], out: &mut [f32]) {
    for (o, t) in out.iter_mut().zip(train) {
        *o = distance(q, t);
    }
}

/// Train descriptors with their squared norms |t|^2, computed once for all
/// the queries of a [`distance_rows`] batch.
pub struct TrainSet<'a> {
    rows: &'a [[u8; 128]],
    /// Only the x86 two-query kernels use the norms; elsewhere it is empty.
    #[cfg_attr(not(target_arch = "x86_64"), allow(dead_code))]
    norms: Vec<i32>,
}

impl<'a> TrainSet<'a> {
    pub fn new(rows: &'a [[u8; 128]]) -> Self {
        let norms = if cfg!(target_arch = "x86_64") { rows.iter().map(norm_sq).collect() } else { Vec::new() };
        TrainSet { rows, norms }
    }

    pub fn len(&self) -> usize {
        self.rows.len()
    }

    pub fn is_empty(&self) -> bool {
        self.rows.is_empty()
    }
}

/// |t|^2 = the sum of squares of the bytes, at most 128 * 255^2.
fn norm_sq(t: &[u8; 128]) -> i32 {
    t.iter().map(|&x| x as i32 * x as i32).sum()
}

/// Distances from each of several queries to every train descriptor, as
/// `out[i * train.len() + j]` = `distance(queries[i], train[j])`; `out` must
/// hold `queries.len() * train.len()` values (extra entries are left
/// untouched, missing ones are not computed).
///
/// Same values as [`distance_row`] per query, faster for many queries: with
/// AVX-512 two queries share each train row's loads, and the sum is taken as
/// |q|^2 + |t|^2 - 2 q.t with the train norms computed once, which needs one
/// multiply-add per 32 bytes and no subtraction (all three terms and the
/// result are exact integers below 2^31).
pub fn distance_rows(queries: &[[u8; 128]], train: &TrainSet, out: &mut [f32]) {
    let nt = train.len();
    if nt == 0 {
        return;
    }
    let nq = queries.len().min(out.len() / nt);
    let (queries, out) = (&queries[..nq], &mut out[..nq * nt]);
    #[cfg(target_arch = "x86_64")]
    {
        if nq >= 2 && std::is_x86_feature_detected!("avx512bw") {
            let vnni = std::is_x86_feature_detected!("avx512vnni");
            let mut q2 = queries.chunks_exact(2);
            let mut o2 = out.chunks_exact_mut(2 * nt);
            for (q, o) in (&mut q2).zip(&mut o2) {
                let (o0, o1) = o.split_at_mut(nt);
                // SAFETY: the CPU has every feature the functions enable.
                unsafe {
                    if vnni {
                        x86::rows2_avx512_vnni([&q[0], &q[1]], train.rows, &train.norms, [o0, o1]);
                    } else {
                        x86::rows2_avx512([&q[0], &q[1]], train.rows, &train.norms, [o0, o1]);
                    }
                }
            }
            for (q, o) in q2.remainder().iter().zip(o2.into_remainder().chunks_exact_mut(nt)) {
                distance_row_into(q, train.rows, o);
            }
            return;
        }
    }
    for (q, o) in queries.iter().zip(out.chunks_exact_mut(nt)) {
        distance_row_into(q, train.rows, o);
    }
}

#[cfg(target_arch = "x86_64")]
mod x86 {
    use std::arch::x86_64::*;

    /// The sums of the four i32 vectors' lanes, as lanes 0..3.
    ///
    /// Interleaving pairs of vectors and adding halves the lane count per
    /// step without a horizontal add: after the two unpack levels each 128-bit
    /// lane holds [a, b, c, d] partial sums, and the 128-bit lanes are then
    /// folded together.
    #[inline]
    #[target_feature(enable = "avx512bw")]
    unsafe fn hsum4_512(a: __m512i, b: __m512i, c: __m512i, d: __m512i) -> __m128i {
        let ab = _mm512_add_epi32(_mm512_unpacklo_epi32(a, b), _mm512_unpackhi_epi32(a, b));
        let cd = _mm512_add_epi32(_mm512_unpacklo_epi32(c, d), _mm512_unpackhi_epi32(c, d));
        let s = _mm512_add_epi32(_mm512_unpacklo_epi64(ab, cd), _mm512_unpackhi_epi64(ab, cd));
        let y = _mm256_add_epi32(_mm512_castsi512_si256(s), _mm512_extracti64x4_epi64::<1>(s));
        _mm_add_epi32(_mm256_castsi256_si128(y), _mm256_extracti128_si256::<1>(y))
    }

    /// 32 bytes at `p` zero-extended to 32 i16.
    #[inline]
    #[target_feature(enable = "avx512bw")]
    unsafe fn load_u8x32_as_i16(p: *const u8) -> __m512i {
        _mm512_cvtepu8_epi16(_mm256_loadu_si256(p as *const __m256i))
    }

    /// One AVX-512 row kernel per way of accumulating `d * d` pairs: the
    /// query stays in four registers as i16, each train row is four loads.
    macro_rules! avx512_row_kernel {
        ($(#[$doc:meta])* $name:ident, $features:literal, |$acc:ident, $d:ident| $mac:expr) => {
            $(#[$doc])*
            #[target_feature(enable = $features)]
            pub(super) unsafe fn $name(q: &[u8; 128], train: &[[u8; 128]], out: &mut [f32]) {
                let qp = q.as_ptr();
                let qv = [
                    load_u8x32_as_i16(qp),
                    load_u8x32_as_i16(qp.add(32)),
                    load_u8x32_as_i16(qp.add(64)),
                    load_u8x32_as_i16(qp.add(96)),
                ];
                // The 16 i32 lanes of partial sums of one row.
                let row = |t: &[u8; 128]| -> __m512i {
                    let tp = t.as_ptr();
                    let mut $acc = _mm512_setzero_si512();
                    for (k, &qk) in qv.iter().enumerate() {
                        let $d = _mm512_sub_epi16(qk, load_u8x32_as_i16(tp.add(32 * k)));
                        $acc = $mac;
                    }
                    $acc
                };
                let mut t4 = train.chunks_exact(4);
                let mut o4 = out.chunks_exact_mut(4);
                for (t, o) in (&mut t4).zip(&mut o4) {
                    let s = hsum4_512(row(&t[0]), row(&t[1]), row(&t[2]), row(&t[3]));
                    _mm_storeu_ps(o.as_mut_ptr(), _mm_sqrt_ps(_mm_cvtepi32_ps(s)));
                }
                super::row_generic(q, t4.remainder(), o4.into_remainder());
            }
        };
    }

    avx512_row_kernel!(
        /// AVX-512BW + VNNI: `vpdpwssd` squares, pairs and accumulates in one
        /// instruction.
        row_avx512_vnni,
        "avx512bw,avx512vnni",
        |acc, d| dpwssd(acc, d, d)
    );

    /// `acc + pairwise sums of a * b` (i16 -> i32) as one `vpdpwssd`. Written
    /// as asm because LLVM turns `_mm512_dpwssd_epi32` back into `vpmaddwd` +
    /// `vpaddd` here, one more uop per 32 bytes in the hottest loop.
    #[inline]
    #[target_feature(enable = "avx512bw,avx512vnni")]
    unsafe fn dpwssd(mut acc: __m512i, a: __m512i, b: __m512i) -> __m512i {
        std::arch::asm!(
            "vpdpwssd {acc}, {a}, {b}",
            acc = inout(zmm_reg) acc,
            a = in(zmm_reg) a,
            b = in(zmm_reg) b,
            options(pure, nomem, nostack, preserves_flags),
        );
        acc
    }

    /// Bytes `64h .. 64h + 64` of a descriptor as two i16 vectors: the even
    /// bytes (`w & 0xff` of each 16-bit word) and the odd bytes (`w >> 8`).
    /// Any fixed pairing of query and train bytes gives the same dot product,
    /// and this split costs one ALU op per 32 bytes (no shuffles).
    #[inline]
    #[target_feature(enable = "avx512bw")]
    unsafe fn even_odd(p: *const u8) -> (__m512i, __m512i) {
        let w = _mm512_loadu_si512(p as *const __m512i);
        (_mm512_and_si512(w, _mm512_set1_epi16(0xff)), _mm512_srli_epi16::<8>(w))
    }

    /// Two queries against every train row, four rows per pass, as
    /// |q|^2 + |t|^2 - 2 q.t: each train row is loaded and split once for
    /// both queries, and each 32 bytes of a pair is one multiply-add.
    macro_rules! avx512_rows2_kernel {
        ($(#[$doc:meta])* $name:ident, $features:literal, |$acc:ident, $a:ident, $b:ident| $mac:expr) => {
            $(#[$doc])*
            #[target_feature(enable = $features)]
            pub(super) unsafe fn $name(
                q: [&[u8; 128]; 2],
                train: &[[u8; 128]],
                norms: &[i32],
                out: [&mut [f32]; 2],
            ) {
                let n = train.len().min(norms.len()).min(out[0].len()).min(out[1].len());
                let split = |d: &[u8; 128]| {
                    let (e0, o0) = even_odd(d.as_ptr());
                    let (e1, o1) = even_odd(d.as_ptr().add(64));
                    [e0, o0, e1, o1]
                };
                let qv = [split(q[0]), split(q[1])];
                let qn = [_mm_set1_epi32(super::norm_sq(q[0])), _mm_set1_epi32(super::norm_sq(q[1]))];
                let mut j = 0;
                while j + 4 <= n {
                    let tv = [split(&train[j]), split(&train[j + 1]), split(&train[j + 2]), split(&train[j + 3])];
                    let tn = _mm_loadu_si128(norms.as_ptr().add(j) as *const __m128i);
                    for (qk, (qvk, qnk)) in qv.iter().zip(qn).enumerate() {
                        let dot = |t: &[__m512i; 4]| -> __m512i {
                            let mut $acc = _mm512_setzero_si512();
                            for (&$a, &$b) in qvk.iter().zip(t) {
                                $acc = $mac;
                            }
                            $acc
                        };
                        let d = hsum4_512(dot(&tv[0]), dot(&tv[1]), dot(&tv[2]), dot(&tv[3]));
                        let sq = _mm_sub_epi32(_mm_add_epi32(qnk, tn), _mm_slli_epi32::<1>(d));
                        let o = out[qk].as_mut_ptr().add(j);
                        _mm_storeu_ps(o, _mm_sqrt_ps(_mm_cvtepi32_ps(sq)));
                    }
                    j += 4;
                }
                for (qk, o) in out.into_iter().enumerate() {
                    super::row_generic(q[qk], &train[j..n], &mut o[j..n]);
                }
            }
        };
    }

    avx512_rows2_kernel!(
        /// AVX-512BW + VNNI (`vpdpwssd`).
        rows2_avx512_vnni,
        "avx512bw,avx512vnni",
        |acc, a, b| dpwssd(acc, a, b)
    );

    avx512_rows2_kernel!(
        /// AVX-512BW (`vpmaddwd` + `vpaddd`).
        rows2_avx512,
        "avx512bw",
        |acc, a, b| _mm512_add_epi32(acc, _mm512_madd_epi16(a, b))
    );

    avx512_row_kernel!(
        /// AVX-512BW without VNNI: `vpmaddwd` then `vpaddd`.
        row_avx512,
        "avx512bw",
        |acc, d| _mm512_add_epi32(acc, _mm512_madd_epi16(d, d))
    );

    /// [`hsum4_512`] for 256-bit vectors.
    #[inline]
    #[target_feature(enable = "avx2")]
    unsafe fn hsum4_256(a: __m256i, b: __m256i, c: __m256i, d: __m256i) -> __m128i {
        let ab = _mm256_add_epi32(_mm256_unpacklo_epi32(a, b), _mm256_unpackhi_epi32(a, b));
        let cd = _mm256_add_epi32(_mm256_unpacklo_epi32(c, d), _mm256_unpackhi_epi32(c, d));
        let s = _mm256_add_epi32(_mm256_unpacklo_epi64(ab, cd), _mm256_unpackhi_epi64(ab, cd));
        _mm_add_epi32(_mm256_castsi256_si128(s), _mm256_extracti128_si256::<1>(s))
    }

    /// AVX2: the query in eight registers as i16, `vpmaddwd` + `vpaddd`.
    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn row_avx2(q: &[u8; 128], train: &[[u8; 128]], out: &mut [f32]) {
        let ld = |p: *const u8| _mm256_cvtepu8_epi16(_mm_loadu_si128(p as *const __m128i));
        let qp = q.as_ptr();
        let qv: [__m256i; 8] = std::array::from_fn(|k| ld(qp.add(16 * k)));
        let row = |t: &[u8; 128]| -> __m256i {
            let tp = t.as_ptr();
            let mut acc = _mm256_setzero_si256();
            for (k, &qk) in qv.iter().enumerate() {
                let d = _mm256_sub_epi16(qk, ld(tp.add(16 * k)));
                acc = _mm256_add_epi32(acc, _mm256_madd_epi16(d, d));
            }
            acc
        };
        let mut t4 = train.chunks_exact(4);
        let mut o4 = out.chunks_exact_mut(4);
        for (t, o) in (&mut t4).zip(&mut o4) {
            let s = hsum4_256(row(&t[0]), row(&t[1]), row(&t[2]), row(&t[3]));
            _mm_storeu_ps(o.as_mut_ptr(), _mm_sqrt_ps(_mm_cvtepi32_ps(s)));
        }
        super::row_generic(q, t4.remainder(), o4.into_remainder());
    }
}

#[cfg(all(target_arch = "wasm32", target_feature = "simd128"))]
mod wasm {
    use core::arch::wasm32::*;

    /// Bytes `16k .. 16k + 16` of a descriptor, `k < 8`.
    #[inline(always)]
    fn load(d: &[u8; 128], k: usize) -> v128 {
        debug_assert!(k < 8);
        // SAFETY: 16 * k + 16 <= 128 bytes of `d` are readable; wasm loads
        // need no alignment.
        unsafe { v128_load(d.as_ptr().add(16 * k) as *const v128) }
    }

    /// simd128: the query as sixteen i16x8 vectors, `i32x4.dot_i16x8_s`
    /// squares and pairs the differences.
    pub(super) fn row_simd128(q: &[u8; 128], train: &[[u8; 128]], out: &mut [f32]) {
        let qv: [v128; 16] = std::array::from_fn(|k| {
            let b = load(q, k / 2);
            if k % 2 == 0 {
                u16x8_extend_low_u8x16(b)
            } else {
                u16x8_extend_high_u8x16(b)
            }
        });
        let row = |t: &[u8; 128]| -> v128 {
            let mut acc = i32x4_splat(0);
            for k in 0..8 {
                let b = load(t, k);
                let lo = i16x8_sub(qv[2 * k], u16x8_extend_low_u8x16(b));
                let hi = i16x8_sub(qv[2 * k + 1], u16x8_extend_high_u8x16(b));
                acc = i32x4_add(acc, i32x4_add(i32x4_dot_i16x8(lo, lo), i32x4_dot_i16x8(hi, hi)));
            }
            acc
        };
        let mut t4 = train.chunks_exact(4);
        let mut o4 = out.chunks_exact_mut(4);
        for (t, o) in (&mut t4).zip(&mut o4) {
            let (a, b, c, d) = (row(&t[0]), row(&t[1]), row(&t[2]), row(&t[3]));
            // The same two interleave-and-add levels as the x86 reduction.
            let ab = i32x4_add(i32x4_shuffle::<0, 4, 1, 5>(a, b), i32x4_shuffle::<2, 6, 3, 7>(a, b));
            let cd = i32x4_add(i32x4_shuffle::<0, 4, 1, 5>(c, d), i32x4_shuffle::<2, 6, 3, 7>(c, d));
            let s = i32x4_add(i64x2_shuffle::<0, 2>(ab, cd), i64x2_shuffle::<1, 3>(ab, cd));
            let r = f32x4_sqrt(f32x4_convert_i32x4(s));
            o[0] = f32x4_extract_lane::<0>(r);
            o[1] = f32x4_extract_lane::<1>(r);
            o[2] = f32x4_extract_lane::<2>(r);
            o[3] = f32x4_extract_lane::<3>(r);
        }
        super::row_generic(q, t4.remainder(), o4.into_remainder());
    }
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

    /// Deterministic pseudo-random descriptors.
    fn random_descriptors(n: usize, seed: u64) -> Vec<[u8; 128]> {
        let mut rng = crate::testutil::XorShift64::new(seed);
        (0..n).map(|_| std::array::from_fn(|_| rng.byte())).collect()
    }

    /// Descriptors at the edges of the range: all 0, all 255, one byte
    /// differing at every position, 0/255 alternating both ways.
    fn extreme_descriptors() -> Vec<[u8; 128]> {
        let mut v = vec![[0u8; 128], [255u8; 128]];
        for i in 0..128 {
            let mut a = [0u8; 128];
            a[i] = 255;
            v.push(a);
            let mut b = [255u8; 128];
            b[i] = 0;
            v.push(b);
            let mut c = [7u8; 128];
            c[i] = 8;
            v.push(c);
        }
        v.push(std::array::from_fn(|i| if i % 2 == 0 { 0 } else { 255 }));
        v.push(std::array::from_fn(|i| if i % 2 == 0 { 255 } else { 0 }));
        v
    }

    type Kernel = fn(&[u8; 128], &[[u8; 128]], &mut [f32]);

    /// Every kernel this machine can run, by name (plus the dispatcher).
    fn kernels() -> Vec<(&'static str, Kernel)> {
        let mut k: Vec<(&'static str, Kernel)> = vec![("generic", row_generic), ("dispatch", distance_row_into)];
        #[cfg(target_arch = "x86_64")]
        {
            if std::is_x86_feature_detected!("avx2") {
                // SAFETY (all three): only registered when the CPU has the features.
                k.push(("avx2", |q, t, o| unsafe { x86::row_avx2(q, t, o) }));
            }
            if std::is_x86_feature_detected!("avx512bw") {
                k.push(("avx512bw", |q, t, o| unsafe { x86::row_avx512(q, t, o) }));
                if std::is_x86_feature_detected!("avx512vnni") {
                    k.push(("avx512vnni", |q, t, o| unsafe { x86::row_avx512_vnni(q, t, o) }));
                }
            }
        }
        #[cfg(all(target_arch = "wasm32", target_feature = "simd128"))]
        k.push(("simd128", wasm::row_simd128));
        k
    }

    /// Each kernel against the scalar `distance_sq`, bit for bit, for every
    /// query against train sets of every length mod 4 (the remainder path).
    fn check_all_kernels(queries: &[[u8; 128]], train: &[[u8; 128]]) {
        for (name, kernel) in kernels() {
            for len in [0, 1, 2, 3, 4, 5, 6, 7, train.len()] {
                let t = &train[..len.min(train.len())];
                for q in queries {
                    let mut out = vec![-1.0f32; t.len()];
                    kernel(q, t, &mut out);
                    for (j, (o, tj)) in out.iter().zip(t).enumerate() {
                        let want = (distance_sq(q, tj) as f32).sqrt();
                        assert_eq!(o.to_bits(), want.to_bits(), "{name}: train {j} of {len}");
                    }
                }
            }
        }
    }

    #[test]
    fn kernels_match_scalar_on_random_descriptors() {
        let q = random_descriptors(17, 0x9e37_79b9_7f4a_7c15);
        let t = random_descriptors(203, 0x2545_f491_4f6c_dd1d);
        check_all_kernels(&q, &t);
    }

    #[test]
    fn kernels_match_scalar_on_extreme_descriptors() {
        let e = extreme_descriptors();
        check_all_kernels(&e, &e);
        // The largest possible sum, 128 * 255^2, through every kernel.
        for (name, kernel) in kernels() {
            let mut out = [0.0f32; 5];
            kernel(&[0; 128], &[[255; 128]; 5], &mut out);
            assert!(out.iter().all(|&d| d == 8_323_200f32.sqrt()), "{name}: {out:?}");
            kernel(&[255; 128], &[[255; 128]; 5], &mut out);
            assert!(out.iter().all(|&d| d == 0.0), "{name}: {out:?}");
        }
    }

    /// `distance_rows` (two-query kernels, odd query counts, remainders of
    /// the train rows) against the scalar sum, bit for bit.
    fn check_rows(queries: &[[u8; 128]], train: &[[u8; 128]]) {
        for nq in [0, 1, 2, 3, 5, queries.len()] {
            for len in [1, 2, 3, 4, 5, 7, train.len()] {
                let (q, t) = (&queries[..nq.min(queries.len())], &train[..len.min(train.len())]);
                let mut out = vec![-1.0f32; q.len() * t.len() + 1];
                distance_rows(q, &TrainSet::new(t), &mut out);
                for (i, qi) in q.iter().enumerate() {
                    for (j, tj) in t.iter().enumerate() {
                        let want = (distance_sq(qi, tj) as f32).sqrt();
                        assert_eq!(out[i * t.len() + j].to_bits(), want.to_bits(), "query {i} train {j} of {len}");
                    }
                }
                assert_eq!(out[q.len() * t.len()], -1.0, "the extra entry is untouched");
                // The AVX-512BW kernel without VNNI, which the dispatcher
                // skips on a VNNI machine.
                #[cfg(target_arch = "x86_64")]
                if q.len() >= 2 && std::is_x86_feature_detected!("avx512bw") {
                    let norms: Vec<i32> = t.iter().map(norm_sq).collect();
                    let (mut o0, mut o1) = (vec![-1.0f32; t.len()], vec![-1.0f32; t.len()]);
                    // SAFETY: the CPU has AVX-512BW.
                    unsafe { x86::rows2_avx512([&q[0], &q[1]], t, &norms, [&mut o0, &mut o1]) };
                    assert_eq!([o0, o1].concat(), out[..2 * t.len()].to_vec(), "avx512bw two-query kernel");
                }
            }
        }
    }

    #[test]
    fn distance_rows_match_scalar() {
        check_rows(&random_descriptors(9, 77), &random_descriptors(131, 78));
        let e = extreme_descriptors();
        check_rows(&e, &e);
        let mut out = [0.0f32; 6];
        distance_rows(&[[0; 128], [255; 128]], &TrainSet::new(&[[255; 128], [0; 128], [255; 128]]), &mut out);
        let max = 8_323_200f32.sqrt();
        assert_eq!(out, [max, 0.0, max, 0.0, max, 0.0]);
    }

    #[test]
    fn row_into_leaves_extra_outputs() {
        let t = random_descriptors(6, 3);
        let mut out = [-1.0f32; 8];
        distance_row_into(&t[0], &t, &mut out);
        assert_eq!(out[0], 0.0);
        assert_eq!(&out[6..], &[-1.0, -1.0]);
        assert_eq!(out[5], distance(&t[0], &t[5]));
    }
}
