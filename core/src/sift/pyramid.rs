//! Gaussian and difference-of-Gaussians pyramids (docs/fidelity.md §SIFT-4, §SIFT-5).

use super::blur::gaussian_blur;
use super::image::Plane;
use super::num::rne64;

/// Number of octaves of the doubled base: `rne(log2(min(w, h)) − 2) + 1`
/// with natural logs in f64, as OpenCV writes it.
pub fn octave_count(base_w: usize, base_h: usize) -> usize {
    let m = base_w.min(base_h);
    if m < 2 {
        return 0;
    }
    let n = rne64((m as f64).ln() / 2f64.ln() - 2.0) + 1;
    n.max(0) as usize
}

/// Incremental σ of each level so level i has total σ·k^i (f64, no FMA; §SIFT-4).
pub fn level_sigmas(sigma: f64, layers: usize) -> Vec<f64> {
    let mut sig = vec![sigma; layers + 3];
    let k = 2f64.powf(1.0 / layers as f64);
    for (i, s) in sig.iter_mut().enumerate().skip(1) {
        let sig_prev = k.powf((i - 1) as f64) * sigma;
        let sig_total = sig_prev * k;
        *s = (sig_total * sig_total - sig_prev * sig_prev).sqrt();
    }
    sig
}

/// The `sig.len()` Gaussian levels of one octave from its first level, each
/// blurred from the one before by `sig[i]`; the pyramid is `octaves` of
/// these, octave o + 1 starting from [`next_octave_base`] of octave o.
/// OpenCV also stores the `layers + 2` DoG levels (level i+1 − level i);
/// here the extrema scan takes those differences row by row as it goes, the
/// same f32 subtractions, instead of writing five more planes per octave
/// and reading them back three times.
pub fn octave_levels(first: Plane, sig: &[f64]) -> Vec<Plane> {
    let mut levels = Vec::with_capacity(sig.len());
    levels.push(first);
    for &s in &sig[1..] {
        let level = gaussian_blur(&levels[levels.len() - 1], s);
        levels.push(level);
    }
    levels
}

/// The first level of the next octave (§SIFT-4): INTER_NEAREST to (w/2, h/2) of the
/// level with twice the octave's base σ (level `layers`); for these sizes it
/// always samples src[2y][2x].
pub fn next_octave_base(levels: &[Plane], layers: usize) -> Plane {
    downsample(&levels[layers])
}

fn downsample(src: &Plane) -> Plane {
    let (w, h) = (src.width / 2, src.height / 2);
    let mut out = Plane::for_overwrite(w, h);
    for y in 0..h {
        let s = src.row(2 * y);
        let d = out.row_mut(y);
        // Eight output pixels from sixteen source pixels at a time (one at
        // a time the loop waited on every fresh output line: 1.4 % of a VO
        // profile, 1.0 % so), the rest one by one.
        let groups = w / 8;
        // The next source row is two plane rows on: the hardware prefetcher
        // does not follow that stride, so each of its lines is asked for
        // while this row's line at the same place is read.
        let next = (2 * y + 2 < src.height).then(|| src.row(2 * y + 2));
        for (g, (d8, s16)) in d.chunks_exact_mut(8).zip(s.chunks_exact(16)).enumerate() {
            if let Some(n) = next {
                prefetch(&n[16 * g..]);
            }
            let mut v = [0f32; 8];
            for (k, e) in v.iter_mut().enumerate() {
                *e = s16[2 * k];
            }
            d8.copy_from_slice(&v);
        }
        for x in 8 * groups..w {
            d[x] = s[2 * x];
        }
    }
    out
}

/// Asks for the cache line holding `s[0]`.
#[inline(always)]
fn prefetch(s: &[f32]) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: a prefetch never faults, and the address is inside `s`.
    unsafe {
        std::arch::x86_64::_mm_prefetch::<{ std::arch::x86_64::_MM_HINT_T0 }>(s.as_ptr().cast())
    };
    #[cfg(not(target_arch = "x86_64"))]
    let _ = s;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sigmas_match_spec() {
        let s = level_sigmas(1.6, 3);
        assert_eq!(s[1], 1.2262734984654078);
        assert_eq!(s[2], 1.5450077936447955);
        assert_eq!(s[3], 1.9465878414647133);
        assert_eq!(s[4], 2.4525469969308156);
        assert_eq!(s[5], 3.090015587289591);
    }

    #[test]
    fn downsample_takes_every_other_pixel_of_every_other_row() {
        // Widths with and without a remainder after the groups of eight.
        for (w, h) in [(21, 5), (32, 4), (7, 3), (2, 2)] {
            let mut src = Plane::new(w, h);
            for y in 0..h {
                for (x, v) in src.row_mut(y).iter_mut().enumerate() {
                    *v = (100 * y + x) as f32;
                }
            }
            let d = downsample(&src);
            assert_eq!((d.width, d.height), (w / 2, h / 2));
            for y in 0..h / 2 {
                let expected: Vec<f32> = (0..w / 2).map(|x| (200 * y + 2 * x) as f32).collect();
                assert_eq!(d.row(y), &expected[..], "{w}x{h} row {y}");
            }
        }
    }

    #[test]
    fn octaves_for_common_sizes() {
        assert_eq!(octave_count(1280, 960), 9); // 640x480 input
        assert_eq!(octave_count(2482, 752), 9); // KITTI 1241x376
        assert_eq!(octave_count(2, 2), 0);
    }
}
