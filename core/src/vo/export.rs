//! Pose files of an odometry run: the KITTI format (12 numbers a line, what
//! the lab's poses file holds) and the TUM format that `evo` and the TUM RGB-D
//! tools read (`timestamp x y z qx qy qz qw`).

use super::linalg::{Mat3, Vec3};
use super::odometry::pose_row;
use crate::dataset::PoseRow;
use crate::pyfmt::py_float;
use nalgebra::{Matrix3, Rotation3, UnitQuaternion};

/// KITTI lines, one per (R, position), numbers as Python prints them.
pub fn kitti_text(poses: &[(Mat3, Vec3)]) -> String {
    let rows: Vec<PoseRow> = poses.iter().map(|(r, t)| pose_row(r, t)).collect();
    kitti_rows_text(&rows)
}

/// [`kitti_text`] of poses already as KITTI rows (what the app's worker keeps).
pub fn kitti_rows_text(rows: &[PoseRow]) -> String {
    rows.iter().map(|row| row.iter().map(|v| py_float(*v)).collect::<Vec<_>>().join(" ") + "\n").collect()
}

/// The unit quaternion (x, y, z, w) of `r`, w ≥ 0 (q and −q are the same turn).
pub fn quaternion(r: &Mat3) -> [f64; 4] {
    let m = Matrix3::from_fn(|i, j| r[i][j]);
    let q = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(m));
    let s = if q.w < 0.0 { -1.0 } else { 1.0 };
    [s * q.i, s * q.j, s * q.k, s * q.w]
}

/// TUM lines: frame i at i/10 s (KITTI's 10 Hz), position, rotation as a quaternion.
pub fn tum_text(poses: &[(Mat3, Vec3)]) -> String {
    poses
        .iter()
        .enumerate()
        .map(|(i, (r, t))| {
            let q = quaternion(r);
            format!(
                "{:.1} {:?} {:?} {:?} {:?} {:?} {:?} {:?}\n",
                i as f64 / 10.0,
                t[0],
                t[1],
                t[2],
                q[0],
                q[1],
                q[2],
                q[3]
            )
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tum_lines_and_quaternions() {
        let (c, s) = (0.6f64, 0.8f64);
        // A turn about y by atan2(0.8, 0.6): q = (0, sin(θ/2), 0, cos(θ/2)).
        let r = [[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]];
        let q = quaternion(&r);
        let half = 0.8f64.atan2(0.6) / 2.0;
        assert!((q[1] - half.sin()).abs() < 1e-15 && (q[3] - half.cos()).abs() < 1e-15 && q[0] == 0.0, "{q:?}");
        let id = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        let text = tum_text(&[(id, [0.0; 3]), (id, [1.5, -2.0, 3.25])]);
        assert_eq!(text, "0.0 0.0 0.0 0.0 0.0 0.0 0.0 1.0\n0.1 1.5 -2.0 3.25 0.0 0.0 0.0 1.0\n");
        assert_eq!(kitti_text(&[(id, [1.5, 0.0, 2.0])]), "1.0 0.0 0.0 1.5 0.0 1.0 0.0 0.0 0.0 0.0 1.0 2.0\n");
    }
}
