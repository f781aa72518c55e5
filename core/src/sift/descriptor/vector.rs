//! The descriptor's kernels with vectors ([`Lanes`]: AVX-512, AVX2 or
//! SIMD128): a window row's samples and the histogram update of OpenCV's SIMD
//! body, each lane doing the operations of the scalar loops of `mod.rs`
//! ([`super::collect_samples`], [`super::bins`]), so the same samples in the
//! same order and the same histogram (docs/fidelity.md §SIFT-11: the SIMD body
//! rounds every product and difference).

use super::super::lanes::{Kernel, Lanes};
use super::layout::{cell_offsets, Rows, Samples, BINS_PER_DEG, D, HIST_LEN, N};

/// Lane numbers, for the column index of each lane.
static LANE: [f32; 16] = [0., 1., 2., 3., 4., 5., 6., 7., 8., 9., 10., 11., 12., 13., 14., 15.];

/// Columns `c0 + t` of one window row, `t` in `0..n` (positions are `t`).
pub(super) struct SampleRow<'a> {
    pub s: &'a mut Samples,
    /// The row and the rows above and below, with columns `c0 − 1 ..= c0 + n`.
    pub rows: [&'a [f32]; 3],
    pub c0: usize,
    pub n: usize,
    /// The window column of `t = 0`.
    pub j0: f32,
    pub rot: [f32; 4],
    pub exp_scale: f32,
}

impl Kernel for SampleRow<'_> {
    #[inline(always)]
    fn apply<L: Lanes>(&mut self, l: L, start: usize) -> usize {
        let (nl, c0, n) = (L::N, self.c0, self.n);
        let [row, up, down] = self.rows;
        assert!(c0 >= 1 && [row, up, down].iter().all(|r| r.len() > c0 + n), "columns c0 − 1 ..= c0 + n");
        let [cos_t, sin_t, a, b] = self.rot;
        // SAFETY: LANE holds 16 >= N values.
        let lane = unsafe { l.load(LANE.as_ptr()) };
        let (cos_v, sin_v, a_v, b_v) = (l.splat(cos_t), l.splat(sin_t), l.splat(a), l.splat(b));
        let (half, point5, lo, hi) = (l.splat(D as f32 / 2.0), l.splat(0.5), l.splat(-1.0), l.splat(D as f32));
        let s = &mut *self.s;
        // Room for every column left plus one whole vector: the kept lanes
        // are stored as a vector, the ones past them cut off by `set_len`.
        for v in [&mut s.dx, &mut s.dy, &mut s.w, &mut s.rbin, &mut s.cbin] {
            v.reserve(n - start.min(n) + nl);
        }
        let mut t = start;
        while t + nl <= n {
            let fj = l.add(l.splat(self.j0 + t as f32), lane);
            let c_rot = l.fma(fj, cos_v, a_v);
            let r_rot = l.fma(fj, sin_v, b_v);
            let rbin = l.sub(l.add(r_rot, half), point5);
            let cbin = l.sub(l.add(c_rot, half), point5);
            let inside = l.and(l.and(l.gt(rbin, lo), l.lt(rbin, hi)), l.and(l.gt(cbin, lo), l.lt(cbin, hi)));
            let keep = l.bits(inside);
            if keep != 0 {
                let c = c0 + t;
                // SAFETY: columns c − 1 ..= c + nl <= c0 + n of the three rows
                // (asserted above).
                let (dx, dy) = unsafe {
                    (
                        l.sub(l.load(row.as_ptr().add(c + 1)), l.load(row.as_ptr().add(c - 1))),
                        l.sub(l.load(up.as_ptr().add(c)), l.load(down.as_ptr().add(c))),
                    )
                };
                let w = l.mul(l.fma(c_rot, c_rot, l.mul(r_rot, r_rot)), l.splat(self.exp_scale));
                let k = keep.count_ones() as usize;
                let len = s.dx.len();
                for (v, x) in
                    [(&mut s.dx, dx), (&mut s.dy, dy), (&mut s.w, w), (&mut s.rbin, rbin), (&mut s.cbin, cbin)]
                {
                    debug_assert!(v.capacity() >= len + nl);
                    // SAFETY: the vector has room for a whole vector past
                    // `len` (reserved above: at most t kept so far), and its
                    // first k values are the kept lanes.
                    unsafe {
                        l.compress_store(v.as_mut_ptr().add(len), keep, x);
                        v.set_len(len + k);
                    }
                }
            }
            t += nl;
        }
        t
    }
}

