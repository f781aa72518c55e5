//! `cv::solvePoly` (docs/fidelity.md §VO-3.7): Durand–Kerner in complex
//! f64, the roots of the five-point solver's degree-10 polynomial. Baseline
//! code in OpenCV: plain f64 operations, no FMA.

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Complex {
    pub re: f64,
    pub im: f64,
}

impl Complex {
    const fn new(re: f64, im: f64) -> Self {
        Complex { re, im }
    }
    #[inline]
    fn mul(self, o: Complex) -> Complex {
        Complex::new(self.re * o.re - self.im * o.im, self.re * o.im + self.im * o.re)
    }
    #[inline]
    fn add(self, o: Complex) -> Complex {
        Complex::new(self.re + o.re, self.im + o.im)
    }
    #[inline]
    fn sub(self, o: Complex) -> Complex {
        Complex::new(self.re - o.re, self.im - o.im)
    }
    /// `cv::Complex` division: one reciprocal of |o|², then two products.
    #[inline]
    fn div(self, o: Complex) -> Complex {
        let t = 1.0 / (o.re * o.re + o.im * o.im);
        Complex::new((self.re * o.re + self.im * o.im) * t, (-self.re * o.im + self.im * o.re) * t)
    }
}

/// `cv::solvePoly` (§VO-3.7): Durand–Kerner with in-place updates. `c[k]` is the
/// coefficient of z^k. Returns the roots in index order.
pub fn solve_poly(c: &[f64], max_iters: usize) -> Vec<Complex> {
    durand_kerner(c, max_iters, true).0
}

/// OpenCV runs all `max_iters` sweeps unless every step is exactly 0, which
/// converged roots rarely reach: rounding leaves them cycling through a few
/// states whose last bits differ (periods of 1 to 12 sweeps, entered after
/// 15 to 50). A sweep is a function of the roots alone, so once a state
/// repeats, every later state is known: with `skip_cycles` the roots after
/// `max_iters` sweeps are read from the cycle instead of computed — OpenCV's
/// roots, bit for bit (the 300 sweeps were 85 % of findEssentialMat). Some
/// polynomials never repeat within 300 sweeps (their last bits wander) and
/// still take all of them. Returns the roots and the sweeps computed.
fn durand_kerner(c: &[f64], max_iters: usize, skip_cycles: bool) -> (Vec<Complex>, usize) {
    let n0 = c.len().saturating_sub(1);
    let coeffs: Vec<Complex> = c.iter().map(|&v| Complex::new(v, 0.0)).collect();
    let mut n = n0;
    while n > 1 {
        // An absolute test on the leading coefficient, as OpenCV writes it.
        if coeffs[n].re.abs() + coeffs[n].im.abs() > f64::EPSILON {
            break;
        }
        n -= 1;
    }
    let mut roots = vec![Complex::new(0.0, 0.0); n0];
    let mut p = Complex::new(1.0, 0.0);
    let r = Complex::new(1.0, 1.0);
    for root in roots.iter_mut().take(n) {
        *root = p;
        p = p.mul(r);
    }
    // history[t·n..] = the roots after t sweeps, fingerprints[t] a hash of
    // their bits (the states are compared in full when the hashes agree).
    let fingerprint = |r: &[Complex]| {
        r.iter()
            .flat_map(|z| [z.re.to_bits(), z.im.to_bits()])
            .fold(0u64, |h, v| (h ^ v).wrapping_mul(0x9E37_79B9_7F4A_7C15).rotate_left(29))
    };
    let same = |a: &[Complex], b: &[Complex]| {
        a.iter().zip(b).all(|(x, y)| x.re.to_bits() == y.re.to_bits() && x.im.to_bits() == y.im.to_bits())
    };
    let mut history: Vec<Complex> = Vec::new();
    let mut fingerprints: Vec<u64> = Vec::new();
    let mut sweeps = 0;
    while sweeps < max_iters {
        if skip_cycles {
            let f = fingerprint(&roots[..n]);
            let repeat = (0..sweeps).find(|&t| fingerprints[t] == f && same(&history[t * n..(t + 1) * n], &roots[..n]));
            if let Some(first) = repeat {
                // States first..sweeps−1 repeat forever, and each of them
                // moved a root (else the loop had stopped): no early stop
                // comes, and the last state is the cycle's entry at max_iters.
                let t = first + (max_iters - first) % (sweeps - first);
                roots[..n].copy_from_slice(&history[t * n..(t + 1) * n]);
                break;
            }
            fingerprints.push(f);
            history.extend_from_slice(&roots[..n]);
        }
        sweeps += 1;
        if !sweep(&coeffs[..=n], &mut roots[..n]) {
            break;
        }
    }
    for root in roots.iter_mut() {
        if root.im.abs() < 1e-100 {
            root.im = 0.0;
        }
    }
    roots.truncate(n);
    (roots, sweeps)
}

