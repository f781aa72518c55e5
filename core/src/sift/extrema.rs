//! Scale-space extrema: the 26-neighbour scan, sub-pixel refinement with
//! OpenCV's exact arithmetic, contrast and edge tests (spec §6, §7).

use super::image::Plane;
use super::num::{fma, rne, rne64};
use super::orientation::push_oriented;
use super::{KeyPoint, SiftParams};

pub const IMG_BORDER: usize = 5;
const MAX_INTERP_STEPS: usize = 5;

const IMG_SCALE: f32 = 1.0 / 255.0;
const DERIV_SCALE: f32 = IMG_SCALE * 0.5;
const SECOND_DERIV_SCALE: f32 = IMG_SCALE;
const CROSS_DERIV_SCALE: f32 = IMG_SCALE * 0.25;

/// Finds the keypoints of one (octave, layer) DoG image, rows `[r0, r1)`,
/// appending them with every orientation peak (unordered; §10 sorts).
pub fn scan_layer(
    gauss: &[Plane],
    dog: &[Plane],
    o: usize,
    layer: usize,
    rows: std::ops::Range<usize>,
    p: &SiftParams,
    out: &mut Vec<KeyPoint>,
) {
    let nl = p.n_octave_layers;
    let idx = o * (nl + 2) + layer;
    let (prev, cur, next) = (&dog[idx - 1], &dog[idx], &dog[idx + 1]);
    let (w, h) = (cur.width, cur.height);
    // floor(0.5 * contrastThreshold / nOctaveLayers * 255 * SIFT_FIXPT_SCALE),
    // an int compared as float: 1 with the defaults.
    let threshold = (0.5 * p.contrast_threshold / nl as f64 * 255.0).floor() as i32 as f32;
    let r_start = rows.start.max(IMG_BORDER);
    let r_end = rows.end.min(h.saturating_sub(IMG_BORDER));
    if w <= 2 * IMG_BORDER {
        return;
    }
    for r in r_start..r_end {
        let (cp, cc, cn) = (cur.row(r - 1), cur.row(r), cur.row(r + 1));
        let (pp, pc, pn) = (prev.row(r - 1), prev.row(r), prev.row(r + 1));
        let (np, nc, nn) = (next.row(r - 1), next.row(r), next.row(r + 1));
        for c in IMG_BORDER..w - IMG_BORDER {
            let v = cc[c];
            if v.abs() <= threshold {
                continue;
            }
            let is_ext = if v > 0.0 {
                v >= cc[c - 1] && v >= cc[c + 1]
                    && v >= cp[c - 1] && v >= cp[c] && v >= cp[c + 1]
                    && v >= cn[c - 1] && v >= cn[c] && v >= cn[c + 1]
                    && v >= pc[c - 1] && v >= pc[c] && v >= pc[c + 1]
                    && v >= pp[c - 1] && v >= pp[c] && v >= pp[c + 1]
                    && v >= pn[c - 1] && v >= pn[c] && v >= pn[c + 1]
                    && v >= nc[c - 1] && v >= nc[c] && v >= nc[c + 1]
                    && v >= np[c - 1] && v >= np[c] && v >= np[c + 1]
                    && v >= nn[c - 1] && v >= nn[c] && v >= nn[c + 1]
            } else {
                v <= cc[c - 1] && v <= cc[c + 1]
                    && v <= cp[c - 1] && v <= cp[c] && v <= cp[c + 1]
                    && v <= cn[c - 1] && v <= cn[c] && v <= cn[c + 1]
                    && v <= pc[c - 1] && v <= pc[c] && v <= pc[c + 1]
                    && v <= pp[c - 1] && v <= pp[c] && v <= pp[c + 1]
                    && v <= pn[c - 1] && v <= pn[c] && v <= pn[c + 1]
                    && v <= nc[c - 1] && v <= nc[c] && v <= nc[c + 1]
                    && v <= np[c - 1] && v <= np[c] && v <= np[c + 1]
                    && v <= nn[c - 1] && v <= nn[c] && v <= nn[c + 1]
            };
            if !is_ext {
                continue;
            }
            if let Some(refined) = adjust_local_extremum(dog, o, layer, r, c, p) {
                push_oriented(gauss, refined, p, out);
            }
        }
    }
}

