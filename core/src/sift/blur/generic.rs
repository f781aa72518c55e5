//! The blur's portable block loops, generic over the multiply-add: the plain
//! path's and, compiled again inside their target-feature functions, the
//! x86 kernels' (`x86`).

// The accumulation loops keep a block of output pixels in registers while
// every tap is applied (x blocks outer, taps inner), so each tap costs one
// load and one FMA per vector instead of a load-modify-store of the output;
// each pixel still sees its taps in OpenCV's order, so results are unchanged.
// On x86-64 they are compiled again with FMA (AVX2, and AVX-512 where the CPU
// has it) and picked at run time, because `mul_add` without the `fma` target
// feature is a library call per tap. On wasm the FMA is `num::fma`.

/// Pixels per register block: 4 AVX-512 or 8 AVX2 vectors; the rest of a
/// row goes in blocks of one AVX-512 vector, then pixel by pixel.
pub(super) const BLOCK: usize = 64;
const SMALL_BLOCK: usize = 16;

/// Starts of blocks `x..x + b` covering `0..w`: one after another, the last
/// ending at `w` and overlapping the one before (each pixel's value depends
/// only on its own taps, so the overlap is recomputed identically, where a
/// lone pixel would cost a chain of dependent FMAs); and where the uncovered
/// rest starts: `w`, or 0 when `w < b`. (No closure: a closure here would be
/// compiled apart from its caller, without the caller's FMA feature.)
#[inline(always)]
pub(super) fn blocks(w: usize, b: usize) -> (impl Iterator<Item = usize>, usize) {
    let whole = if w < b { 0 } else { w / b };
    let last = (w >= b && !w.is_multiple_of(b)).then_some(w.wrapping_sub(b));
    ((0..whole).map(move |i| i * b).chain(last), if w < b { 0 } else { w })
}

/// The blocks of the generic passes over a row of `w` pixels: blocks of `b`
/// ([`blocks`]), or, in a row narrower than `b`, blocks of [`SMALL_BLOCK`]
/// (at most one of the two iterators yields); and where the pixel-by-pixel
/// rest starts.
#[inline(always)]
pub(super) fn two_block_sizes(w: usize, b: usize) -> (impl Iterator<Item = usize>, impl Iterator<Item = usize>, usize) {
    let (big, x) = blocks(w, b);
    // Blocks of `b` cover the row: no small blocks (those of an empty row).
    let (small, rest) = blocks(if x == 0 { w } else { 0 }, SMALL_BLOCK);
    (big, small, if x == 0 { rest } else { x })
}

#[inline(always)]
fn row_block<const B: usize>(src: &[f32], kx: &[f32], dst: &mut [f32], fma: &impl Fn(f32, f32, f32) -> f32) {
    let mut acc = [0f32; B];
    for (a, &s) in acc.iter_mut().zip(&src[..B]) {
        *a = s * kx[0];
    }
    for (k, &kv) in kx.iter().enumerate().skip(1) {
        for (a, &s) in acc.iter_mut().zip(&src[k..k + B]) {
            *a = fma(s, kv, *a);
        }
    }
    dst[..B].copy_from_slice(&acc);
}

#[inline(always)]
pub(super) fn accumulate_row_generic<const B: usize>(
    padded: &[f32],
    kx: &[f32],
    dst: &mut [f32],
    fma: impl Fn(f32, f32, f32) -> f32,
) {
    let (big, small, x) = two_block_sizes(dst.len(), B);
    for x in big {
        row_block::<B>(&padded[x..], kx, &mut dst[x..], &fma);
    }
    for x in small {
        row_block::<SMALL_BLOCK>(&padded[x..], kx, &mut dst[x..], &fma);
    }
    for (i, d) in dst.iter_mut().enumerate().skip(x) {
        let mut a = padded[i] * kx[0];
        for (k, &kv) in kx.iter().enumerate().skip(1) {
            a = fma(padded[i + k], kv, a);
        }
        *d = a;
    }
}

#[inline(always)]
fn column_block<const B: usize>(
    x: usize,
    centre: &[f32],
    pairs: &[(&[f32], &[f32])],
    ky: &[f32],
    dst: &mut [f32],
    fma: &impl Fn(f32, f32, f32) -> f32,
) {
    let mut acc = [0f32; B];
    for (a, &s) in acc.iter_mut().zip(&centre[x..x + B]) {
        *a = s * ky[0];
    }
    for (k, (up, down)) in pairs.iter().enumerate() {
        let kv = ky[k + 1];
        for ((a, &u), &d) in acc.iter_mut().zip(&up[x..x + B]).zip(&down[x..x + B]) {
            *a = fma(u + d, kv, *a);
        }
    }
    dst[x..x + B].copy_from_slice(&acc);
}

#[inline(always)]
pub(super) fn accumulate_column_generic(
    centre: &[f32],
    pairs: &[(&[f32], &[f32])],
    ky: &[f32],
    dst: &mut [f32],
    fma: impl Fn(f32, f32, f32) -> f32,
) {
    let (big, small, x) = two_block_sizes(dst.len(), BLOCK);
    for x in big {
        column_block::<BLOCK>(x, centre, pairs, ky, dst, &fma);
    }
    for x in small {
        column_block::<SMALL_BLOCK>(x, centre, pairs, ky, dst, &fma);
    }
    for i in x..dst.len() {
        let mut a = centre[i] * ky[0];
        for (k, (up, down)) in pairs.iter().enumerate() {
            a = fma(up[i] + down[i], ky[k + 1], a);
        }
        dst[i] = a;
    }
}
