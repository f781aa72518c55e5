//! `cv::clipLine`, a segment clipped to the image before it is drawn, and
//! the clipped fixed-point segment as OpenCV's lines walk it.

use super::pixel::XY_SHIFT;

/// `cv::clipLine(Size2l, Point2l&, Point2l&)`: Cohen-Sutherland with
/// OpenCV's integer divisions (truncating), so clipped endpoints land on the
/// same pixels.
pub(super) fn clip_line(width: i64, height: i64, p1: &mut (i64, i64), p2: &mut (i64, i64)) -> bool {
    let (right, bottom) = (width - 1, height - 1);
    if width <= 0 || height <= 0 {
        return false;
    }
    let code = |p: (i64, i64)| -> i32 {
        (p.0 < 0) as i32 + (p.0 > right) as i32 * 2 + (p.1 < 0) as i32 * 4 + (p.1 > bottom) as i32 * 8
    };
    let (mut c1, mut c2) = (code(*p1), code(*p2));
    if (c1 & c2) == 0 && (c1 | c2) != 0 {
        if c1 & 12 != 0 {
            let a = if c1 < 8 { 0 } else { bottom };
            p1.0 += (a - p1.1) * (p2.0 - p1.0) / (p2.1 - p1.1);
            p1.1 = a;
            c1 = (p1.0 < 0) as i32 + (p1.0 > right) as i32 * 2;
        }
        if c2 & 12 != 0 {
            let a = if c2 < 8 { 0 } else { bottom };
            p2.0 += (a - p2.1) * (p2.0 - p1.0) / (p2.1 - p1.1);
            p2.1 = a;
            c2 = (p2.0 < 0) as i32 + (p2.0 > right) as i32 * 2;
        }
        if (c1 & c2) == 0 && (c1 | c2) != 0 {
            if c1 != 0 {
                let a = if c1 == 1 { 0 } else { right };
                p1.1 += (a - p1.0) * (p2.1 - p1.1) / (p2.0 - p1.0);
                p1.0 = a;
                c1 = 0;
            }
            if c2 != 0 {
                let a = if c2 == 1 { 0 } else { right };
                p2.1 += (a - p2.0) * (p2.1 - p1.1) / (p2.0 - p1.0);
                p2.0 = a;
                c2 = 0;
            }
        }
    }
    (c1 | c2) == 0
}

/// A fixed-point segment clipped to the image and oriented as OpenCV's
/// `LineAA` and `Line2` walk it. OpenCV writes each walk twice, along x for
/// a shallow segment and along y for a steep one, the second the first with
/// x and y exchanged; here both are one walk in (u, v) coordinates, u the
/// major axis and v the minor one, so every integer operation is OpenCV's.
pub(super) struct Walk {
    /// Start and end in (u, v), XY_SHIFT fixed point, with a.0 ≤ b.0.
    pub a: (i64, i64),
    pub b: (i64, i64),
    /// The change of v per unit of u, XY_SHIFT fixed point.
    pub v_step: i64,
    /// Whether u is y (|dx| ≤ |dy|: OpenCV walks a tie along y).
    steep: bool,
}

impl Walk {
    /// `p1`–`p2` (XY_SHIFT fixed point) clipped to a `w`×`h` image; `None`
    /// when nothing of it is inside.
    pub fn new(w: i64, h: i64, mut p1: (i64, i64), mut p2: (i64, i64)) -> Option<Walk> {
        if !clip_line(w << XY_SHIFT, h << XY_SHIFT, &mut p1, &mut p2) {
            return None;
        }
        // OpenCV's branch-free |d| and sign: (d ^ s) − s with s the sign mask.
        let sign = |d: i64| if d < 0 { -1 } else { 0 };
        let abs = |d: i64| (d ^ sign(d)) - sign(d);
        let steep = abs(p2.0 - p1.0) <= abs(p2.1 - p1.1);
        let uv = |p: (i64, i64)| if steep { (p.1, p.0) } else { p };
        let (mut a, mut b) = (uv(p1), uv(p2));
        // Walk towards increasing u; the minor delta takes the major's sign.
        let s = sign(b.0 - a.0);
        let au = ((b.0 - a.0) ^ s) - s;
        let dv = ((b.1 - a.1) ^ s) - s;
        if s != 0 {
            std::mem::swap(&mut a, &mut b);
        }
        Some(Walk { a, b, v_step: (dv << XY_SHIFT) / (au | 1), steep })
    }

    /// The pixel (x, y) of a pixel (u, v).
    pub fn xy(&self, (u, v): (i64, i64)) -> (i64, i64) {
        if self.steep {
            (v, u)
        } else {
            (u, v)
        }
    }
}
