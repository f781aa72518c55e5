//! The x86 window kernels against the scalar ones, bit for bit, on both of
//! their paths (exact integer sums and OpenCV's replayed f32 order).

use super::wide::{self, pos, EXACT};
use super::x86::{self, Avx2, Avx512};
use super::{weights, Deriv, Kernels, Level, Scalar, WIN};

/// A level of smooth texture plus `noise` (0..=255) of xorshift noise:
/// noise makes gradients and residuals large enough to overflow the
/// exactness bounds, smooth texture keeps them small.
fn level(w: usize, h: usize, noise: u32, seed: u64) -> Level {
    let mut rng = crate::testutil::XorShift64::new(seed);
    let data = (0..w * h)
        .map(|i| {
            let s = rng.next_u64();
            let (x, y) = ((i % w) as f64, (i / w) as f64);
            let smooth = 128.0 + 60.0 * (x * 0.11 + y * 0.07).sin() + 40.0 * (y * 0.13 - x * 0.05).cos();
            let n = if noise == 0 { 0 } else { (s % (2 * noise as u64 + 1)) as i64 - noise as i64 };
            (smooth as i64 + n).clamp(0, 255) as u8
        })
        .collect();
    Level::new(data, w, h)
}

/// Every kernel against the scalar reference, bit for bit, at random
/// window positions (borders included) and sub-pixel weights; both the
/// exact-integer path and the replay path must be taken.
#[test]
fn kernels_equal_the_scalar_ones_on_both_paths() {
    if !std::is_x86_feature_detected!("avx2") {
        return;
    }
    let (w, h) = (160, 90);
    let mut rng = crate::testutil::XorShift64::new(0x9e37_79b9_7f4a_7c15);
    let mut rnd = move || rng.next_u64();
    let (mut exact_seen, mut replay_seen, mut tensor_replays) = (0, 0, 0);
    for (noise, cases) in [(0u32, 400), (12, 400), (90, 400), (255, 200)] {
        let prev = level(w, h, noise, 1 + noise as u64);
        let next = level(w, h, noise, 7 + noise as u64);
        let deriv = Deriv::new(&prev);
        let (mut sp, mut vp, mut zp) = (Scalar::new_patch(), Avx2::new_patch(), Avx512::new_patch());
        let avx512 = std::is_x86_feature_detected!("avx512bw");
        for _ in 0..cases {
            let mut coord = |n: usize| (rnd() % (n as u64 + 21)) as i32 - 21;
            let (ix, iy, jx, jy) = (coord(w), coord(h), coord(w), coord(h));
            let frac = |r: u64| (r % 4096) as f32 / 4096.0;
            let w0 = weights(frac(rnd()), frac(rnd()));
            let w1 = weights(frac(rnd()), frac(rnd()));
            let a = Scalar::load_patch(&prev, &deriv, ix, iy, &w0, &mut sp);
            let b = Avx2::load_patch(&prev, &deriv, ix, iy, &w0, &mut vp);
            // Whether ΣX²'s tail went through the replay (its bound is itself).
            let tail_xx: u64 =
                vp.x.iter().map(|r| r.0[16..WIN].iter().map(|&v| (v as i64 * v as i64) as u64).sum::<u64>()).sum();
            tensor_replays += (tail_xx > EXACT) as usize;
            assert_eq!(
                [a.0.to_bits(), a.1.to_bits(), a.2.to_bits()],
                [b.0.to_bits(), b.1.to_bits(), b.2.to_bits()],
                "tensor at ({ix}, {iy}), noise {noise}"
            );
            let a = Scalar::mismatch(&next, jx, jy, &w1, &mut sp);
            let b = Avx2::mismatch(&next, jx, jy, &w1, &mut vp);
            assert_eq!(
                [a.0.to_bits(), a.1.to_bits()],
                [b.0.to_bits(), b.1.to_bits()],
                "mismatch ({ix}, {iy}) → ({jx}, {jy}), noise {noise}"
            );
            if avx512 {
                Avx512::load_patch(&prev, &deriv, ix, iy, &w0, &mut zp);
                let c = Avx512::mismatch(&next, jx, jy, &w1, &mut zp);
                assert_eq!(
                    [a.0.to_bits(), a.1.to_bits()],
                    [c.0.to_bits(), c.1.to_bits()],
                    "AVX-512 mismatch ({ix}, {iy}) → ({jx}, {jy}), noise {noise}"
                );
                assert!(vp.d.iter().zip(zp.d.iter()).all(|(u, v)| u.0[..24] == v.0[..24]), "J − T rows");
            }
            // The portable replay of OpenCV's lane order (what wasm
            // uses) against this module's vector one, on this J − T.
            // SAFETY: AVX2 checked at the top.
            let (r, q) = (wide::mismatch_lanes_replay(&vp), unsafe { x86::mismatch_lanes_replay(&vp) });
            assert_eq!(r.map(f32::to_bits), q.map(f32::to_bits));
            let a = Scalar::abs_diff_sum(&next, jx, jy, &w1, &mut sp);
            let b = Avx2::abs_diff_sum(&next, jx, jy, &w1, &mut vp);
            assert_eq!(a.to_bits(), b.to_bits());
            // Which path the mismatch's X lanes took (its bound, recomputed).
            let bound: [u64; 4] = std::array::from_fn(|k| {
                (0..WIN)
                    .map(|y| {
                        [k, k + 4, k + 8, k + 12]
                            .iter()
                            .map(|&c| (vp.d[y].0[pos(c)] as i64 * vp.x[y].0[pos(c)] as i64).unsigned_abs())
                            .sum::<u64>()
                    })
                    .sum()
            });
            if bound.iter().all(|&v| v <= EXACT) {
                exact_seen += 1;
            } else {
                replay_seen += 1;
            }
        }
    }
    assert!(exact_seen > 100 && replay_seen > 100, "exact {exact_seen}, replayed {replay_seen}");
    assert!(tensor_replays > 100 && tensor_replays < 1300, "tensor replays {tensor_replays} of 1400");
}
