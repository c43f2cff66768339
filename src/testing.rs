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

/// A noisy volume of blocks for the walks' tests: `(x/3 + y/4 + z/5) mod 7` times ten, noise of
/// up to 2.8 (f32, in steps of 0.7, so that values fall on bin edges) or 4 (integers), and a
/// missing voxel in about 97 where `voxel_type` is f32.
pub fn awkward_volume(
    dims: [usize; 3],
    spacing: [f64; 3],
    voxel_type: crate::volume::VoxelType,
    seed: u64,
) -> crate::volume::Volume {
    let float = voxel_type == crate::volume::VoxelType::F32;
    let mut lcg = Lcg::new(seed);
    let data = (0..dims.iter().product::<usize>())
        .map(|i| {
            let r = (lcg.next_u64() >> 33) as u32;
            let (x, y, z) = (
                i % dims[0],
                (i / dims[0]) % dims[1],
                i / (dims[0] * dims[1]),
            );
            let noise = (r % 5) as f32 * if float { 0.7 } else { 1.0 };
            if float && r.is_multiple_of(97) {
                f32::NAN
            } else {
                ((x / 3 + y / 4 + z / 5) % 7) as f32 * 10.0 + noise
            }
        })
        .collect();
    crate::volume::Volume::new(dims, spacing, voxel_type, data).unwrap()
}

/// The circle test: no two files import each other.
mod circles;
/// The layer test: imports against the layer order of the design.
mod layers;
