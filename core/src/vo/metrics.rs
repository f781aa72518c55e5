//! Trajectory scores as the comparison scripts report them: absolute
//! trajectory error (RMSE of position differences, no alignment: the lab's
//! estimate is already in ground-truth scale) and per-frame differences.

use crate::{Error, Result};

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
