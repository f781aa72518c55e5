//! `adjustLocalExtrema` (docs/fidelity.md §SIFT-7): up to five Newton steps
//! from a scan candidate with OpenCV's exact derivative and Cramer's-rule
//! arithmetic, then the contrast and edge tests, and the keypoint's fields.

use super::super::image::Plane;
use super::super::keypoint::{KeyPoint, Refined};
use super::super::num::{fma, pow2f, rne, rne64};
use super::super::params::SiftParams;
use crate::sift::observer::Rejection;

/// `SIFT_IMG_BORDER`: no extremum within 5 pixels of the border (§SIFT-1).
pub const IMG_BORDER: usize = 5;

// §SIFT-1: at most five refinement steps; the image and derivative scales.
const MAX_INTERP_STEPS: usize = 5;

const IMG_SCALE: f32 = 1.0 / 255.0;
const DERIV_SCALE: f32 = IMG_SCALE * 0.5;
const SECOND_DERIV_SCALE: f32 = IMG_SCALE;
const CROSS_DERIV_SCALE: f32 = IMG_SCALE * 0.25;

/// One DoG level, read through the two Gaussian levels it is the difference
/// of: the value OpenCV stores in its DoG pyramid is this same f32
/// subtraction, so every refinement step sees the same numbers.
#[derive(Clone, Copy)]
struct Dog<'a> {
    hi: &'a Plane,
    lo: &'a Plane,
}

impl Dog<'_> {
    #[inline(always)]
    fn at(&self, r: usize, c: usize) -> f32 {
        self.hi.at(r, c) - self.lo.at(r, c)
    }
}

/// DoG level `j` of an octave whose Gaussian levels are `levels`.
#[inline(always)]
fn dog(levels: &[Plane], j: usize) -> Dog<'_> {
    Dog { hi: &levels[j + 1], lo: &levels[j] }
}

struct Derivs {
    d: [f32; 3],
    dxx: f32,
    dyy: f32,
    dss: f32,
    dxy: f32,
    dxs: f32,
    dys: f32,
}

#[inline(always)]
fn first_derivs(cur: Dog, prev: Dog, next: Dog, r: usize, c: usize) -> [f32; 3] {
    [
        (cur.at(r, c + 1) - cur.at(r, c - 1)) * DERIV_SCALE,
        (cur.at(r + 1, c) - cur.at(r - 1, c)) * DERIV_SCALE,
        (next.at(r, c) - prev.at(r, c)) * DERIV_SCALE,
    ]
}

#[inline(always)]
fn xy_second_derivs(cur: Dog, r: usize, c: usize) -> (f32, f32, f32) {
    let v2 = cur.at(r, c) * 2.0;
    let dxx = ((cur.at(r, c + 1) + cur.at(r, c - 1)) - v2) * SECOND_DERIV_SCALE;
    let dyy = ((cur.at(r + 1, c) + cur.at(r - 1, c)) - v2) * SECOND_DERIV_SCALE;
    let dxy = (((cur.at(r + 1, c + 1) - cur.at(r + 1, c - 1)) - cur.at(r - 1, c + 1)) + cur.at(r - 1, c - 1))
        * CROSS_DERIV_SCALE;
    (dxx, dyy, dxy)
}

#[inline(always)]
fn derivs(cur: Dog, prev: Dog, next: Dog, r: usize, c: usize) -> Derivs {
    let d = first_derivs(cur, prev, next, r, c);
    let (dxx, dyy, dxy) = xy_second_derivs(cur, r, c);
    let v2 = cur.at(r, c) * 2.0;
    let dss = ((next.at(r, c) + prev.at(r, c)) - v2) * SECOND_DERIV_SCALE;
    let dxs = (((next.at(r, c + 1) - next.at(r, c - 1)) - prev.at(r, c + 1)) + prev.at(r, c - 1)) * CROSS_DERIV_SCALE;
    let dys = (((next.at(r + 1, c) - next.at(r - 1, c)) - prev.at(r + 1, c)) + prev.at(r - 1, c)) * CROSS_DERIV_SCALE;
    Derivs { d, dxx, dyy, dss, dxy, dxs, dys }
}

/// `Matx33f::solve(DECOMP_LU)`: Cramer's rule with the common subexpressions
/// and fusions GCC produced (docs/fidelity.md §SIFT-7). Returns the offsets (xc, xr, xi).
#[inline(always)]
fn solve_offsets(g: &Derivs) -> (f32, f32, f32) {
    let Derivs { d, dxx, dyy, dss, dxy, dxs, dys } = *g;
    let [d0, d1, d2] = d;
    let a = fma(dyy, dss, -(dys * dys));
    let b = fma(dss, dxy, -(dxs * dys));
    let cc = fma(dxy, dys, -(dyy * dxs));
    let det = fma(dxs, cc, fma(dxx, a, -(dxy * b)));
    if det == 0.0 {
        return (-0.0, -0.0, -0.0);
    }
    let dinv = 1.0 / det;
    let t177 = d2 * dyy;
    let pp = fma(d1, dss, -(d2 * dys));
    let q = fma(d1, dys, -t177);
    let rr = fma(d2, dxy, -(d1 * dxs));
    let s = fma(-d1, dys, t177);
    let x0 = dinv * fma(dxs, q, fma(d0, a, -(dxy * pp)));
    let x1 = dinv * fma(dxs, rr, fma(dxx, pp, -(d0 * b)));
    let x2 = dinv * fma(d0, cc, fma(dxx, s, -(dxy * rr)));
    (-x0, -x1, -x2)
}

