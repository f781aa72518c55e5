//! The tracker proper (docs/fidelity.md §VO-2.4, §VO-2.5): every point from
//! the coarsest level to the finest, each level a chain of iterations whose
//! windows come from `window`, then status and error at level 0. Points are
//! independent, so they are visited in an order kind to the caches and split
//! over threads without changing a bit.

use super::pyramid::{build_pyramid, Deriv, Level, Pyramid};
#[cfg(all(target_arch = "wasm32", target_feature = "simd128"))]
use super::window::Simd128;
use super::window::{weights, Kernels, Scalar};
#[cfg(target_arch = "x86_64")]
use super::window::{Avx2, Avx512};
use super::{LkParams, LkResult, FLT_SCALE, WIN};
use crate::image::GrayImage;

/// `(winSize - 1) * 0.5f`.
const HALF_WIN: f32 = 10.0;

/// `cv2.calcOpticalFlowPyrLK(prev, next, pts, None, winSize=(21,21), ...)`.
/// Both images must have the same size.
pub fn calc_optical_flow_pyr_lk(prev: &GrayImage, next: &GrayImage, pts: &[[f32; 2]], params: &LkParams) -> LkResult {
    lk_from_images(prev, next, pts, params, false)
}

/// The same call with the portable scalar kernels only (the reference the
/// vector kernels are tested against; what wasm without SIMD runs).
pub fn calc_optical_flow_pyr_lk_portable(
    prev: &GrayImage,
    next: &GrayImage,
    pts: &[[f32; 2]],
    params: &LkParams,
) -> LkResult {
    lk_from_images(prev, next, pts, params, true)
}

/// calcOpticalFlowPyrLK on prebuilt pyramids (the previous one may be deeper;
/// OpenCV limits the second pyramid to the first one's depth).
pub fn calc_optical_flow_pyr_lk_pyramids(
    prev: &Pyramid,
    next: &Pyramid,
    pts: &[[f32; 2]],
    params: &LkParams,
) -> LkResult {
    let depth = prev.levels.len().min(next.levels.len()).min(params.max_level + 1);
    let derivs = prev.levels[..depth].iter().map(Deriv::new).collect();
    let prep = Prepared { prev: &prev.levels[..depth], next: &next.levels[..depth], derivs };
    track_prepared(&prep, pts, params, false)
}

fn lk_from_images(prev: &GrayImage, next: &GrayImage, pts: &[[f32; 2]], params: &LkParams, portable: bool) -> LkResult {
    let prev_pyr = build_pyramid(prev, params.max_level);
    let max_level = prev_pyr.len() - 1;
    let next_pyr = build_pyramid(next, max_level);
    let derivs = prev_pyr.iter().map(Deriv::new).collect();
    let prep = Prepared { prev: &prev_pyr, next: &next_pyr, derivs };
    track_prepared(&prep, pts, params, portable)
}

fn track_prepared(prep: &Prepared, pts: &[[f32; 2]], params: &LkParams, scalar: bool) -> LkResult {
    let n = pts.len();
    // Visit the points in bands of rows, left to right within a band, not
    // in the caller's order (for SIFT keypoints that is response order,
    // spatially random): neighbouring windows then share cached rows of the
    // pyramids and derivative planes. Each point's result depends on its
    // own window only, so the order changes the speed, not a bit of them.
    let mut order: Vec<u32> = (0..n as u32).collect();
    order.sort_by_key(|&i| {
        let [x, y] = pts[i as usize];
        // Keys from the clamped coordinates: NaN or huge inputs sort anywhere.
        let band = (y.clamp(-1.0e6, 1.0e6) as i32) >> 5;
        (band, x.clamp(-1.0e6, 1.0e6) as i32)
    });
    let sorted: Vec<[f32; 2]> = order.iter().map(|&i| pts[i as usize]).collect();
    let out = track_ordered(prep, &sorted, params, scalar);
    let mut next_pts = vec![[0f32; 2]; n];
    let mut status = vec![true; n];
    let mut err = vec![0f32; n];
    for (k, &i) in order.iter().enumerate() {
        next_pts[i as usize] = out.next_pts[k];
        status[i as usize] = out.status[k];
        err[i as usize] = out.err[k];
    }
    LkResult { next_pts, status, err }
}

