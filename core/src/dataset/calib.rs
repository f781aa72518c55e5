//! KITTI's `calib.txt`: one line per camera, `P0:` … `P3:` (3×4 projection
//! matrices, row-major) and `Tr:`. The odometry uses camera 0 (`image_0`):
//! fx = P0[0], cx = P0[2], fy = P0[5], cy = P0[6]. The lab hard-codes
//! sequence 00's values, which are exactly its `calib.txt`'s.

use crate::camera::Camera;
use crate::{Error, Result};

/// Camera 0's intrinsics from `calib.txt` text; `file` names it in errors.
pub fn parse_calib(text: &str, file: &str) -> Result<Camera> {
    let bad = |n: usize, what: String| {
        Error::Dataset(format!(
            "{file} line {n}: {what}; KITTI's P0 line is `P0:` and 12 numbers (the 3x4 projection of camera 0)"
        ))
    };
    for (n, line) in text.lines().enumerate() {
        let Some(rest) = line.trim_start().strip_prefix("P0:") else { continue };
        let fields: Vec<&str> = rest.split_whitespace().collect();
        if fields.len() != 12 {
            return Err(bad(n + 1, format!("P0 has {} numbers, not 12", fields.len())));
        }
        let mut p = [0.0f64; 12];
        for (k, f) in fields.iter().enumerate() {
            p[k] = f.parse().map_err(|_| bad(n + 1, format!("P0 number {} ({f:?}) is not a number", k + 1)))?;
        }
        let cam = Camera { fx: p[0], fy: p[5], cx: p[2], cy: p[6] };
        cam.validate().map_err(|e| bad(n + 1, e.to_string()))?;
        return Ok(cam);
    }
    Err(Error::Dataset(format!(
        "{file} has no `P0:` line: siftlab takes camera 0's intrinsics from it (fx, cx, fy, cy = P0[0], P0[2], P0[5], P0[6])"
    )))
}

/// `fx = fy = 718.856, cx = 607.1928, cy = 185.2157`: a camera as a user reads it.
pub fn describe_camera(c: &Camera) -> String {
    if c.fx == c.fy {
        format!("fx = fy = {}, cx = {}, cy = {}", c.fx, c.cx, c.cy)
    } else {
        format!("fx = {}, fy = {}, cx = {}, cy = {}", c.fx, c.fy, c.cx, c.cy)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// KITTI's sequences/00/calib.txt (first two lines).
    const SEQ00: &str = "P0: 7.188560000000e+02 0.000000000000e+00 6.071928000000e+02 0.000000000000e+00 \
        0.000000000000e+00 7.188560000000e+02 1.852157000000e+02 0.000000000000e+00 0.000000000000e+00 \
        0.000000000000e+00 1.000000000000e+00 0.000000000000e+00\n\
        P1: 7.188560000000e+02 0.000000000000e+00 6.071928000000e+02 -3.861448000000e+02 0.000000000000e+00 \
        7.188560000000e+02 1.852157000000e+02 0.000000000000e+00 0.000000000000e+00 0.000000000000e+00 \
        1.000000000000e+00 0.000000000000e+00\n";

    #[test]
    fn sequence_00_gives_the_labs_camera() {
        assert_eq!(parse_calib(SEQ00, "calib.txt").unwrap(), Camera::default());
        assert_eq!(describe_camera(&Camera::default()), "fx = fy = 718.856, cx = 607.1928, cy = 185.2157");
    }

    #[test]
    fn p0_is_read_wherever_it_is() {
        let text = "Tr: 1 0 0 0 0 1 0 0 0 0 1 0\nP0: 721.5377 0 609.5593 0 0 721.5377 172.854 0 0 0 1 0\n";
        let c = parse_calib(text, "sequences/03/calib.txt").unwrap();
        assert_eq!(c, Camera { fx: 721.5377, fy: 721.5377, cx: 609.5593, cy: 172.854 });
    }

    #[test]
    fn malformed_p0_lines_are_named() {
        let e = |t: &str| parse_calib(t, "sequences/03/calib.txt").unwrap_err().to_string();
        assert_eq!(
            e("P1: 1 2 3\n"),
            "sequences/03/calib.txt has no `P0:` line: siftlab takes camera 0's intrinsics from it \
             (fx, cx, fy, cy = P0[0], P0[2], P0[5], P0[6])"
        );
        assert!(e("P0: 1 2 3\n").starts_with("sequences/03/calib.txt line 1: P0 has 3 numbers, not 12; KITTI's P0"));
        assert!(e("\nP0: 7 0 6 0 0 7 1 0 0 0 1 x\n").contains("line 2: P0 number 12 (\"x\") is not a number"));
        assert!(e("P0: 0 0 6 0 0 7 1 0 0 0 1 0\n").contains("line 1: invalid camera intrinsics fx=0"));
        assert!(e("P0: nan 0 6 0 0 7 1 0 0 0 1 0\n").contains("invalid camera intrinsics"));
    }
}