/// One Durand–Kerner sweep over `roots` in place, for the polynomial of
/// degree `roots.len()` with coefficients `coeffs` (ascending). Returns
/// whether OpenCV's maxDiff became positive (else it stops).
fn sweep(coeffs: &[Complex], roots: &mut [Complex]) -> bool {
    let n = roots.len();
    // OpenCV keeps maxDiff = max(maxDiff, |Δ|) and stops when it is 0; only
    // "is it still 0" matters, so the hypot is replaced by the exact test
    // of when it is positive (see `moved`).
    let mut changed = false;
    for i in 0..n {
        let p = roots[i];
        let mut num = coeffs[n];
        let mut den = coeffs[n];
        for j in 0..n {
            num = num.mul(p).add(coeffs[n - j - 1]);
            if j != i {
                let d = p.sub(roots[j]);
                // OpenCV skips an exactly coinciding root (p == roots[j]).
                if d.re != 0.0 || d.im != 0.0 {
                    den = den.mul(d);
                }
            }
        }
        let delta = num.div(den);
        roots[i] = p.sub(delta);
        changed |= moved(delta);
    }
    changed
}

/// Whether `std::max(maxDiff, hypot(Δ))` makes a zero maxDiff positive:
/// hypot is +inf when a part is infinite (even with a NaN beside it), NaN
/// when a part is NaN otherwise (and max keeps the 0 then), and positive
/// for any finite Δ ≠ 0 (it does not underflow).
#[inline]
fn moved(d: Complex) -> bool {
    d.re.is_infinite() || d.im.is_infinite() || (!d.re.is_nan() && !d.im.is_nan() && (d.re != 0.0 || d.im != 0.0))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::CvRng;

    #[test]
    fn moved_is_hypot_making_max_positive() {
        let v = [0.0, -0.0, 5e-324, -1e-300, 1.0, f64::INFINITY, f64::NEG_INFINITY, f64::NAN];
        for &re in &v {
            for &im in &v {
                let d = Complex::new(re, im);
                assert_eq!(moved(d), 0.0f64.max(re.hypot(im)) > 0.0, "{re} {im}");
            }
        }
    }

    #[test]
    fn solve_poly_finds_known_roots_in_start_order() {
        // (z-1)(z-2)(z+3) = z^3 - 7z + 6
        let roots = solve_poly(&[6.0, -7.0, 0.0, 1.0], 300);
        assert_eq!(roots.len(), 3);
        let mut re: Vec<f64> = roots.iter().map(|r| r.re).collect();
        for r in &roots {
            assert!(r.im.abs() < 1e-10);
        }
        re.sort_by(|a, b| a.partial_cmp(b).unwrap());
        for (got, want) in re.iter().zip([-3.0, 1.0, 2.0]) {
            assert!((got - want).abs() < 1e-12, "{got}");
        }
        // z^2 + 1: a complex pair.
        let roots = solve_poly(&[1.0, 0.0, 1.0], 300);
        assert!(roots.iter().all(|r| (r.im.abs() - 1.0).abs() < 1e-12 && r.re.abs() < 1e-12));
    }

    /// Reading the roots off a cycle gives those of all 300 sweeps bit for
    /// bit, and does save sweeps, on the five-point solver's kind of input:
    /// degree 10, real roots and complex pairs over several magnitudes
    /// (expanded from chosen roots), and plain random coefficients.
    #[test]
    fn solve_poly_skips_cycles_with_the_full_runs_roots() {
        let mut rng = CvRng::new(24011);
        let mut unit = || rng.next_u32() as f64 / u32::MAX as f64 * 2.0 - 1.0;
        let mut sweeps = Vec::new();
        for case in 0..300 {
            let c: Vec<f64> = if case % 2 == 0 {
                // Π (z − rₖ), rₖ real or in conjugate pairs, |rₖ| from 1e-3 to 1e3.
                let mut poly = vec![Complex::new(1.0, 0.0)];
                while poly.len() < 11 {
                    let scale = 10f64.powf(3.0 * unit());
                    let root = Complex::new(
                        scale * unit(),
                        if poly.len() < 10 && unit() > 0.0 { scale * unit() } else { 0.0 },
                    );
                    let pair = if root.im != 0.0 { vec![root, Complex::new(root.re, -root.im)] } else { vec![root] };
                    for r in pair {
                        let mut next = vec![Complex::new(0.0, 0.0); poly.len() + 1];
                        for (k, &a) in poly.iter().enumerate() {
                            next[k + 1] = next[k + 1].add(a);
                            next[k] = next[k].sub(a.mul(r));
                        }
                        poly = next;
                    }
                }
                poly.iter().map(|z| z.re).collect()
            } else {
                (0..11).map(|_| unit() * 10f64.powf(2.0 * unit())).collect()
            };
            let (fast, n) = durand_kerner(&c, 300, true);
            let (full, m) = durand_kerner(&c, 300, false);
            let bits = |r: &[Complex]| r.iter().map(|z| (z.re.to_bits(), z.im.to_bits())).collect::<Vec<_>>();
            assert_eq!(bits(&fast), bits(&full), "case {case}: {c:?}");
            assert!(n <= m);
            sweeps.push(n);
        }
        sweeps.sort();
        let median = sweeps[sweeps.len() / 2];
        assert!(median < 100, "median sweeps {median}: cycles are no longer skipped");
        eprintln!("solve_poly sweeps: median {median}, max {}", sweeps[sweeps.len() - 1]);
    }
}
