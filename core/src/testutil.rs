//! Seeded pseudo-random inputs for the unit tests: one xorshift64 stream
//! (Marsaglia's 13/7/17 triple), so a failing case names its seed and
//! replays exactly.
//!
//! Test inputs that must equal a Python generator's (the VO goldens'
//! `lcg_scene`) keep that generator beside their test instead.

/// A xorshift64 stream.
#[derive(Clone, Debug)]
pub struct XorShift64(u64);

impl XorShift64 {
    /// The stream from `seed` (0, the one fixed point of xorshift, is
    /// replaced by a nonzero constant).
    pub fn new(seed: u64) -> Self {
        XorShift64(if seed == 0 { 0x9e37_79b9_7f4a_7c15 } else { seed })
    }

    pub fn next_u64(&mut self) -> u64 {
        let mut s = self.0;
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        self.0 = s;
        s
    }

    /// A byte from the high half of the next value.
    pub fn byte(&mut self) -> u8 {
        (self.next_u64() >> 32) as u8
    }

    /// A uniform f64 in [−1, 1), from the top 53 bits.
    pub fn signed_unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    }
}

/// [`XorShift64::signed_unit`] as a closure, for inputs written as `rnd()`.
pub fn signed_units(seed: u64) -> impl FnMut() -> f64 {
    let mut rng = XorShift64::new(seed);
    move || rng.signed_unit()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_stream_is_marsaglias_xorshift64() {
        // The first values of xorshift64 (13, 7, 17) from seed 1.
        let mut r = XorShift64::new(1);
        assert_eq!([r.next_u64(), r.next_u64()], [1_082_269_761, 1_152_992_998_833_853_505]);
        let mut u = signed_units(7);
        assert!((0..1000).map(|_| u()).all(|v| (-1.0..1.0).contains(&v)));
    }
}
