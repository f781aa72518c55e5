//! Trajectory scores as the comparison scripts report them: absolute
//! trajectory error (RMSE of position differences, no alignment: the lab's
//! estimate is already in ground-truth scale) and per-frame differences.

use crate::{Error, Result};

/// Euclidean distance of two 3-D points, accurately rounded like Python's
/// `math.dist` (the lab's scale): the sum of squares is kept as a
/// double-double (exact products by FMA, TwoSum), then the square root gets
/// one Newton correction. A plain `sqrt(dx²+dy²+dz²)` can be off by one ulp.
pub fn dist3(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    let (mut hi, mut lo) = (0.0f64, 0.0f64);
    for k in 0..3 {
        let d = a[k] - b[k];
        let p = d * d;
        let pe = d.mul_add(d, -p);
        // TwoSum(hi, p)
        let s = hi + p;
        let bb = s - hi;
        let e = (hi - (s - bb)) + (p - bb);
        hi = s;
        lo += e + pe;
    }
    let s = hi + lo;
    let lo = lo - (s - hi);
    if s == 0.0 || !s.is_finite() {
        return s.sqrt();
    }
    let h = s.sqrt();
    // Residual (s + lo) − h², with h² exact via FMA.
    let hh = h * h;
    let hh_err = h.mul_add(h, -hh);
    let r = ((s - hh) - hh_err) + lo;
    h + r / (2.0 * h)
}

/// Root mean square of the position differences.
pub fn ate_rmse(est: &[[f64; 3]], gt: &[[f64; 3]]) -> Result<f64> {
    if est.len() != gt.len() || est.is_empty() {
        return Err(Error::InvalidArgument(format!(
            "trajectory error needs the same non-zero number of estimated and ground-truth \
             positions ({} vs {})",
            est.len(),
            gt.len()
        )));
    }
    let sum: f64 = est.iter().zip(gt).map(|(e, g)| (0..3).map(|k| (e[k] - g[k]) * (e[k] - g[k])).sum::<f64>()).sum();
    Ok((sum / est.len() as f64).sqrt())
}

/// Euclidean distance between the two trajectories, frame by frame.
pub fn position_differences(a: &[[f64; 3]], b: &[[f64; 3]]) -> Vec<f64> {
    a.iter().zip(b).map(|(p, q)| (0..3).map(|k| (p[k] - q[k]) * (p[k] - q[k])).sum::<f64>().sqrt()).collect()
}

/// (max, median) of a list of non-negative numbers; (0, 0) when empty.
pub fn max_median(v: &[f64]) -> (f64, f64) {
    if v.is_empty() {
        return (0.0, 0.0);
    }
    let mut s = v.to_vec();
    s.sort_by(|a, b| a.total_cmp(b));
    let n = s.len();
    let med = if n % 2 == 1 { s[n / 2] } else { (s[n / 2 - 1] + s[n / 2]) / 2.0 };
    (s[n - 1], med)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dist_is_accurately_rounded() {
        assert_eq!(dist3(&[0.0; 3], &[3.0, 4.0, 12.0]), 13.0);
        // math.dist((0.1, 0.2, 0.3), (0.4, 0.5, 0.6)) in CPython 3.11.
        assert_eq!(dist3(&[0.1, 0.2, 0.3], &[0.4, 0.5, 0.6]), 0.5196152422706632);
        // math.dist((-0.4686, -0.0283, 1.3347), (-0.9381, -0.0511, 2.1234)) in CPython 3.11.
        assert_eq!(dist3(&[-0.4686, -0.0283, 1.3347], &[-0.9381, -0.0511, 2.1234]), 0.9181491055378752);
    }

    #[test]
    fn ate_and_differences() {
        let gt = [[0.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0, 2.0]];
        let est = [[0.0, 0.0, 0.0], [0.0, 0.0, 1.3], [0.4, 0.0, 2.0]];
        let ate = ate_rmse(&est, &gt).unwrap();
        assert!((ate - (0.25f64 / 3.0).sqrt()).abs() < 1e-15);
        let d = position_differences(&est, &gt);
        assert_eq!(max_median(&d), (0.4, d[1]));
        assert!(ate_rmse(&est, &gt[..2]).is_err());
    }
}
