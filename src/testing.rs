//! Helpers for the unit tests.

/// Knuth's MMIX linear congruential generator: the same numbers on every machine, for test data.
pub struct Lcg {
    state: u64,
    increment: u64,
}

impl Lcg {
    /// MMIX's generator from `seed`.
    pub fn new(seed: u64) -> Self {
        Self::with_increment(seed, 1_442_695_040_888_963_407)
    }

    /// The same multiplier with another increment.
    pub fn with_increment(seed: u64, increment: u64) -> Self {
        Self {
            state: seed,
            increment,
        }
    }

    /// The next state (its high bits are the random ones).
    pub fn next_u64(&mut self) -> u64 {
        self.state = self
            .state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(self.increment);
        self.state
    }
}

/// The circle test: no two files import each other.
mod circles;
/// The layer test: imports against the layer order of the design.
mod layers;
