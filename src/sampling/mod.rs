//! The numbers a render draws: the sampler of pixel samples ([`SampleStream`]), the
//! sequences behind it ([`sequence`]), a plain random stream for everything else
//! ([`Rng`]), and the warps from the unit square to directions and points
//! ([`warps`]).

pub mod rng;
pub mod sequence;
pub mod warps;

pub use rng::{splitmix64, Rng};
pub use warps::{
    concentric_disk, cosine_hemisphere, cosine_hemisphere_pdf, uniform_cone, uniform_hemisphere,
    uniform_hemisphere_pdf, uniform_sphere, uniform_sphere_pdf,
};

use crate::lanes::{Lanes, UInt};
use crate::names::{display_from_table, Named};
use sequence::{hash32, independent_2d, sobol_2d, sobol_2d_upper};

/// Which numbers pixel samples draw (`--sampler`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum SamplerKind {
    /// Independent uniform numbers.
    Independent,
    /// Every pair of numbers a path draws stratified over the pixel's samples.
    #[default]
    Sobol,
}

impl Named for SamplerKind {
    const WHAT: &'static str = "sampler";
    const TABLE: &'static [(Self, &'static str, &'static str)] = &[
        (
            SamplerKind::Sobol,
            "sobol",
            "Owen-scrambled Sobol points: every pair of numbers of every bounce stratified over the pixel's samples",
        ),
        (
            SamplerKind::Independent,
            "independent",
            "Independent uniform numbers (for comparison)",
        ),
    ];
}
display_from_table!(SamplerKind);

/// The dimension pairs of a camera sample: the position in the pixel, the point on
/// the lens; a path's own numbers start at [`FIRST_PATH_PAIR`].
pub const PIXEL_PAIR: u32 = 0;
pub const LENS_PAIR: u32 = 1;
pub const FIRST_PATH_PAIR: u32 = 2;

/// The hash of a render's seed and a pixel (row-major index in the full image), from
/// which all of the pixel's samples derive.
pub fn pixel_key(seed: u64, pixel: u64) -> u32 {
    let h = splitmix64(splitmix64(seed) ^ pixel);
    (h ^ (h >> 32)) as u32
}

/// The numbers of one pixel sample per lane: for each dimension pair `d`, a 2D point
/// that is a function of (pixel key, sample index, `d`) only, so a sample draws the
/// same numbers whatever else is rendered with it (shards, `--spp-offset`, lanes,
/// threads). With [`SamplerKind::Sobol`], pair `d` of a pixel's samples `0..n` is a
/// stratified set of its own.
#[derive(Clone, Copy)]
pub struct SampleStream<L: Lanes> {
    pub kind: SamplerKind,
    pub key: L::U,
    pub index: L::U,
}

/// The hash of a dimension pair's number, which seeds its set with the pixel's key.
#[inline(always)]
fn pair_hash<U: UInt>(pair: U) -> U {
    hash32(
        pair.wrapping_mul(pair.splat_as(0x9e37_79b9))
            .wrapping_add(pair.splat_as(1)),
    )
}

impl<L: Lanes> SampleStream<L> {
    /// The point of dimension pair `pair` (per lane).
    #[inline(always)]
    pub fn get_2d(&self, pair: L::U) -> (L::F, L::F) {
        self.get_2d_hashed(pair_hash(pair))
    }

    /// The point of pair `pair`, stratified jointly with pair `partner`: with
    /// [`SamplerKind::Sobol`], dimensions 2 and 3 of the 4D Sobol set whose
    /// dimensions 0 and 1 are `get_2d(partner)` (the same shuffled index). On its
    /// own it is as uniform and as stratified as `get_2d(pair)`; `partner` must not
    /// be coupled to another pair.
    #[inline(always)]
    pub fn get_2d_coupled(&self, partner: L::U, pair: L::U) -> (L::F, L::F) {
        match self.kind {
            SamplerKind::Sobol => sobol_2d_upper(
                self.index,
                self.pair_seed(pair_hash(partner)),
                self.pair_seed(pair_hash(pair)),
            ),
            SamplerKind::Independent => self.get_2d(pair),
        }
    }

    /// `get_2d` of the same pair in every lane.
    #[inline(always)]
    pub fn get_2d_at(&self, l: L, pair: u32) -> (L::F, L::F) {
        self.get_2d_hashed(l.u(pair_hash(pair)))
    }

