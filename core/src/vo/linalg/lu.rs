//! OpenCV's small LU inverse (docs/fidelity.md §VO-3.6), which eliminates
//! the five-point constraint matrix. Baseline code in OpenCV: plain f64
//! operations, no FMA.

/// `cv::invert(A, DECOMP_LU)` for an n×n block (§VO-3.6): `LUImpl<double>`
/// against the identity. Returns `None` where OpenCV would return an all-zero
/// inverse (pivot below 100·DBL_EPSILON).
pub fn lu_inverse(a: &[f64], n: usize) -> Option<Vec<f64>> {
    let mut a = a.to_vec();
    let mut b = vec![0.0; n * n];
    for i in 0..n {
        b[i * n + i] = 1.0;
    }
    let eps = f64::EPSILON * 100.0;
    for i in 0..n {
        let mut k = i;
        for j in i + 1..n {
            if a[j * n + i].abs() > a[k * n + i].abs() {
                k = j;
            }
        }
        if a[k * n + i].abs() < eps {
            return None;
        }
        if k != i {
            for j in i..n {
                a.swap(i * n + j, k * n + j);
            }
            for j in 0..n {
                b.swap(i * n + j, k * n + j);
            }
        }
        let d = -1.0 / a[i * n + i];
        for j in i + 1..n {
            let alpha = a[j * n + i] * d;
            for k in i + 1..n {
                a[j * n + k] += alpha * a[i * n + k];
            }
            for k in 0..n {
                b[j * n + k] += alpha * b[i * n + k];
            }
        }
    }
    for i in (0..n).rev() {
        for j in 0..n {
            let mut s = b[i * n + j];
            for k in i + 1..n {
                s -= a[i * n + k] * b[k * n + j];
            }
            b[i * n + j] = s / a[i * n + i];
        }
    }
    Some(b)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lu_inverse_inverts_and_flags_singular() {
        let a = [2.0, 1.0, 0.0, 1.0, 3.0, 1.0, 0.0, 1.0, 4.0];
        let inv = lu_inverse(&a, 3).unwrap();
        for r in 0..3 {
            for c in 0..3 {
                let v: f64 = (0..3).map(|k| a[r * 3 + k] * inv[k * 3 + c]).sum();
                assert!((v - if r == c { 1.0 } else { 0.0 }).abs() < 1e-15);
            }
        }
        assert!(lu_inverse(&[1.0, 2.0, 2.0, 4.0], 2).is_none());
    }
}
