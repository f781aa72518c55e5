//! The arithmetic kernels in the browser: the lane-wise FMA emulation, the
//! four-lane gradient kernels, and the relaxed build's fused multiply-add.

use wasm_bindgen_test::*;

/// Multiply-adds where an FMA is easy to get wrong.
const FMA_SPECIAL: [(f32, f32, f32); 6] = [
    (1.0 + f32::EPSILON, 1.0 + f32::EPSILON, -1.0), // exact result 2^-22 + 2^-46: halfway in f64
    (1.0 + 1.0 / 4096.0, 1.0 + 1.0 / 4096.0, 0.0),  // 1 + 2^-11 + 2^-24: an f32 halfway point
    (1.0 + 1.0 / 4096.0, 1.0 + 1.0 / 4096.0, -(1.0 + 1.0 / 2048.0)), // 2^-24 fused, 0 unfused
    (3.0, 5.0, -15.0),                              // exact zero
    (1e-20, 1e-20, 0.0),                            // f32-subnormal product
    (1e-20, -1e-20, 1e-39),                         // subnormal sum
];

/// Random f32s: `random(lo)` takes the sign and mantissa bits of an xorshift draw
/// and `lo` as its exponent bits.
fn random_f32(seed: u64) -> impl FnMut(u32) -> f32 {
    let mut state = seed;
    move |lo| {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        f32::from_bits((state as u32 & 0x807F_FFFF) | lo)
    }
}

/// The lane-wise FMA emulation the wasm blur and gradient kernels use equals the scalar one (itself tested
/// against hardware FMA natively) on random triples and on sums that land exactly on an
/// f32 halfway point, zero or an f32-subnormal magnitude (the lanes that take the fallback).
#[wasm_bindgen_test]
fn simd_fma_emulation_equals_the_scalar_one() {
    use core::arch::wasm32::*;
    use siftlab_core::internals::num::{fma_emulated, fma_emulated_x4};
    let mut random = random_f32(0x9E37_79B9_7F4A_7C15);
    let mut checked = 0;
    for round in 0..250_000 {
        let (a, b, c) = match FMA_SPECIAL.get(round) {
            // The special case in lane 2, random values around it.
            Some(&(x, y, z)) => (
                [random(0x3F00_0000), random(0x4000_0000), x, random(0x3E00_0000)],
                [random(0x3F00_0000), random(0x3E00_0000), y, random(0x3F00_0000)],
                [random(0x3300_0000), random(0x4300_0000), z, random(0x3F00_0000)],
            ),
            // Half the rounds with one weight in every lane, as the blur calls it.
            None => {
                let w = random(0x3F00_0000);
                (
                    [random(0x3F00_0000), random(0x4000_0000), random(0x3E00_0000), random(0x4300_0000)],
                    if round % 2 == 0 {
                        [w; 4]
                    } else {
                        [w, random(0x3E00_0000), random(0x4000_0000), random(0x3F00_0000)]
                    },
                    [random(0x3300_0000), random(0x4300_0000), random(0x3F00_0000), -random(0x4000_0000)],
                )
            }
        };
        let v = |x: [f32; 4]| f32x4(x[0], x[1], x[2], x[3]);
        let got = fma_emulated_x4(v(a), v(b), v(c));
        let got = [
            f32x4_extract_lane::<0>(got),
            f32x4_extract_lane::<1>(got),
            f32x4_extract_lane::<2>(got),
            f32x4_extract_lane::<3>(got),
        ];
        for l in 0..4 {
            assert_eq!(
                got[l].to_bits(),
                fma_emulated(a[l], b[l], c[l]).to_bits(),
                "lane {l}: {} * {} + {}",
                a[l],
                b[l],
                c[l]
            );
            checked += 1;
        }
    }
    assert_eq!(checked, 1_000_000);
}