fn track_ordered(prep: &Prepared, pts: &[[f32; 2]], params: &LkParams, scalar: bool) -> LkResult {
    let max_level = prep.prev.len().min(prep.next.len()) - 1;
    let max_count = params.max_count.min(100);
    let eps = params.epsilon.clamp(0.0, 10.0);
    let crit = (max_count, eps * eps);
    let min_eig = params.min_eig_threshold as f32;
    let n = pts.len();
    let mut next_pts = vec![[0f32; 2]; n];
    let mut status = vec![true; n];
    let mut err = vec![0f32; n];

    // Points are independent (OpenCV runs them in parallel too, each result
    // written by one task), so splitting them over threads changes nothing.
    let run = |range: std::ops::Range<usize>, np: &mut [[f32; 2]], st: &mut [bool], er: &mut [f32]| {
        let job = Job { prep, pts, range, max_level, crit, min_eig, scalar };
        run_job(&job, np, st, er);
    };

    #[cfg(not(target_arch = "wasm32"))]
    {
        // Within `par::with_threads`' cap: the odometry tracks on one core
        // while the detection workers take the others.
        let threads = crate::par::threads();
        if threads > 1 && n >= 64 {
            let chunk = n.div_ceil(threads);
            std::thread::scope(|s| {
                let mut start = 0;
                for ((np, st), er) in
                    next_pts.chunks_mut(chunk).zip(status.chunks_mut(chunk)).zip(err.chunks_mut(chunk))
                {
                    let range = start..start + np.len();
                    start += np.len();
                    let run = &run;
                    s.spawn(move || run(range, np, st, er));
                }
            });
            return LkResult { next_pts, status, err };
        }
    }
    run(0..n, &mut next_pts, &mut status, &mut err);
    LkResult { next_pts, status, err }
}

/// Pyramids and derivatives of a frame pair, built once per call.
struct Prepared<'a> {
    prev: &'a [Level],
    next: &'a [Level],
    derivs: Vec<Deriv>,
}

struct Job<'a> {
    prep: &'a Prepared<'a>,
    pts: &'a [[f32; 2]],
    range: std::ops::Range<usize>,
    max_level: usize,
    crit: (usize, f64),
    min_eig: f32,
    /// Forces the scalar kernels (tests compare both paths).
    scalar: bool,
}

/// Every level of the job's points, two points at a time: a point's
/// iterations form one chain (each window is placed by the previous
/// iteration's result), and the end of an iteration — the sums' reduction,
/// the step, the next window's weights and address — is a short serial
/// stretch the vector units sit out. With a second point's iteration next
/// in program order, its window work fills that stretch. Each point still
/// runs exactly its own iterations, so no result changes.
#[inline(always)]
fn run_job_body<K: Kernels>(job: &Job, np: &mut [[f32; 2]], st: &mut [bool], er: &mut [f32]) {
    let prep = job.prep;
    let mut patches = [K::new_patch(), K::new_patch()];
    for level in (0..=job.max_level).rev() {
        let cx = LevelCtx {
            prev: &prep.prev[level],
            deriv: &prep.derivs[level],
            next: &prep.next[level],
            level,
            max_level: job.max_level,
            crit: job.crit,
            min_eig_threshold: job.min_eig,
        };
        let mut lanes: [Option<Track>; 2] = [None, None];
        let mut todo = 0..job.range.len();
        loop {
            let mut busy = false;
            for (lane, patch) in lanes.iter_mut().zip(patches.iter_mut()) {
                while lane.is_none() {
                    let Some(k) = todo.next() else { break };
                    let i = job.range.start + k;
                    *lane = Track::start::<K>(&cx, k, job.pts[i], &mut np[k], &mut st[k], &mut er[k], patch);
                }
                if let Some(t) = lane {
                    let k = t.k;
                    if !t.step::<K>(&cx, &mut np[k], &mut st[k], &mut er[k], patch) {
                        *lane = None;
                    }
                    busy = true;
                }
            }
            if !busy {
                break;
            }
        }
    }
}

