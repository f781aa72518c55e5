//! KITTI's ground-truth poses (`poses/NN.txt`: one 3×4 [R|t] per line) and
//! the lab's scale taken from them.

use crate::{Error, Result};

/// The lab's ground-truth poses (sequence 00), relative to the dataset root.
pub const POSES_FILE: &str = "poses/00.txt";

/// A KITTI pose line: the 3×4 matrix [R|t], row-major.
pub type PoseRow = [f64; 12];

/// The camera position of a pose (elements 3, 7, 11).
pub fn position(p: &PoseRow) -> [f64; 3] {
    [p[3], p[7], p[11]]
}

/// Checks that `file` (holding `have` poses) covers frames 0 … n − 1 before
/// an odometry run reads any frame: the lab's loop takes each frame's scale
/// from its true pose, so a short file would fail the run part way through.
/// The one check the CLI, the app's loader and its tracking worker all make.
pub fn check_pose_count(file: &str, have: usize, n: usize) -> Result<()> {
    if have >= n {
        return Ok(());
    }
    Err(Error::Dataset(format!(
        "{file} has {have} poses but the odometry needs {n} (frames 0 to {}): the lab takes each frame's scale \
         from its ground-truth pose",
        n - 1
    )))
}

/// Parses KITTI pose text: 12 numbers per non-empty line, separated by
/// whitespace. Errors name the line (1-based) and what is wrong with it.
pub fn parse_poses(text: &str) -> Result<Vec<PoseRow>> {
    parse_poses_in(text, POSES_FILE)
}

/// [`parse_poses`] for the file `file` (`poses/03.txt`), named in errors.
pub fn parse_poses_in(text: &str, file: &str) -> Result<Vec<PoseRow>> {
    let mut poses = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() {
            continue;
        }
        let fields: Vec<&str> = line.split_whitespace().collect();
        if fields.len() != 12 {
            return Err(Error::Dataset(format!(
                "{file} line {}: expected 12 numbers (a 3x4 [R|t] matrix), found {}",
                n + 1,
                fields.len()
            )));
        }
        let mut row = [0.0; 12];
        for (k, f) in fields.iter().enumerate() {
            // Rust's parse is correctly rounded, like Python's float().
            let v: f64 = f.parse().map_err(|_| {
                Error::Dataset(format!("{file} line {}: field {} ({f:?}) is not a number", n + 1, k + 1))
            })?;
            if !v.is_finite() {
                return Err(Error::Dataset(format!("{file} line {}: field {} ({f:?}) is not finite", n + 1, k + 1)));
            }
            row[k] = v;
        }
        poses.push(row);
    }
    if poses.is_empty() {
        return Err(Error::Dataset(format!("{file} is empty: it needs one pose line per frame")));
    }
    Ok(poses)
}

/// The lab's scale for frame `i`: the Euclidean distance between the ground
/// truth positions of frames i−1 and i, accurately rounded as `math.dist`.
pub fn gt_scale(poses: &[PoseRow], i: usize) -> Result<f64> {
    if i == 0 || i >= poses.len() {
        return Err(Error::Dataset(format!(
            "no ground-truth scale for frame {i}: the poses file has {} poses (the scale of \
             frame i needs poses i-1 and i)",
            poses.len()
        )));
    }
    Ok(dist3(&position(&poses[i - 1]), &position(&poses[i])))
}

/// Euclidean distance of two 3-D points, accurately rounded like Python's
/// `math.dist` (the lab's scale): the sum of squares is kept as a
/// double-double (exact products by FMA, TwoSum), then the square root gets
/// one Newton correction. A plain `sqrt(dx²+dy²+dz²)` can be off by one ulp.
pub fn dist3(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    // Squares of differences above ~1e154 overflow (the error terms become
    // inf - inf = NaN) and below ~1e-154 underflow, where math.dist still
    // gives the distance: such points are scaled by a power of two first.
    // Real poses never get here, so their results keep every bit (found by
    // fuzzing, tests/fuzz/regressions/poses).
    let m = (0..3).map(|k| (a[k] - b[k]).abs()).fold(0.0f64, f64::max);
    if m != 0.0 && !(TINY..=HUGE).contains(&m) && a.iter().chain(b).all(|v| v.is_finite()) {
        // Both points times the same power of two (exact); an overflowed
        // difference (m = inf) is brought in range by a second pass.
        let k = if m.is_finite() { m.log2().floor() as i32 } else { 4 };
        let s = 2f64.powi(-k);
        let (sa, sb) = (a.map(|v| v * s), b.map(|v| v * s));
        return dist3(&sa, &sb) * 2f64.powi(k);
    }
    dist3_unscaled(a, b)
}

