//! The wasm fast path's fallback, in the browser (`cargo test --target
//! wasm32-unknown-unknown`): a block holding one sum that lands, rounded to
//! f64, exactly on an f32 halfway point it does not lie on, so rounding that
//! f64 to f32 goes the wrong way. Real images hit such a sum about once in a
//! million FMAs, too rarely for a random test to be sure of one.

use super::super::super::num::fma_emulated;
use super::super::kernel::gaussian_kernel;
use super::fast as wasm_fast;
use wasm_bindgen_test::*;

wasm_bindgen_test_configure!(run_in_browser);

/// A tap t in `taps` and a value p1 such that, with acc = k[t−1] (the sum
/// so far when the previous tap saw a 1 and all before it 0), acc + p1·k[t]
/// is a hard sum: its f64 rounding is the f32 halfway point above an odd
/// f32 `low` (so that tie goes up) and the exact value lies just below it,
/// so the FMA gives `low`. Returns (t, p1, low).
fn hard_sum(k: &[f32], taps: std::ops::Range<usize>) -> (usize, f32, f32) {
    for t in taps {
        let acc = k[t - 1];
        for j in 0..1u32 << 20 {
            let low = f32::from_bits(acc.to_bits() + j);
            if low.to_bits() & 1 == 0 {
                continue;
            }
            let midpoint = (low as f64 + f32::from_bits(low.to_bits() + 1) as f64) / 2.0;
            let target = midpoint - acc as f64;
            let p1 = (target / k[t] as f64) as f32;
            let product = p1 as f64 * k[t] as f64;
            if acc as f64 + product == midpoint && product < target {
                assert_eq!(fma_emulated(p1, k[t], acc), low);
                assert_ne!(((acc as f64 + product) as f32).to_bits(), low.to_bits());
                return (t, p1, low);
            }
        }
    }
    panic!("no hard sum found");
}

/// The fast path's rounding and narrowing against Rust's f64 → f32 conversion,
/// on random tame values of every binade (2^-120 to 2^100) and zero: the
/// split rounds every value that is not a tie as the conversion does, and
/// `narrow` returns the f32 of every f32-valued lane.
#[wasm_bindgen_test]
fn split_rounding_and_narrowing_equal_the_conversion() {
    use core::arch::wasm32::*;
    let mut state = 0x9E37_79B9_7F4A_7C15u64;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    let lane = |v: v128| [f64x2_extract_lane::<0>(v), f64x2_extract_lane::<1>(v)];
    let (mut checked, mut ties) = (0, 0);
    for i in 0..400_000u32 {
        let r = next();
        // Exponent 2^-120 ..= 2^100, random significand; every 64th a
        // sum with few low bits, where ties are common.
        let e = (r >> 52) % 221;
        let bits = ((1023 - 120 + e) << 52) | (r & ((1 << 52) - 1));
        let bits = if i % 64 == 0 { bits & !((1 << 27) - 1) } else { bits };
        let s = [f64::from_bits(bits), if i % 97 == 0 { 0.0 } else { f64::from_bits(bits ^ (r >> 40)) }];
        let v = f64x2(s[0], s[1]);
        let got = lane(wasm_fast::round_split(v));
        for (k, &x) in s.iter().enumerate() {
            if x.to_bits() & 0x1FFF_FFFF == 0x1000_0000 {
                ties += 1;
                continue;
            }
            let want = x as f32;
            assert_eq!(got[k].to_bits(), (want as f64).to_bits(), "{x:e}");
            checked += 1;
        }
        let n = wasm_fast::narrow(f64x2(got[0], got[1]), f64x2(got[1], 0.0));
        let n = [f32x4_extract_lane::<0>(n), f32x4_extract_lane::<1>(n), f32x4_extract_lane::<2>(n)];
        assert_eq!(n.map(f32::to_bits), [got[0] as f32, got[1] as f32, got[1] as f32].map(f32::to_bits));
        assert_eq!(f32x4_extract_lane::<3>(wasm_fast::narrow(v, f64x2_splat(0.0))).to_bits(), 0);
    }
    assert!(checked > 790_000 && ties > 10, "{checked} {ties}");
}

#[wasm_bindgen_test]
fn a_block_with_a_hard_sum_is_redone_exactly() {
    // The pyramid's second level; its kernel has hard sums in both halves.
    let k = gaussian_kernel(1.5450077936447955);
    let c = k.len() / 2;
    assert!(wasm_fast::tame_kernel(&k));
    // Row pass: output pixel 3 of a 16-pixel block sees 1·k[t−1] + p1·k[t].
    let (t, p1, want) = hard_sum(&k, 1..k.len());
    let mut padded = vec![0f32; 16 + k.len() - 1];
    padded[3 + t - 1] = 1.0;
    padded[3 + t] = p1;
    assert!(wasm_fast::tame(&padded));
    let (mut fast, mut exact) = (vec![0f32; 16], vec![0f32; 16]);
    wasm_fast::row_tame(&padded, &k, &mut fast);
    for (i, e) in exact.iter_mut().enumerate() {
        let mut a = padded[i] * k[0];
        for (t, &kv) in k.iter().enumerate().skip(1) {
            a = fma_emulated(padded[i + t], kv, a);
        }
        *e = a;
    }
    assert_eq!(fast[3], want);
    assert_eq!(fast, exact);
    // Column pass: pixel 5 sees the same two taps in the kernel's upper half
    // (pair q of rows has weight k[c+1+q]; the centre row has k[c]).
    let (t, p1, want) = hard_sum(&k, c + 1..k.len());
    let zeros = [0f32; 16];
    let mut rows = vec![vec![0f32; 16]; k.len() - c];
    rows[t - 1 - c][5] = 1.0;
    rows[t - c][5] = p1;
    let pairs: Vec<(&[f32], &[f32])> = rows[1..].iter().map(|r| (&r[..], &zeros[..])).collect();
    let mut fast = vec![0f32; 16];
    wasm_fast::column_tame(&rows[0], &pairs, &k[c..], &mut fast);
    assert_eq!(fast[5], want);
    assert!(fast.iter().enumerate().all(|(i, &v)| i == 5 || v == 0.0));
}
