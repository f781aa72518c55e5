//! The lab's monocular visual odometry, stage by stage as OpenCV 4.8 computes
//! it (`docs/fidelity.md` §VO-1 to §VO-7): [`lk`] tracks points
//! (`calcOpticalFlowPyrLK`), [`ransac`] estimates the essential matrix with the
//! [`five_point`] kernel (`findEssentialMat`), [`recover_pose`](fn@recover_pose) picks R, t
//! (`recoverPose`), [`odometry`] is the lab's accumulation loop, [`metrics`]
//! scores a trajectory against ground truth.

pub mod five_point;
pub mod linalg;
pub mod lk;
pub mod metrics;
pub mod null_vectors;
pub mod odometry;
pub mod ransac;
pub mod recover_pose;

pub use lk::{calc_optical_flow_pyr_lk, LkParams, LkResult};
pub use odometry::{Odometry, StepResult, Steps};
pub use ransac::{find_essential_mat, EssentialResult, RansacParams};
pub use recover_pose::{recover_pose, Pose};

/// A 3×3 matrix, row-major.
pub type Mat3 = [[f64; 3]; 3];
pub type Vec3 = [f64; 3];

/// Pinhole intrinsics. The lab passes `focal` and `pp` (fx = fy).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    pub fx: f64,
    pub fy: f64,
    pub cx: f64,
    pub cy: f64,
}

impl Default for Camera {
    /// KITTI sequence 00, camera 0, as the lab hard-codes it.
    fn default() -> Self {
        Camera { fx: 718.856, fy: 718.856, cx: 607.1928, cy: 185.2157 }
    }
}

impl Camera {
    /// Checks the intrinsics are usable (finite, positive focal lengths).
    pub fn validate(&self) -> crate::Result<()> {
        let ok = [self.fx, self.fy, self.cx, self.cy].iter().all(|v| v.is_finite()) && self.fx > 0.0 && self.fy > 0.0;
        if ok {
            Ok(())
        } else {
            Err(crate::Error::InvalidArgument(format!(
                "invalid camera intrinsics fx={} fy={} cx={} cy={}: focal lengths must be \
                 positive and all values finite",
                self.fx, self.fy, self.cx, self.cy
            )))
        }
    }

    /// Pixel → normalized coordinates as findEssentialMat/recoverPose do on
    /// an AVX2 build (docs/fidelity.md §VO-3.2): `fma(x, 1/f, (−c)·(1/f))`, one rounding.
    #[inline]
    pub fn normalize(&self, p: [f32; 2]) -> [f64; 2] {
        let (ax, ay) = (1.0 / self.fx, 1.0 / self.fy);
        let (bx, by) = (-self.cx * ax, -self.cy * ay);
        [(p[0] as f64).mul_add(ax, bx), (p[1] as f64).mul_add(ay, by)]
    }
}

pub fn mat_mul(a: &Mat3, b: &Mat3) -> Mat3 {
    std::array::from_fn(|r| std::array::from_fn(|c| a[r][0] * b[0][c] + a[r][1] * b[1][c] + a[r][2] * b[2][c]))
}

pub fn mat_vec(a: &Mat3, v: &Vec3) -> Vec3 {
    std::array::from_fn(|r| a[r][0] * v[0] + a[r][1] * v[1] + a[r][2] * v[2])
}

pub fn transpose(a: &Mat3) -> Mat3 {
    std::array::from_fn(|r| std::array::from_fn(|c| a[c][r]))
}

pub fn det3(a: &Mat3) -> f64 {
    a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0])
        + a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0])
}

/// The cross-product matrix `[v]ₓ`.
pub fn skew(v: Vec3) -> Mat3 {
    [[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]]
}

pub const IDENTITY: Mat3 = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
