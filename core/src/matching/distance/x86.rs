//! The x86 distance kernels (AVX-512 BW with and without VNNI, AVX2) on the
//! exact integer sums of `super`: the same distances bit for bit
//! (docs/fidelity.md §SIFT-16).

use std::arch::x86_64::*;

/// The sums of the four i32 vectors' lanes, as lanes 0..3.
///
/// Interleaving pairs of vectors and adding halves the lane count per
/// step without a horizontal add: after the two unpack levels each 128-bit
/// lane holds [a, b, c, d] partial sums, and the 128-bit lanes are then
/// folded together.
#[inline]
#[target_feature(enable = "avx512bw")]
fn hsum4_512(a: __m512i, b: __m512i, c: __m512i, d: __m512i) -> __m128i {
    let ab = _mm512_add_epi32(_mm512_unpacklo_epi32(a, b), _mm512_unpackhi_epi32(a, b));
    let cd = _mm512_add_epi32(_mm512_unpacklo_epi32(c, d), _mm512_unpackhi_epi32(c, d));
    let s = _mm512_add_epi32(_mm512_unpacklo_epi64(ab, cd), _mm512_unpackhi_epi64(ab, cd));
    let y = _mm256_add_epi32(_mm512_castsi512_si256(s), _mm512_extracti64x4_epi64::<1>(s));
    _mm_add_epi32(_mm256_castsi256_si128(y), _mm256_extracti128_si256::<1>(y))
}

/// 32 bytes at `p` zero-extended to 32 i16.
///
/// # Safety
/// `p[0..32]` must be readable, and the CPU must have AVX-512 BW.
#[inline]
#[target_feature(enable = "avx512bw")]
unsafe fn load_u8x32_as_i16(p: *const u8) -> __m512i {
    // SAFETY: the caller vouches for p[0..32]; an unaligned load.
    _mm512_cvtepu8_epi16(unsafe { _mm256_loadu_si256(p as *const __m256i) })
}

/// The one-query kernels' outer loop: four train rows a step, `sums4` giving
/// their exact i32 sums of squared differences, stored as distances; the
/// rows left over go the generic way. The kernels differ only in `sums4`.
/// (Inlined into each kernel, so it runs with the kernel's features.)
#[inline(always)]
fn by_fours(q: &[u8; 128], train: &[[u8; 128]], out: &mut [f32], sums4: impl Fn(&[[u8; 128]]) -> __m128i) {
    let mut t4 = train.chunks_exact(4);
    let mut o4 = out.chunks_exact_mut(4);
    for (t, o) in (&mut t4).zip(&mut o4) {
        let s = sums4(t);
        // SAFETY: `o` is a chunk of 4 f32; an unaligned store.
        unsafe { _mm_storeu_ps(o.as_mut_ptr(), _mm_sqrt_ps(_mm_cvtepi32_ps(s))) };
    }
    super::scalar::row_generic(q, t4.remainder(), o4.into_remainder());
}