/// The loop compiled for AVX2 around the AVX2 window kernels: only integer
/// ops and separately rounded f32 adds/multiplies are involved (Rust never
/// contracts to FMA), so this changes the speed, not a bit of the result.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn run_job_avx2(job: &Job, np: &mut [[f32; 2]], st: &mut [bool], er: &mut [f32]) {
    run_job_body::<Avx2>(job, np, st, er)
}

/// The same loop around the AVX-512 BW mismatch kernel.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512bw,avx512f,avx2")]
fn run_job_avx512(job: &Job, np: &mut [[f32; 2]], st: &mut [bool], er: &mut [f32]) {
    run_job_body::<Avx512>(job, np, st, er)
}

/// The kernel set for the whole job: the fastest the CPU has, unless the
/// portable one is asked for. The choice is made once, outside the loop, so
/// that the whole loop is compiled for that kernel set and its features.
fn run_job(job: &Job, np: &mut [[f32; 2]], st: &mut [bool], er: &mut [f32]) {
    #[cfg(target_arch = "x86_64")]
    {
        if !job.scalar && crate::simd::avx512bw() {
            // SAFETY: the CPU supports AVX-512 F and BW (checked just above),
            // and every AVX-512 CPU has AVX2.
            unsafe { run_job_avx512(job, np, st, er) };
            return;
        }
        if !job.scalar && crate::simd::avx2() {
            // SAFETY: the CPU supports AVX2 (checked just above).
            unsafe { run_job_avx2(job, np, st, er) };
            return;
        }
    }
    #[cfg(all(target_arch = "wasm32", target_feature = "simd128"))]
    {
        if !job.scalar {
            return run_job_body::<Simd128>(job, np, st, er);
        }
    }
    run_job_body::<Scalar>(job, np, st, er)
}

/// One point at one level (LKTrackerInvoker::operator()), as a state that
/// advances one iteration at a time, so that [`run_job_body`] can keep two
/// points going side by side. `next` holds the stored estimate, updated in
/// place; `status`/`err` are only touched at level 0.
struct Track {
    /// Index of the point in the job's output slices.
    k: usize,
    a11: f32,
    a12: f32,
    a22: f32,
    dinv: f32,
    /// Window corner of the current estimate (`next − HALF_WIN`).
    n: [f32; 2],
    prev_delta: [f32; 2],
    /// Iterations done.
    j: usize,
}

/// What a level of one point needs from its job.
struct LevelCtx<'a> {
    prev: &'a Level,
    deriv: &'a Deriv,
    next: &'a Level,
    level: usize,
    max_level: usize,
    crit: (usize, f64),
    min_eig_threshold: f32,
}

impl Track {
    /// The guess, the template window and the structure tensor; `None` when
    /// the point is done at this level before any iteration.
    #[inline(always)]
    fn start<K: Kernels>(
        cx: &LevelCtx,
        k: usize,
        prev_pt: [f32; 2],
        next: &mut [f32; 2],
        status: &mut bool,
        err: &mut f32,
        patch: &mut K::Patch,
    ) -> Option<Track> {
        let level = cx.level;
        let scale = 1.0 / (1u32 << level) as f32;
        let p = [prev_pt[0] * scale, prev_pt[1] * scale];
        // §VO-2.4 "Initial guess": the point itself at the top level, below
        // it twice the coarser level's result, stored at once.
        let guess = if level == cx.max_level { p } else { [next[0] * 2.0, next[1] * 2.0] };
        *next = guess;

        let q = [p[0] - HALF_WIN, p[1] - HALF_WIN];
        let (ix, iy) = (q[0].floor() as i32, q[1].floor() as i32);
        if out_of_bounds(ix, iy, cx.prev.w, cx.prev.h) {
            // §VO-2.4 "Template window": skip the level; only level 0 sets
            // status 0 and err 0 (the one status-0 err OpenCV initialises).
            if level == 0 {
                *status = false;
                *err = 0.0;
            }
            return None;
        }
        let wts = weights(q[0] - ix as f32, q[1] - iy as f32);
        let (s11, s12, s22) = K::load_patch(cx.prev, cx.deriv, ix, iy, &wts, patch);
        let (a11, a12, a22) = (s11 * FLT_SCALE, s12 * FLT_SCALE, s22 * FLT_SCALE);
        // §VO-2.4 "Structure tensor": D and the smaller eigenvalue over the
        // window area 2·21², separately rounded f32 operations.
        let det = a11 * a22 - a12 * a12;
        let min_eig = (a22 + a11 - ((a11 - a22) * (a11 - a22) + 4.0 * a12 * a12).sqrt()) / (2 * WIN * WIN) as f32;
        if min_eig < cx.min_eig_threshold || det < f32::EPSILON {
            if level == 0 {
                *status = false;
            }
            return None;
        }
        if cx.crit.0 == 0 {
            Track::finish::<K>(cx, next, status, err, patch);
            return None;
        }
        Some(Track {
            k,
            a11,
            a12,
            a22,
            dinv: 1.0 / det,
            n: [guess[0] - HALF_WIN, guess[1] - HALF_WIN],
            prev_delta: [0.0; 2],
            j: 0,
        })
    }