/// Where the scan found an extremum: octave `o`, DoG layer, row and column
/// (the refinement's wrapper and body take it whole).
#[derive(Clone, Copy)]
pub(super) struct Candidate {
    pub o: usize,
    pub layer: usize,
    pub r: usize,
    pub c: usize,
}

/// `adjustLocalExtrema`: up to five Newton steps, then the contrast and
/// edge tests, or why OpenCV rejects the candidate (the plain pipeline
/// ignores the reason; the anatomy view counts it).
///
/// Compiled with FMA where the CPU has it: its two dozen `fma`s and
/// roundings were calls to `fmaf` and `rintf` otherwise.
pub(super) fn adjust_local_extremum(levels: &[Plane], at: Candidate, p: &SiftParams) -> Result<Refined, Rejection> {
    crate::with_hw_fma!(Result<Refined, Rejection>, refine(levels, at, p))
}

#[inline(always)]
fn refine(levels: &[Plane], at: Candidate, p: &SiftParams) -> Result<Refined, Rejection> {
    let Candidate { o, layer: layer0, r: r0, c: c0 } = at;
    let nl = p.n_octave_layers;
    let (w, h) = (levels[0].width as i64, levels[0].height as i64);
    let border = IMG_BORDER as i64;
    let (mut layer, mut r, mut c) = (layer0 as i64, r0 as i64, c0 as i64);
    let (mut xi, mut xr, mut xc) = (0f32, 0f32, 0f32);
    let mut converged = false;
    for _ in 0..MAX_INTERP_STEPS {
        let li = layer as usize;
        let g = derivs(dog(levels, li), dog(levels, li - 1), dog(levels, li + 1), r as usize, c as usize);
        (xc, xr, xi) = solve_offsets(&g);
        if xi.abs() < 0.5 && xr.abs() < 0.5 && xc.abs() < 0.5 {
            converged = true;
            break;
        }
        let lim = (i32::MAX / 3) as f32;
        if xi.abs() > lim || xr.abs() > lim || xc.abs() > lim {
            // A step this large is a diverging solve: OpenCV's "no convergence".
            return Err(Rejection::NoConvergence);
        }
        c += rne(xc) as i64;
        r += rne(xr) as i64;
        layer += rne(xi) as i64;
        if layer < 1 || layer > nl as i64 || c < border || c >= w - border || r < border || r >= h - border {
            return Err(Rejection::LeftScaleSpace);
        }
    }
    if !converged {
        return Err(Rejection::NoConvergence);
    }
    let (layer, r, c) = (layer as usize, r as usize, c as usize);
    let (cur, prev, next) = (dog(levels, layer), dog(levels, layer - 1), dog(levels, layer + 1));

    let [d0, d1, d2] = first_derivs(cur, prev, next, r, c);
    let t = fma(d2, xi, fma(d1, xr, d0 * xc));
    let contr = fma(cur.at(r, c), IMG_SCALE, t * 0.5);
    if contr.abs() * (nl as f32) < (p.contrast_threshold as f32) {
        return Err(Rejection::LowContrast);
    }

    let (dxx, dyy, dxy) = xy_second_derivs(cur, r, c);
    let tr = dxx + dyy;
    let det = fma(dxx, dyy, -(dxy * dxy));
    let e = p.edge_threshold as f32;
    if det <= 0.0 || tr * tr * e >= (e + 1.0) * (e + 1.0) * det {
        return Err(Rejection::EdgeLike);
    }

    let scale = (1u32 << o) as f32;
    let kp = KeyPoint {
        x: (c as f32 + xc) * scale,
        y: (r as f32 + xr) * scale,
        octave: o as i32 + ((layer as i32) << 8) + (rne64((xi as f64 + 0.5) * 255.0) << 16),
        size: ((p.sigma as f32) * pow2f((layer as f32 + xi) / nl as f32)) * scale * 2.0,
        response: contr.abs(),
        angle: 0.0,
    };
    Ok(Refined { kp, o, layer, r, c })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solve_identity_hessian() {
        let g = Derivs { d: [0.25, -0.5, 0.125], dxx: 1.0, dyy: 1.0, dss: 1.0, dxy: 0.0, dxs: 0.0, dys: 0.0 };
        assert_eq!(solve_offsets(&g), (-0.25, 0.5, -0.125));
    }

    #[test]
    fn singular_hessian_gives_zero_step() {
        let g = Derivs { d: [1.0, 1.0, 1.0], dxx: 0.0, dyy: 0.0, dss: 0.0, dxy: 0.0, dxs: 0.0, dys: 0.0 };
        let (a, b, c) = solve_offsets(&g);
        assert_eq!((a, b, c), (0.0, 0.0, 0.0));
    }
}
