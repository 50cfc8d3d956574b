//! SplitMix64 (Steele, Lea & Flood, "Fast splittable pseudorandom number generators",
//! OOPSLA 2014): a 64-bit counter advanced by the golden-ratio increment, then mixed. Fast,
//! statistically sound for simulation, and fully determined by its seed.

/// The golden-ratio increment 2⁶⁴/φ, rounded to odd.
pub const GOLDEN: u64 = 0x9e37_79b9_7f4a_7c15;

/// SplitMix64's output mix (a bijection on u64): well-spread bits from any counter or hash
/// input.
#[inline]
pub fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// A seeded SplitMix64 stream.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SplitMix64(pub u64);

impl SplitMix64 {
    /// The stream of `seed`.
    pub fn new(seed: u64) -> SplitMix64 {
        SplitMix64(seed)
    }

    /// Next 64 random bits.
    #[inline]
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(GOLDEN);
        mix64(self.0)
    }

    /// Uniform in [0, 1), 24 bits (every value exact in f32).
    #[inline]
    pub fn unit(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32
    }

    /// Uniform in [−1, 1), 24 bits.
    #[inline]
    pub fn sym(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 / (1u64 << 23) as f32 - 1.0
    }

    /// Uniform in [0, 1), 53 bits.
    #[inline]
    pub fn unit_f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform integer in [0, n) (n ≥ 1; modulo bias below 2⁻³² for n < 2³²).
    #[inline]
    pub fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n.max(1) as u64) as usize
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The published reference: seed 1234567 gives 6457827717110365317 first (the values in
    /// Vigna's splitmix64.c test vectors).
    #[test]
    fn matches_the_reference_stream() {
        let mut r = SplitMix64::new(1_234_567);
        assert_eq!(r.next_u64(), 6_457_827_717_110_365_317);
        assert_eq!(r.next_u64(), 3_203_168_211_198_807_973);
    }

    #[test]
    fn floats_lie_in_their_ranges_and_are_uniform() {
        let mut r = SplitMix64::new(7);
        let n = 100_000;
        let (mut su, mut ss) = (0.0f64, 0.0f64);
        for _ in 0..n {
            let (u, s) = (r.unit(), r.sym());
            assert!((0.0..1.0).contains(&u) && (-1.0..1.0).contains(&s));
            su += u as f64;
            ss += s as f64;
        }
        // Means within 5 standard errors of 1/2 and 0.
        assert!((su / n as f64 - 0.5).abs() < 5.0 * (1.0 / 12.0f64 / n as f64).sqrt());
        assert!((ss / n as f64).abs() < 5.0 * (1.0 / 3.0f64 / n as f64).sqrt());
        assert!((0..1000).all(|_| r.below(3) < 3));
    }
}