/// One AVX-512 row kernel per way of accumulating `d * d` pairs: the
/// query stays in four registers as i16, each train row is four loads.
macro_rules! avx512_row_kernel {
    ($(#[$doc:meta])* $name:ident, $features:literal, |$acc:ident, $d:ident| $mac:expr) => {
        $(#[$doc])*
        #[target_feature(enable = $features)]
        pub(super) fn $name(q: &[u8; 128], train: &[[u8; 128]], out: &mut [f32]) {
            let qp = q.as_ptr();
            // SAFETY: the four 32-byte quarters of the 128-byte query.
            let qv = unsafe {
                [
                    load_u8x32_as_i16(qp),
                    load_u8x32_as_i16(qp.add(32)),
                    load_u8x32_as_i16(qp.add(64)),
                    load_u8x32_as_i16(qp.add(96)),
                ]
            };
            // The 16 i32 lanes of partial sums of one row.
            let row = |t: &[u8; 128]| -> __m512i {
                let tp = t.as_ptr();
                let mut $acc = _mm512_setzero_si512();
                for (k, &qk) in qv.iter().enumerate() {
                    // SAFETY: quarter k < 4 of the 128-byte train row.
                    let $d = _mm512_sub_epi16(qk, unsafe { load_u8x32_as_i16(tp.add(32 * k)) });
                    $acc = $mac;
                }
                $acc
            };
            by_fours(q, train, out, |t| hsum4_512(row(&t[0]), row(&t[1]), row(&t[2]), row(&t[3])));
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
fn dpwssd(mut acc: __m512i, a: __m512i, b: __m512i) -> __m512i {
    // SAFETY: one register-only instruction of AVX-512 VNNI, which this
    // function requires; it touches no memory, stack or flags.
    unsafe {
        std::arch::asm!(
            "vpdpwssd {acc}, {a}, {b}",
            acc = inout(zmm_reg) acc,
            a = in(zmm_reg) a,
            b = in(zmm_reg) b,
            options(pure, nomem, nostack, preserves_flags),
        )
    };
    acc
}

/// Bytes `64h .. 64h + 64` of a descriptor as two i16 vectors: the even
/// bytes (`w & 0xff` of each 16-bit word) and the odd bytes (`w >> 8`).
/// Any fixed pairing of query and train bytes gives the same dot product,
/// and this split costs one ALU op per 32 bytes (no shuffles).
///
/// # Safety
/// `p[0..64]` must be readable, and the CPU must have AVX-512 BW.
#[inline]
#[target_feature(enable = "avx512bw")]
unsafe fn even_odd(p: *const u8) -> (__m512i, __m512i) {
    // SAFETY: the caller vouches for p[0..64]; an unaligned load.
    let w = unsafe { _mm512_loadu_si512(p as *const __m512i) };
    (_mm512_and_si512(w, _mm512_set1_epi16(0xff)), _mm512_srli_epi16::<8>(w))
}

/// Two queries against every train row, four rows per pass, as
/// |q|^2 + |t|^2 - 2 q.t: each train row is loaded and split once for
/// both queries, and each 32 bytes of a pair is one multiply-add.
macro_rules! avx512_rows2_kernel {
    ($(#[$doc:meta])* $name:ident, $features:literal, |$acc:ident, $a:ident, $b:ident| $mac:expr) => {
        $(#[$doc])*
        #[target_feature(enable = $features)]
        pub(super) fn $name(
            q: [&[u8; 128]; 2],
            train: &[[u8; 128]],
            norms: &[i32],
            out: [&mut [f32]; 2],
        ) {
            let n = train.len().min(norms.len()).min(out[0].len()).min(out[1].len());
            let split = |d: &[u8; 128]| {
                // SAFETY: the two 64-byte halves of the 128-byte descriptor.
                let ((e0, o0), (e1, o1)) = unsafe { (even_odd(d.as_ptr()), even_odd(d.as_ptr().add(64))) };
                [e0, o0, e1, o1]
            };
            let qv = [split(q[0]), split(q[1])];
            let qn = [_mm_set1_epi32(super::scalar::norm_sq(q[0])), _mm_set1_epi32(super::scalar::norm_sq(q[1]))];
            let mut j = 0;
            while j + 4 <= n {
                let tv = [split(&train[j]), split(&train[j + 1]), split(&train[j + 2]), split(&train[j + 3])];
                // SAFETY: norms j .. j + 4 ≤ n ≤ norms.len(); an unaligned load.
                let tn = unsafe { _mm_loadu_si128(norms.as_ptr().add(j) as *const __m128i) };
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
                    // SAFETY: outputs j .. j + 4 ≤ n ≤ out[qk].len(); an
                    // unaligned store.
                    unsafe { _mm_storeu_ps(out[qk].as_mut_ptr().add(j), _mm_sqrt_ps(_mm_cvtepi32_ps(sq))) };
                }
                j += 4;
            }
            for (qk, o) in out.into_iter().enumerate() {
                super::scalar::row_generic(q[qk], &train[j..n], &mut o[j..n]);
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
fn hsum4_256(a: __m256i, b: __m256i, c: __m256i, d: __m256i) -> __m128i {
    let ab = _mm256_add_epi32(_mm256_unpacklo_epi32(a, b), _mm256_unpackhi_epi32(a, b));
    let cd = _mm256_add_epi32(_mm256_unpacklo_epi32(c, d), _mm256_unpackhi_epi32(c, d));
    let s = _mm256_add_epi32(_mm256_unpacklo_epi64(ab, cd), _mm256_unpackhi_epi64(ab, cd));
    _mm_add_epi32(_mm256_castsi256_si128(s), _mm256_extracti128_si256::<1>(s))
}

/// 16 bytes at `p` zero-extended to 16 i16.
///
/// # Safety
/// `p[0..16]` must be readable, and the CPU must have AVX2.
#[inline]
#[target_feature(enable = "avx2")]
unsafe fn load_u8x16_as_i16(p: *const u8) -> __m256i {
    // SAFETY: the caller vouches for p[0..16]; an unaligned load.
    _mm256_cvtepu8_epi16(unsafe { _mm_loadu_si128(p as *const __m128i) })
}

/// AVX2: the query in eight registers as i16, `vpmaddwd` + `vpaddd`.
#[target_feature(enable = "avx2")]
pub(super) fn row_avx2(q: &[u8; 128], train: &[[u8; 128]], out: &mut [f32]) {
    let qp = q.as_ptr();
    // SAFETY: block k < 8 of the 128-byte query.
    let qv: [__m256i; 8] = std::array::from_fn(|k| unsafe { load_u8x16_as_i16(qp.add(16 * k)) });
    let row = |t: &[u8; 128]| -> __m256i {
        let tp = t.as_ptr();
        let mut acc = _mm256_setzero_si256();
        for (k, &qk) in qv.iter().enumerate() {
            // SAFETY: block k < 8 of the 128-byte train row.
            let d = _mm256_sub_epi16(qk, unsafe { load_u8x16_as_i16(tp.add(16 * k)) });
            acc = _mm256_add_epi32(acc, _mm256_madd_epi16(d, d));
        }
        acc
    };
    by_fours(q, train, out, |t| hsum4_256(row(&t[0]), row(&t[1]), row(&t[2]), row(&t[3])));
}
