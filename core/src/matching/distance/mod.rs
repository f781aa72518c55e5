//! L2 distances between SIFT descriptors as `cv2.BFMatcher()` computes them
//! (docs/fidelity.md §SIFT-16): OpenCV sums float squares, but every partial sum of squared
//! 0..255 differences is an integer below 2^24, so the float sum is exact and
//! equals this integer sum; the distance is its correctly rounded f32 sqrt.
//!
//! `scalar` holds the plain sum; this module the dispatch. The row kernels beside
//! it (`x86`: AVX-512 BW with and without VNNI, AVX2; `wasm`: simd128)
//! compute that same integer sum with SIMD: bytes are
//! zero-extended to i16, subtracted (|d| <= 255), and squared-and-paired by a
//! 16-bit multiply-add into i32 lanes (2 * 255^2 per pair, 128 * 255^2 in
//! all, far below 2^31). Integer arithmetic is exact in any order, the i32 ->
//! f32 conversion is exact below 2^24 and the vector sqrt is IEEE correctly
//! rounded like `f32::sqrt`, so every kernel returns bit-identical distances.
//! Each kernel handles four train rows per pass so their four horizontal sums
//! share one reduction and one 4-wide sqrt; a remainder of < 4 rows takes the
//! scalar path.

mod scalar;
#[cfg(all(target_arch = "wasm32", target_feature = "simd128"))]
mod wasm;
#[cfg(target_arch = "x86_64")]
mod x86;

#[cfg(test)]
pub use scalar::{distance, distance_sq};
use scalar::{norm_sq, row_generic};

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
            // SAFETY: the CPU has AVX-512 BW and VNNI, the features the function enables.
            unsafe { x86::row_avx512_vnni(q, train, out) };
            return;
        }
        if std::is_x86_feature_detected!("avx512bw") {
            // SAFETY: the CPU has AVX-512 BW, the feature the function enables.
            unsafe { x86::row_avx512(q, train, out) };
            return;
        }
        if std::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU has AVX2, the feature the function enables.
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
                if vnni {
                    // SAFETY: the CPU has AVX-512 BW and VNNI, the features the function enables.
                    unsafe { x86::rows2_avx512_vnni([&q[0], &q[1]], train.rows, &train.norms, [o0, o1]) };
                } else {
                    // SAFETY: the CPU has AVX-512 BW, the feature the function enables.
                    unsafe { x86::rows2_avx512([&q[0], &q[1]], train.rows, &train.norms, [o0, o1]) };
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
                // SAFETY: registered only when the CPU has AVX2.
                k.push(("avx2", |q, t, o| unsafe { x86::row_avx2(q, t, o) }));
            }
            if std::is_x86_feature_detected!("avx512bw") {
                // SAFETY: registered only when the CPU has AVX-512 BW.
                k.push(("avx512bw", |q, t, o| unsafe { x86::row_avx512(q, t, o) }));
                if std::is_x86_feature_detected!("avx512vnni") {
                    // SAFETY: registered only when the CPU also has AVX-512 VNNI.
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
