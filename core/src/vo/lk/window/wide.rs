//! What the vector kernels (`avx2`, `simd128`) share: 16-bit windows in a
//! column order made for pairwise multiply-adds, and the rule that turns
//! their exact integer sums into OpenCV's f32 sums.
//!
//! Windows are kept as 16-bit rows (every value fits: T, J ≤ 8160, |X|, |Y| ≤
//! 4080, |J − T| ≤ 8160) in this order:
//!
//! ```text
//! positions  0..8    columns 0 4 1 5 2 6 3 7      (block 0)
//! positions  8..16   columns 8 12 9 13 10 14 11 15 (block 8)
//! positions 16..24   columns 16 .. 23              (tail; 21..23 are scratch)
//! ```
//!
//! so one multiply-add of a pair of positions (`vpmaddwd`,
//! `i32x4.dot_i16x8_s`) gives `d(c)·Z(c) + d(c+4)·Z(c+4)`, the exact integer
//! pair sum OpenCV's SSE loop rounds to f32 (docs/fidelity.md §VO-2.4 step 3). Bilinear
//! interpolation is a multiply-add of (I(c), I(c+1)) pairs, shuffled straight
//! into that order, with (w00, w01) and (w10, w11).
//!
//! OpenCV accumulates the sums in f32 in a fixed order, and a chain of 42 (or,
//! in the scalar tail, 105) dependent f32 adds per iteration is what made the
//! tracker slow. Here the sums are first taken as exact integers, together
//! with a bound Σ|terms| per f32 accumulator. When the bound is ≤ 2^24, every
//! term and every partial sum of OpenCV's running sum is an integer f32
//! represents exactly, so each of its adds was exact and its result *is* the
//! integer sum. Only when a bound exceeds 2^24 is the running sum replayed in
//! OpenCV's order. Either way the bits are OpenCV's.

use super::{FLT_SCALE, WIN};

/// One window row in the layout above (positions 24..32 stay 0 in T, X, Y
/// and their magnitudes; X and Y are also 0 at columns 21..23).
#[repr(C, align(32))]
#[derive(Clone, Copy)]
pub struct Row(pub [i16; 32]);

pub type Win16 = [Row; WIN];

/// Template T, gradients X, Y and their magnitudes, plus the last J − T.
pub struct Patch {
    pub t: Win16,
    pub x: Win16,
    pub y: Win16,
    pub ax: Win16,
    pub ay: Win16,
    pub d: Win16,
}

impl super::NewBoxed for Patch {
    fn new_boxed() -> Box<Patch> {
        let zero = [Row([0; 32]); WIN];
        Box::new(Patch { t: zero, x: zero, y: zero, ax: zero, ay: zero, d: zero })
    }
}

/// Position of window column `c` in a [`Row`].
#[inline(always)]
pub fn pos(c: usize) -> usize {
    if c < 16 {
        let r = c % 8;
        8 * (c / 8) + if r < 4 { 2 * r } else { 2 * (r - 4) + 1 }
    } else {
        c
    }
}

/// Largest accumulator bound for which every partial sum is exact in f32.
pub const EXACT: u64 = 1 << 24;

/// An accumulator of pair sums over the window: i32 lanes of the two blocks
/// (lane k of a block: column group k, i.e. columns k, k+4, k+8, k+12) and
/// of the tail.
#[derive(Clone, Copy, Default)]
pub struct Acc {
    pub blocks: [i32; 8],
    pub tail: [i32; 4],
}

impl Acc {
    /// Exact sums of the four column groups and of the tail.
    #[inline(always)]
    pub fn groups(&self) -> ([i64; 4], i64) {
        let l = &self.blocks;
        let g = |k: usize| l[k] as i64 + l[4 + k] as i64;
        ([g(0), g(1), g(2), g(3)], self.tail.iter().map(|&v| v as i64).sum())
    }

    /// As a bound (non-negative lanes that may exceed i32 once combined):
    /// whether every column group's running sum is exact in f32.
    #[inline(always)]
    pub fn groups_exact(&self) -> bool {
        let l = self.blocks.map(|v| v as u32 as u64);
        (0..4).all(|k| l[k] + l[4 + k] <= EXACT)
    }

    /// The same for the tail's running sum.
    #[inline(always)]
    pub fn tail_exact(&self) -> bool {
        self.tail.iter().map(|&v| v as u32 as u64).sum::<u64>() <= EXACT
    }
}

/// OpenCV's tensor lanes L0..L3 of ΣA·B, replayed term by term: columns
/// 0..15 in column order, column c into lane c mod 4 (§VO-2.4 "Structure tensor").
fn tensor_lanes_replay(a: &Win16, b: &Win16) -> [f32; 4] {
    let mut l = [0f32; 4];
    for (ra, rb) in a.iter().zip(b) {
        for c in 0..16 {
            l[c % 4] += (ra.0[pos(c)] as i32 * rb.0[pos(c)] as i32) as f32;
        }
    }
    l
}

