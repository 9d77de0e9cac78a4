//! A plain random stream (PCG32), for what is not a pixel sample: tests, benchmark
//! rays and meshes, and the BVH builder's checks. Pixel samples draw from
//! [`super::SampleStream`] instead.

use glam::Vec2;
use rand_core::{RngCore, SeedableRng};
use rand_pcg::Pcg32;

pub struct Rng(Pcg32);

impl Rng {
    pub fn from_seed(seed: u64) -> Self {
        Rng(Pcg32::seed_from_u64(seed))
    }

    /// The stream of `(seed, a, b)`, e.g. a render seed, a pixel and a pass: distinct
    /// triples give unrelated streams.
    pub fn new(seed: u64, a: u64, b: u64) -> Self {
        let state = splitmix64(seed ^ splitmix64(a.wrapping_add(0x9E37_79B9_7F4A_7C15)));
        let stream = splitmix64(b ^ 0xD1B5_4A32_D192_ED03).wrapping_add(a);
        Rng(Pcg32::new(state, stream))
    }

    pub fn next_u32(&mut self) -> u32 {
        self.0.next_u32()
    }

    /// Uniform in `[0, 1)`: the top 24 bits.
    pub fn next_f32(&mut self) -> f32 {
        super::sequence::to_unit(self.0.next_u32())
    }

    pub fn next_2d(&mut self) -> Vec2 {
        let x = self.next_f32();
        Vec2::new(x, self.next_f32())
    }
}

pub fn splitmix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}
