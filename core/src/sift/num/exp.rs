//! OpenCV's `exp32f` with IPP off (docs/fidelity.md §SIFT-12, §SIFT-14): the
//! orientation and descriptor windows' Gaussian weights.

use super::{fma, rne};

pub(super) const EXP_TAB: [u32; 64] = [
    0x3c1e707a, 0x3c202a27, 0x3c21e8a3, 0x3c23abfb, 0x3c25743e, 0x3c274179, 0x3c2913b9, 0x3c2aeb0d, 0x3c2cc783,
    0x3c2ea92a, 0x3c30900f, 0x3c327c41, 0x3c346dcf, 0x3c3664c9, 0x3c38613c, 0x3c3a6339, 0x3c3c6acf, 0x3c3e780d,
    0x3c408b03, 0x3c42a3c1, 0x3c44c258, 0x3c46e6d7, 0x3c491150, 0x3c4b41d2, 0x3c4d786e, 0x3c4fb536, 0x3c51f83b,
    0x3c54418e, 0x3c569140, 0x3c58e764, 0x3c5b440b, 0x3c5da748, 0x3c60112d, 0x3c6281cc, 0x3c64f939, 0x3c677786,
    0x3c69fcc6, 0x3c6c890c, 0x3c6f1c6e, 0x3c71b6fd, 0x3c7458ce, 0x3c7701f6, 0x3c79b289, 0x3c7c6a9b, 0x3c7f2a41,
    0x3c80f8c9, 0x3c826050, 0x3c83cbc2, 0x3c853b29, 0x3c86ae90, 0x3c882602, 0x3c89a18b, 0x3c8b2136, 0x3c8ca50f,
    0x3c8e2d21, 0x3c8fb977, 0x3c914a1f, 0x3c92df23, 0x3c947891, 0x3c961674, 0x3c97b8d8, 0x3c995fcb, 0x3c9b0b59,
    0x3c9cbb8f,
];
pub(super) const EXP_A1: f32 = f32::from_bits(0x40B7AA3D);
pub(super) const EXP_A2: f32 = f32::from_bits(0x41C6BB64);
pub(super) const EXP_A3: f32 = f32::from_bits(0x428F5AD6);
pub(super) const EXP_A4: f32 = f32::from_bits(0x42CED13A);

/// `cv::hal::exp32f` with IPP disabled (docs/fidelity.md §SIFT-12). The default wheel uses
/// IPP's closed-source exp instead, which no formula reproduces; this is the
/// reason angles can differ from that wheel at the 1e-5 degree level.
#[inline(always)]
pub fn exp32f(x: f32) -> f32 {
    let x = x.clamp(-2079.4417, 2079.4417) * f32::from_bits(0x42B8AA3B);
    let xi = rne(x);
    let xf = (x - xi as f32) * 0.015625;
    let e = ((xi >> 6) + 127).clamp(0, 255) as u32;
    let tab = f32::from_bits(EXP_TAB[(xi & 63) as usize]) * f32::from_bits(e << 23);
    let mut z = xf + EXP_A1;
    z = fma(z, xf, EXP_A2);
    z = fma(z, xf, EXP_A3);
    z = fma(z, xf, EXP_A4);
    z * tab
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exp32f_is_close_to_exp() {
        for &x in &[0.0f32, -0.5, -1.0, -3.25, -10.0, -20.0] {
            let r = exp32f(x);
            assert!(((r - x.exp()) / x.exp()).abs() < 1e-6, "{x}: {r} vs {}", x.exp());
        }
        assert_eq!(exp32f(0.0), 1.0);
    }
}