/// The four-lane gradient kernels of orientation and descriptors (`num::x4`, behind
/// `gradient_directions` and `gradient_samples`) equal the scalar `fast_atan2_deg`,
/// `magnitude` and `exp32f` on every element: random differences of 8-bit-scale pixels,
/// the axes and diagonals where fastAtan2's branches switch (±0 included), and exponents
/// from 0 to beyond exp32f's clamp. Lengths not a multiple of 4 check the scalar tail.
#[wasm_bindgen_test]
fn gradient_kernels_equal_the_scalar_ones() {
    use siftlab_core::internals::num::{exp32f, fast_atan2_deg, gradient_directions, gradient_samples, magnitude};
    let mut random = random_f32(0x243F_6A88_85A3_08D3);
    let edges = [0.0f32, -0.0, 1.0, -1.0, 0.5, -0.5, 255.0, -255.0, 1e-30, -1e-30];
    let (mut dxs, mut dys) = (Vec::new(), Vec::new());
    for &x in &edges {
        for &y in &edges {
            dxs.push(x);
            dys.push(y);
        }
    }
    for _ in 0..100_003 {
        // |v| in [0.5, 256): the range of a difference of two pixels.
        dxs.push(random(0x3F00_0000) * 2f32.powi((random(0x3F80_0000) * 8.0) as i32));
        dys.push(random(0x3F00_0000) * 2f32.powi((random(0x3F80_0000) * 8.0) as i32));
    }
    let args: Vec<f32> = (0..dxs.len())
        .map(|i| if i % 97 == 0 { -3000.0 + i as f32 * 1e-3 } else { -random(0x3F80_0000).abs() * 40.0 })
        .collect();
    let (oris, mags) = gradient_directions(&dxs, &dys);
    let (oris2, mags2, wts) = gradient_samples(&dxs, &dys, &args);
    for i in 0..dxs.len() {
        let (x, y) = (dxs[i], dys[i]);
        assert_eq!(oris[i].to_bits(), fast_atan2_deg(y, x).to_bits(), "atan2({y}, {x}) at {i}");
        assert_eq!(mags[i].to_bits(), magnitude(x, y).to_bits(), "magnitude({x}, {y}) at {i}");
        assert_eq!((oris2[i].to_bits(), mags2[i].to_bits()), (oris[i].to_bits(), mags[i].to_bits()));
        assert_eq!(wts[i].to_bits(), exp32f(args[i]).to_bits(), "exp32f({}) at {i}", args[i]);
    }
    assert_eq!(dxs.len(), 100_103);
}

/// The relaxed-SIMD build (`--features relaxed-simd`; www/worker.js loads it wherever
/// relaxed SIMD validates): Chromium's `f32x4.relaxed_madd` is fused, so every other test
/// of this run (SIFT against OpenCV, the blur against the scalar filter) went through the
/// engine's FMA and not the emulation; and that FMA, as `num::fma` uses it, equals the
/// exact emulation on random triples and on halfway, zero and subnormal cases.
#[cfg(feature = "relaxed-simd")]
#[wasm_bindgen_test]
fn relaxed_madd_is_fused_here_and_equals_the_exact_fma() {
    use siftlab_core::internals::num::{fma, fma_emulated, fma_engine, relaxed_madd_is_fused};
    assert!(
        relaxed_madd_is_fused(),
        "this engine's relaxed_madd is not fused: the relaxed build falls back to the emulation, \
         and this run did not test its fused path"
    );
    assert!(fma_engine().starts_with("relaxed SIMD"), "{}", fma_engine());
    let mut random = random_f32(0xD1B5_4A32_D192_ED03);
    for &(a, b, c) in &FMA_SPECIAL {
        assert_eq!(fma(a, b, c).to_bits(), fma_emulated(a, b, c).to_bits(), "{a} * {b} + {c}");
    }
    for _ in 0..1_000_000 {
        let (a, b, c) = (random(0x3F00_0000), random(0x4000_0000), random(0x3F80_0000));
        assert_eq!(fma(a, b, c).to_bits(), fma_emulated(a, b, c).to_bits(), "{a} * {b} + {c}");
    }
}
