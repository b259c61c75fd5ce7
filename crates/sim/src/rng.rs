//! The simulator's own random numbers (execution times, random phasing, the
//! adversarial search), independent of the model's test generator.
//!
//! SplitMix64 (Steele, Lea, Flood, OOPSLA 2014): tiny, fast, and the same on
//! every platform and version. Its sequence is part of the simulator's
//! contract — the same spec, configuration and seed give the same simulation,
//! bit for bit, and replay commands printed by earlier versions still replay
//! — so a test pins its first values: do not change it.

/// A SplitMix64 stream.
#[derive(Debug, Clone)]
pub struct Rng(u64);

impl Rng {
    /// The stream of `seed`.
    pub fn new(seed: u64) -> Rng {
        Rng(seed ^ 0x9E37_79B9_7F4A_7C15)
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1), from the top 53 bits.
    pub(crate) fn unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform in [lo, hi] (inclusive; the modulo bias is below 2^-40 for
    /// the spans the simulator draws, and kept for reproducibility).
    pub fn range(&mut self, lo: u64, hi: u64) -> u64 {
        debug_assert!(lo <= hi, "empty range {lo}..={hi}");
        lo + self.next_u64() % (hi - lo + 1)
    }

    /// True with probability `p`.
    pub(crate) fn chance(&mut self, p: f64) -> bool {
        self.unit() < p
    }
}

#[cfg(test)]
mod tests {
    use super::Rng;

    /// The sequence the simulator's results (and printed replay commands)
    /// depend on.
    #[test]
    fn the_sequence_is_pinned() {
        let mut r = Rng::new(42);
        let v: Vec<u64> = (0..3).map(|_| r.next_u64()).collect();
        assert_eq!(
            v,
            vec![
                2_949_826_092_126_892_291,
                5_139_283_748_462_763_858,
                6_349_198_060_258_255_764
            ]
        );
        assert_eq!(r.unit(), 0.03803016854024621);
        assert_eq!(r.range(3, 9), 7);
    }
}