const HUGE: f64 = 1.0e150;
const TINY: f64 = 1.0e-150;

fn dist3_unscaled(a: &[f64; 3], b: &[f64; 3]) -> f64 {
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

#[cfg(test)]
mod tests {
    use super::*;

    const TWO: &str = "1 0 0 0 0 1 0 0 0 0 1 0\n\
        9.999978e-01 5.272628e-04 -2.066935e-03 -4.690294e-02 -5.296506e-04 9.999992e-01 -1.154865e-03 -2.839928e-02 2.066324e-03 1.155958e-03 9.999971e-01 8.586941e-01\n";

    #[test]
    fn a_short_poses_file_is_named_with_the_frames_it_lacks() {
        assert!(check_pose_count("poses/03.txt", 3, 3).is_ok());
        let e = check_pose_count("poses/03.txt", 2, 3).unwrap_err().to_string();
        assert_eq!(
            e,
            "poses/03.txt has 2 poses but the odometry needs 3 (frames 0 to 2): the lab takes each frame's scale \
             from its ground-truth pose"
        );
    }

    #[test]
    fn parses_kitti_lines() {
        let p = parse_poses(TWO).unwrap();
        assert_eq!(p.len(), 2);
        assert_eq!(position(&p[1]), [-4.690294e-02, -2.839928e-02, 8.586941e-01]);
        // math.dist((0,0,0), (-4.690294e-02, -2.839928e-02, 8.586941e-01))
        assert_eq!(gt_scale(&p, 1).unwrap(), 0.8604428872737412);
        assert!(gt_scale(&p, 2).is_err());
    }

    #[test]
    fn dist_is_accurately_rounded() {
        assert_eq!(dist3(&[0.0; 3], &[3.0, 4.0, 12.0]), 13.0);
        // math.dist((0.1, 0.2, 0.3), (0.4, 0.5, 0.6)) in CPython 3.11.
        assert_eq!(dist3(&[0.1, 0.2, 0.3], &[0.4, 0.5, 0.6]), 0.5196152422706632);
        // math.dist((-0.4686, -0.0283, 1.3347), (-0.9381, -0.0511, 2.1234)) in CPython 3.11.
        assert_eq!(dist3(&[-0.4686, -0.0283, 1.3347], &[-0.9381, -0.0511, 2.1234]), 0.9181491055378752);
    }

    #[test]
    fn huge_and_tiny_distances_are_finite_like_math_dist() {
        // math.dist((0, 0, 0), (1e200, 0, 0)) == 1e200; math.dist((0,0,0), (3e-200, 4e-200, 0)) == 5e-200.
        assert_eq!(dist3(&[0.0; 3], &[1e200, 0.0, 0.0]), 1e200);
        assert_eq!(dist3(&[-1e300, 0.0, 0.0], &[1e300, 0.0, 0.0]), 2e300);
        assert_eq!(dist3(&[-f64::MAX, 0.0, 0.0], &[f64::MAX, 0.0, 0.0]), f64::INFINITY);
        let d = dist3(&[0.0; 3], &[3e-200, 4e-200, 0.0]);
        assert!((d - 5e-200).abs() <= 5e-200 * 1e-15, "{d}");
    }

    #[test]
    fn malformed_lines_are_named() {
        let e = parse_poses("1 0 0 0 0 1 0 0 0 0 1 0\n1 2 3\n").unwrap_err();
        assert_eq!(e.to_string(), "poses/00.txt line 2: expected 12 numbers (a 3x4 [R|t] matrix), found 3");
        let e = parse_poses("\n1 0 0 0 0 1 0 x 0 0 1 0\n").unwrap_err();
        assert_eq!(e.to_string(), "poses/00.txt line 2: field 8 (\"x\") is not a number");
        let e = parse_poses("1 0 0 0 0 1 0 0 0 0 1 nan\n").unwrap_err();
        assert!(e.to_string().contains("line 1: field 12"), "{e}");
        assert!(parse_poses("\n \n").unwrap_err().to_string().contains("empty"));
    }
}