    /// One iteration; false when the point is done at this level (then
    /// [`Track::finish`] has run).
    #[inline(always)]
    fn step<K: Kernels>(
        &mut self,
        cx: &LevelCtx,
        next: &mut [f32; 2],
        status: &mut bool,
        err: &mut f32,
        patch: &mut K::Patch,
    ) -> bool {
        let n = self.n;
        let (jx, jy) = (n[0].floor() as i32, n[1].floor() as i32);
        let go_on = if out_of_bounds(jx, jy, cx.next.w, cx.next.h) {
            if cx.level == 0 {
                *status = false;
            }
            false
        } else {
            let w = weights(n[0] - jx as f32, n[1] - jy as f32);
            let (b1, b2) = K::mismatch(cx.next, jx, jy, &w, patch);
            let (a11, a12, a22, dinv) = (self.a11, self.a12, self.a22, self.dinv);
            // §VO-2.4 steps 4 and 5: the step by the inverse tensor, no fusing.
            let delta = [(a12 * b2 - a22 * b1) * dinv, (a12 * b1 - a11 * b2) * dinv];
            self.n = [n[0] + delta[0], n[1] + delta[1]];
            *next = [self.n[0] + HALF_WIN, self.n[1] + HALF_WIN];
            let prev_delta = self.prev_delta;
            // §VO-2.4 step 6 (converged, in f64) is tested before step 7
            // (oscillation, from the second iteration), so a converged step
            // is never halved.
            if (delta[0] as f64) * (delta[0] as f64) + (delta[1] as f64) * (delta[1] as f64) <= cx.crit.1 {
                false
            } else if self.j > 0
                && ((delta[0] + prev_delta[0]).abs() as f64) < 0.01
                && ((delta[1] + prev_delta[1]).abs() as f64) < 0.01
            {
                // The step reversed itself: retreat half of it and stop.
                *next = [next[0] - delta[0] * 0.5, next[1] - delta[1] * 0.5];
                false
            } else {
                self.prev_delta = delta;
                self.j += 1;
                self.j < cx.crit.0
            }
        };
        if !go_on {
            Track::finish::<K>(cx, next, status, err, patch);
        }
        go_on
    }

    /// The error of a point still tracked after level 0 (§VO-2.5): the window
    /// at the final position again, Σ|J − T| over 21²·32.
    #[inline(always)]
    fn finish<K: Kernels>(cx: &LevelCtx, next: &[f32; 2], status: &mut bool, err: &mut f32, patch: &mut K::Patch) {
        if *status && cx.level == 0 {
            let m = [next[0] - HALF_WIN, next[1] - HALF_WIN];
            let (jx, jy) = (m[0].floor() as i32, m[1].floor() as i32);
            if out_of_bounds(jx, jy, cx.next.w, cx.next.h) {
                *status = false;
                return;
            }
            let w = weights(m[0] - jx as f32, m[1] - jy as f32);
            let errval = K::abs_diff_sum(cx.next, jx, jy, &w, patch);
            *err = errval / (32 * WIN * WIN) as f32;
        }
    }
}

/// §VO-2.4's bounds rule for a window corner: up to 21 pixels (the padding)
/// left of or above the level, never at or past its far edge.
#[inline]
fn out_of_bounds(ix: i32, iy: i32, w: usize, h: usize) -> bool {
    ix < -(WIN as i32) || ix >= w as i32 || iy < -(WIN as i32) || iy >= h as i32
}