/// A refined extremum, before orientation: the keypoint fields plus the
/// integer pixel and layer the orientation histogram is centred on.
pub struct Refined {
    pub kp: KeyPoint,
    pub o: usize,
    pub layer: usize,
    pub r: usize,
    pub c: usize,
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
fn first_derivs(cur: &Plane, prev: &Plane, next: &Plane, r: usize, c: usize) -> [f32; 3] {
    [
        (cur.at(r, c + 1) - cur.at(r, c - 1)) * DERIV_SCALE,
        (cur.at(r + 1, c) - cur.at(r - 1, c)) * DERIV_SCALE,
        (next.at(r, c) - prev.at(r, c)) * DERIV_SCALE,
    ]
}

#[inline(always)]
fn xy_second_derivs(cur: &Plane, r: usize, c: usize) -> (f32, f32, f32) {
    let v2 = cur.at(r, c) * 2.0;
    let dxx = ((cur.at(r, c + 1) + cur.at(r, c - 1)) - v2) * SECOND_DERIV_SCALE;
    let dyy = ((cur.at(r + 1, c) + cur.at(r - 1, c)) - v2) * SECOND_DERIV_SCALE;
    let dxy = (((cur.at(r + 1, c + 1) - cur.at(r + 1, c - 1)) - cur.at(r - 1, c + 1))
        + cur.at(r - 1, c - 1))
        * CROSS_DERIV_SCALE;
    (dxx, dyy, dxy)
}

fn derivs(cur: &Plane, prev: &Plane, next: &Plane, r: usize, c: usize) -> Derivs {
    let d = first_derivs(cur, prev, next, r, c);
    let (dxx, dyy, dxy) = xy_second_derivs(cur, r, c);
    let v2 = cur.at(r, c) * 2.0;
    let dss = ((next.at(r, c) + prev.at(r, c)) - v2) * SECOND_DERIV_SCALE;
    let dxs = (((next.at(r, c + 1) - next.at(r, c - 1)) - prev.at(r, c + 1)) + prev.at(r, c - 1))
        * CROSS_DERIV_SCALE;
    let dys = (((next.at(r + 1, c) - next.at(r - 1, c)) - prev.at(r + 1, c)) + prev.at(r - 1, c))
        * CROSS_DERIV_SCALE;
    Derivs { d, dxx, dyy, dss, dxy, dxs, dys }
}

/// `Matx33f::solve(DECOMP_LU)`: Cramer's rule with the common subexpressions
/// and fusions GCC produced (spec §7). Returns the offsets (xc, xr, xi).
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

/// `adjustLocalExtrema`: up to five Newton steps, then the contrast and
/// edge tests. `None` when OpenCV rejects the candidate.
fn adjust_local_extremum(
    dog: &[Plane],
    o: usize,
    layer0: usize,
    r0: usize,
    c0: usize,
    p: &SiftParams,
) -> Option<Refined> {
    let nl = p.n_octave_layers;
    let base = o * (nl + 2);
    let (w, h) = (dog[base].width as i64, dog[base].height as i64);
    let border = IMG_BORDER as i64;
    let (mut layer, mut r, mut c) = (layer0 as i64, r0 as i64, c0 as i64);
    let (mut xi, mut xr, mut xc) = (0f32, 0f32, 0f32);
    let mut converged = false;
    for _ in 0..MAX_INTERP_STEPS {
        let li = base + layer as usize;
        let g = derivs(&dog[li], &dog[li - 1], &dog[li + 1], r as usize, c as usize);
        (xc, xr, xi) = solve_offsets(&g);
        if xi.abs() < 0.5 && xr.abs() < 0.5 && xc.abs() < 0.5 {
            converged = true;
            break;
        }
        let lim = (i32::MAX / 3) as f32;
        if xi.abs() > lim || xr.abs() > lim || xc.abs() > lim {
            return None;
        }
        c += rne(xc) as i64;
        r += rne(xr) as i64;
        layer += rne(xi) as i64;
        if layer < 1 || layer > nl as i64 || c < border || c >= w - border || r < border || r >= h - border {
            return None;
        }
    }
    if !converged {
        return None;
    }
    let (layer, r, c) = (layer as usize, r as usize, c as usize);
    let li = base + layer;
    let (cur, prev, next) = (&dog[li], &dog[li - 1], &dog[li + 1]);

    let [d0, d1, d2] = first_derivs(cur, prev, next, r, c);
    let t = fma(d2, xi, fma(d1, xr, d0 * xc));
    let contr = fma(cur.at(r, c), IMG_SCALE, t * 0.5);
    if contr.abs() * (nl as f32) < (p.contrast_threshold as f32) {
        return None;
    }

    let (dxx, dyy, dxy) = xy_second_derivs(cur, r, c);
    let tr = dxx + dyy;
    let det = fma(dxx, dyy, -(dxy * dxy));
    let e = p.edge_threshold as f32;
    if det <= 0.0 || tr * tr * e >= (e + 1.0) * (e + 1.0) * det {
        return None;
    }

    let scale = (1u32 << o) as f32;
    let kp = KeyPoint {
        x: (c as f32 + xc) * scale,
        y: (r as f32 + xr) * scale,
        octave: o as i32 + ((layer as i32) << 8) + (rne64((xi as f64 + 0.5) * 255.0) << 16),
        size: ((p.sigma as f32) * super::num::pow2f((layer as f32 + xi) / nl as f32)) * scale * 2.0,
        response: contr.abs(),
        angle: 0.0,
    };
    Some(Refined { kp, o, layer, r, c })
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