/// The histogram update of samples `0..len` of OpenCV's SIMD body: bin
/// indices and the eight weights of a block of samples computed in vectors
/// (every product and difference rounded separately, as there), then added
/// to the bins sample by sample so each bin sees its contributions in order.
pub(super) struct Accumulate<'a> {
    pub s: &'a Rows<'a>,
    pub len: usize,
    pub ori: f32,
    pub hist: &'a mut [f32; HIST_LEN],
}

impl Kernel for Accumulate<'_> {
    #[inline(always)]
    fn apply<L: Lanes>(&mut self, l: L, start: usize) -> usize {
        let (nl, s) = (L::N, self.s);
        assert!([s.rbin, s.cbin, s.ori, s.mag, s.wt].iter().all(|r| r.len() >= self.len), "a value per sample");
        let (ori_v, bpd) = (l.splat(self.ori), l.splat(BINS_PER_DEG));
        let (one, n_v) = (l.splat_i(1), l.splat_i(N as i32));
        let offs = cell_offsets();
        let mut k = start;
        while k + nl <= self.len {
            // SAFETY: samples k..k + nl <= len, inside every row (asserted).
            // (Loads written out: a closure would be compiled without the
            // ISA's target features, its intrinsics left as calls.)
            let (mut rbin, mut cbin, ori, mag, wt) = unsafe {
                let at = |v: &[f32]| v.as_ptr().add(k);
                (l.load(at(s.rbin)), l.load(at(s.cbin)), l.load(at(s.ori)), l.load(at(s.mag)), l.load(at(s.wt)))
            };
            let mut obin = l.mul(l.sub(ori, ori_v), bpd);
            let mag = l.mul(mag, wt);
            let (r0, c0, o0) = (l.floor(rbin), l.floor(cbin), l.floor(obin));
            rbin = l.sub(rbin, l.to_f(r0));
            cbin = l.sub(cbin, l.to_f(c0));
            obin = l.sub(obin, l.to_f(o0));
            let o0 = l.wrap(o0, n_v);
            let v_r1 = l.mul(mag, rbin);
            let v_r0 = l.sub(mag, v_r1);
            let v_rc11 = l.mul(v_r1, cbin);
            let v_rc10 = l.sub(v_r1, v_rc11);
            let v_rc01 = l.mul(v_r0, cbin);
            let v_rc00 = l.sub(v_r0, v_rc01);
            let row = l.add_i(l.mul_i(l.add_i(r0, one), l.splat_i(D as i32 + 2)), l.add_i(c0, one));
            let idx = l.add_i(l.mul_i(row, l.splat_i(N as i32 + 2)), o0);
            let mut idx_a = [0i32; 16];
            let mut w = [[0f32; 16]; 8];
            // SAFETY: idx_a and each row of w hold 16 >= nl values.
            unsafe {
                l.store_i(idx_a.as_mut_ptr(), idx);
                for (c, rc) in [v_rc00, v_rc01, v_rc10, v_rc11].into_iter().enumerate() {
                    let rco1 = l.mul(rc, obin);
                    l.store(w[2 * c].as_mut_ptr(), l.sub(rc, rco1));
                    l.store(w[2 * c + 1].as_mut_ptr(), rco1);
                }
            }
            for (lane, &idx) in idx_a[..nl].iter().enumerate() {
                // r0, c0 in [-1, 3] and o0 in [0, 7] keep idx in 0..=287;
                // the clamp only tells the compiler so (no bounds checks).
                let idx = idx.clamp(0, 287) as usize;
                for (c, off) in offs.into_iter().enumerate() {
                    self.hist[idx + off] += w[2 * c][lane];
                    self.hist[idx + off + 1] += w[2 * c + 1][lane];
                }
            }
            k += nl;
        }
        k
    }
}
