//! SIFT's anatomy view: a pyramid level under the cursor, as gray pixels,
//! the orientation histogram's bars and where a keypoint sits in the pyramid.

use crate::protocol::inside::LevelThumb;
use siftlab_core::sift::anatomy::values_to_gray;

/// The value of a thumbnail under the cursor at fractions (fx, fy) of its
/// size: the octave pixel (column, row) and the level's value there.
pub fn level_value(l: &LevelThumb, fx: f64, fy: f64) -> Option<(u32, u32, f32)> {
    if !(0.0..1.0).contains(&fx) || !(0.0..1.0).contains(&fy) {
        return None;
    }
    let (c, r) = ((fx * l.width as f64) as u32, (fy * l.height as f64) as u32);
    let v = *l.values.get((r * l.width + c) as usize)?;
    Some((c * l.step, r * l.step, v))
}

/// A level as 8-bit gray for a canvas: Gaussian values as they are, DoG
/// centred on 128 and scaled by its largest |value| (as the CLI's PNGs).
pub fn level_rgba(l: &LevelThumb) -> Vec<u8> {
    values_to_gray(&l.values, l.dog).into_iter().flat_map(|g| [g, g, g, 255]).collect()
}

/// Bars of a 36-bin histogram in a `w`×`h` box scaled to `ymax`: (x, y, width, height) each.
pub fn hist_bars(bins: &[f32], w: f64, h: f64, ymax: f64) -> Vec<(f64, f64, f64, f64)> {
    let bw = w / bins.len().max(1) as f64;
    bins.iter()
        .enumerate()
        .map(|(i, &v)| {
            let bh = if ymax > 0.0 { (v as f64 / ymax).clamp(0.0, 1.0) * h } else { 0.0 };
            (i as f64 * bw, h - bh, bw, bh)
        })
        .collect()
}

/// The pyramid position of a keypoint: "octave −1 (the doubled image), layer 2, scale σ = 3.20".
pub fn keypoint_place(k: &siftlab_core::sift::KeyPoint) -> String {
    let o = k.octave_index();
    let doubled = if o == -1 { " (the doubled image)" } else { "" };
    format!(
        "octave {o}{doubled}, DoG layer {}, size {:.2} px (σ = {:.2} in image pixels), response {:.5}",
        k.layer(),
        k.size,
        k.size / 2.0,
        k.response
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn level_values_and_bars() {
        let l = LevelThumb {
            octave: 0,
            index: 1,
            dog: true,
            step: 4,
            width: 2,
            height: 2,
            values: vec![-2.0, 0.0, 1.0, 2.0],
        };
        assert_eq!(level_value(&l, 0.6, 0.1), Some((4, 0, 0.0)));
        assert_eq!(level_value(&l, 0.0, 0.9), Some((0, 4, 1.0)));
        assert_eq!(level_value(&l, 1.0, 0.0), None);
        let px: Vec<u8> = level_rgba(&l).chunks(4).map(|c| c[0]).collect();
        assert_eq!(px, vec![1, 128, 192, 255]);
        let bars = hist_bars(&[0.0, 5.0, 10.0], 30.0, 100.0, 10.0);
        assert_eq!(bars[1], (10.0, 50.0, 10.0, 50.0));
        assert_eq!(bars[2].3, 100.0);
    }
}
