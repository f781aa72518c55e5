//! The camera the lab hard-codes (KITTI sequence 00, camera 0) and the pixel
//! normalisation findEssentialMat and recoverPose apply first
//! (docs/fidelity.md §VO-3.2).

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