    /// `get_2d` of the pair whose hash is `pair_hash`.
    #[inline(always)]
    fn get_2d_hashed(&self, pair_hash: L::U) -> (L::F, L::F) {
        let pair_seed = self.pair_seed(pair_hash);
        match self.kind {
            SamplerKind::Sobol => sobol_2d(self.index, pair_seed),
            SamplerKind::Independent => independent_2d(hash32(
                pair_seed.xor(self.index.wrapping_mul(pair_seed.splat_as(0x85eb_ca6b))),
            )),
        }
    }

    /// The seed of the pixel's set of the pair whose hash is `pair_hash`.
    #[inline(always)]
    fn pair_seed(&self, pair_hash: L::U) -> L::U {
        hash32(self.key.xor(pair_hash))
    }

    /// Lane `i` of `other` where `m`, else of `self`.
    #[inline(always)]
    pub fn select(m: L::M, other: Self, this: Self) -> Self {
        SampleStream {
            kind: this.kind,
            key: L::U::select(m, other.key, this.key),
            index: L::U::select(m, other.index, this.index),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lanes::{One, SimdTask};

    #[derive(Clone)]
    struct LanesMatch;

    impl SimdTask for LanesMatch {
        type Output = ();
        fn run<S: crate::lanes::Simd>(self, s: S) {
            use crate::lanes::LANES;
            for kind in [SamplerKind::Sobol, SamplerKind::Independent] {
                let keys: [u32; LANES] = std::array::from_fn(|i| pixel_key(7, 1000 * i as u64));
                let index: [u32; LANES] = std::array::from_fn(|i| (i as u32 * 37) % 11);
                let pairs: [u32; LANES] = std::array::from_fn(|i| i as u32 % 5 + 3);
                let lanes = SampleStream::<S> {
                    kind,
                    key: s.u_from(keys),
                    index: s.u_from(index),
                };
                let partners: [u32; LANES] = std::array::from_fn(|i| i as u32 % 3);
                let (x, y) = lanes.get_2d(s.u_from(pairs));
                let (x, y) = (x.to_array(), y.to_array());
                let (cx, cy) = lanes.get_2d_coupled(s.u_from(partners), s.u_from(pairs));
                let (cx, cy) = (cx.to_array(), cy.to_array());
                for i in 0..LANES {
                    let one = SampleStream::<One> {
                        kind,
                        key: keys[i],
                        index: index[i],
                    };
                    let (a, b) = one.get_2d(pairs[i]);
                    assert_eq!((a.to_bits(), b.to_bits()), (x[i].to_bits(), y[i].to_bits()));
                    let (a, b) = one.get_2d_coupled(partners[i], pairs[i]);
                    assert_eq!(
                        (a.to_bits(), b.to_bits()),
                        (cx[i].to_bits(), cy[i].to_bits())
                    );
                }
            }
        }
    }

    #[test]
    fn lanes_draw_what_one_path_draws() {
        crate::lanes::simd::run_each(LanesMatch);
    }

    /// The pairs of one sample are independent: for the first 4096 samples of a
    /// pixel, the 4D points made of two pairs fill a 4×4×4×4 grid evenly (chi-square),
    /// for neighbouring and distant pairs alike, and for a pair coupled to a third
    /// (`Some(partner)`) against any other.
    #[test]
    fn pairs_of_a_sample_are_independent_of_each_other() {
        for kind in [SamplerKind::Sobol, SamplerKind::Independent] {
            let cases = [
                (0u32, 1u32, None),
                (2, 3, None),
                (5, 40, None),
                (7, 1000, None),
                (2, 4, Some(0)),
                (0, 9, Some(2)),
                (3, 4, Some(2)),
            ];
            for (p, q, partner) in cases {
                let mut cells = [0u32; 256];
                let n = 4096u32;
                for i in 0..n {
                    let s = SampleStream::<One> {
                        kind,
                        key: pixel_key(3, 77),
                        index: i,
                    };
                    let (a, b) = s.get_2d(p);
                    let (c, d) = match partner {
                        Some(r) => s.get_2d_coupled(r, q),
                        None => s.get_2d(q),
                    };
                    let k = |v: f32| (v * 4.0) as usize;
                    cells[k(a) + 4 * k(b) + 16 * k(c) + 64 * k(d)] += 1;
                }
                let e = n as f64 / 256.0;
                let chi2: f64 = cells.iter().map(|&o| (o as f64 - e).powi(2) / e).sum();
                // 255 degrees of freedom: mean 255, sd 22.6; 3.5 sd is p ≈ 2e-4.
                assert!(
                    chi2 < 255.0 + 3.5 * 22.6,
                    "{kind:?} pairs {p},{q} (coupled to {partner:?}): χ² {chi2}"
                );
            }
        }
    }
}