/// The scalar running sum over columns 16..20, row by row (tensor S, and
/// s1/s2 of the mismatch with `a` = J − T).
fn tail_replay(a: &Win16, b: &Win16) -> f32 {
    let mut s = 0f32;
    for (ra, rb) in a.iter().zip(b) {
        for c in 16..WIN {
            s += (ra.0[c] as i32 * rb.0[c] as i32) as f32;
        }
    }
    s
}

/// One tensor sum ΣA·B, `S + ((L0 + L2) + (L1 + L3))`: lanes and tail each
/// from the exact integers, or replayed in OpenCV's order when their bound
/// fails.
pub fn tensor_sum(sum: &Acc, bound: &Acc, a: &Win16, b: &Win16) -> f32 {
    let (g, s) = sum.groups();
    let l = if bound.groups_exact() { g.map(|v| v as f32) } else { tensor_lanes_replay(a, b) };
    let s = if bound.tail_exact() { s as f32 } else { tail_replay(a, b) };
    s + ((l[0] + l[2]) + (l[1] + l[3]))
}

/// OpenCV's T0..T3 (= P + Q: X of groups 0+2, Y of 0+2, X of 1+3, Y of 1+3)
/// replayed from the stored J − T: per row and block B ∈ {0, 8},
/// P += (uX(B), uY(B), uX(B+1), uY(B+1)) and Q += the next two, in f32.
#[cfg_attr(target_arch = "x86_64", allow(dead_code))]
pub fn mismatch_lanes_replay(p: &Patch) -> [f32; 4] {
    let (mut pa, mut qa) = ([0f32; 4], [0f32; 4]);
    for y in 0..WIN {
        let (d, x, g) = (&p.d[y].0, &p.x[y].0, &p.y[y].0);
        for block in [0usize, 8] {
            // Positions block + 2k, block + 2k + 1 hold columns B+k, B+k+4.
            let u = |z: &[i16; 32], k: usize| {
                let i = block + 2 * k;
                (d[i] as i32 * z[i] as i32 + d[i + 1] as i32 * z[i + 1] as i32) as f32
            };
            for (lane, k) in [(0, 0), (2, 1)] {
                pa[lane] += u(x, k);
                pa[lane + 1] += u(g, k);
            }
            for (lane, k) in [(0, 2), (2, 3)] {
                qa[lane] += u(x, k);
                qa[lane + 1] += u(g, k);
            }
        }
    }
    [pa[0] + qa[0], pa[1] + qa[1], pa[2] + qa[2], pa[3] + qa[3]]
}

/// (b1, b2) from the exact sums and bounds of J − T against X and Y,
/// replaying in OpenCV's order whatever a bound does not cover.
/// `lanes_replay` is [`mismatch_lanes_replay`] or a vector version of it.
pub fn finish_mismatch(
    p: &Patch,
    sx: &Acc,
    sy: &Acc,
    bx: &Acc,
    by: &Acc,
    lanes_replay: impl FnOnce(&Patch) -> [f32; 4],
) -> (f32, f32) {
    let (gx, ex) = sx.groups();
    let (gy, ey) = sy.groups();
    // T0 + T2 = (P0 + Q0) + (P2 + Q2) with P0 = group 0, Q0 = group 2, ...
    let mut t = [
        gx[0] as f32 + gx[2] as f32,
        gy[0] as f32 + gy[2] as f32,
        gx[1] as f32 + gx[3] as f32,
        gy[1] as f32 + gy[3] as f32,
    ];
    let (lanes_x, lanes_y) = (bx.groups_exact(), by.groups_exact());
    if !(lanes_x && lanes_y) {
        let r = lanes_replay(p);
        if !lanes_x {
            (t[0], t[2]) = (r[0], r[2]);
        }
        if !lanes_y {
            (t[1], t[3]) = (r[1], r[3]);
        }
    }
    let s1 = if bx.tail_exact() { ex as f32 } else { tail_replay(&p.d, &p.x) };
    let s2 = if by.tail_exact() { ey as f32 } else { tail_replay(&p.d, &p.y) };
    ((s1 + (t[0] + t[2])) * FLT_SCALE, (s2 + (t[1] + t[3])) * FLT_SCALE)
}

/// Σ|J − T| from an accumulator of |d| pair sums (tail masked to columns
/// 16..20): ≤ 441·8160 < 2^24, so OpenCV's row-major f32 running sum is this
/// integer.
pub fn abs_diff_total(acc: &Acc) -> f32 {
    let (g, s) = acc.groups();
    (g.iter().sum::<i64>() + s) as f32
}

#[cfg(test)]
mod tests {
    use super::pos;

    #[test]
    fn the_row_layout_pairs_each_column_with_the_one_four_further() {
        let mut seen = [false; 24];
        for c in 0..24 {
            assert!(!seen[pos(c)]);
            seen[pos(c)] = true;
        }
        for c in [0, 1, 2, 3, 8, 9, 10, 11] {
            assert_eq!(pos(c + 4), pos(c) + 1);
            assert_eq!(pos(c) % 2, 0);
        }
    }
}
