//! Low-discrepancy points and hashes over any lane type, from 32-bit integer
//! operations only.
//!
//! Stratified points are Burley's "practical hash-based Owen scrambling" (2020), the
//! scheme of Cycles' Sobol-Burley sampler: each 2D point is the first two dimensions
//! of the Sobol sequence (a (0,2)-sequence: every aligned block of 2ᵐ points puts one
//! point in each of the 2ᵐ elementary intervals of every shape) at a shuffled index,
//! Owen-scrambled. The shuffle (a nested uniform scramble of the index, a
//! permutation of every aligned block) and the scrambles are seeded by a hash of the
//! pixel and the dimension pair, so every pair of numbers a path draws is its own
//! stratified set, independent of the others ("padding", as pbrt-v4's
//! `PaddedSobolSampler`), and pixels are independent of each other.

use crate::lanes::{Real, UInt};

/// Chris Wellons' `lowbias32` integer hash.
#[inline(always)]
pub fn hash32<U: UInt>(x: U) -> U {
    let x = x.xor(x.shr::<16>()).wrapping_mul(x.splat_as(0x7feb_352d));
    let x = x.xor(x.shr::<15>()).wrapping_mul(x.splat_as(0x846c_a68b));
    x.xor(x.shr::<16>())
}

/// The Laine–Karras permutation with pbrt-v4's constants (`FastOwenScrambler`): bit
/// `k` of `x` is flipped by a hash of `seed` and the bits below `k`. Applied to a
/// value's bits reversed, it is an Owen scramble of the value.
#[inline(always)]
fn laine_karras<U: UInt>(x: U, seed: U) -> U {
    let v = x.xor(x.wrapping_mul(x.splat_as(0x3d20_adea)));
    let v = v.wrapping_add(seed);
    let v = v.wrapping_mul(seed.shr::<16>() | x.splat_as(1));
    let v = v.xor(v.wrapping_mul(x.splat_as(0x0552_6c56)));
    v.xor(v.wrapping_mul(x.splat_as(0x53a2_2864)))
}

/// The Owen scramble of the value whose bits reversed are `reversed`.
#[inline(always)]
pub fn owen_scrambled<U: UInt>(reversed: U, seed: U) -> U {
    laine_karras(reversed, seed).reverse_bits()
}

/// The second Sobol dimension at `i`, bits reversed, without a table: its generator
/// is Pascal's triangle mod 2, so output digit `j` is the XOR of the index bits
/// `k ⊇ j` (Lucas), a superset sum done one bit of `j` at a time.
#[inline(always)]
pub fn sobol_pascal<U: UInt>(i: U) -> U {
    let y = i.xor(i.shr::<1>() & i.splat_as(0x5555_5555));
    let y = y.xor(y.shr::<2>() & i.splat_as(0x3333_3333));
    let y = y.xor(y.shr::<4>() & i.splat_as(0x0f0f_0f0f));
    let y = y.xor(y.shr::<8>() & i.splat_as(0x00ff_00ff));
    y.xor(y.shr::<16>() & i.splat_as(0x0000_ffff))
}

/// The top 24 bits as a float in `[0, 1)`.
#[inline(always)]
pub fn to_unit<U: UInt>(bits: U) -> U::F {
    let f = bits.shr::<8>().to_f32();
    f * f.splat_as(1.0 / (1u32 << 24) as f32)
}

/// Point `index` of the stratified set seeded by `seed`: Sobol dimensions 0 and 1 at
/// the index shuffled within its aligned blocks, each Owen-scrambled.
#[inline(always)]
pub fn sobol_2d<U: UInt>(index: U, seed: U) -> (U::F, U::F) {
    // The nested uniform scramble of the index: `owen_scrambled` of its reversal.
    let j = owen_scrambled(index.reverse_bits(), seed);
    // Dimension 0 (van der Corput) at j, bits reversed, is j itself.
    let x = owen_scrambled(j, hash32(seed.xor(index.splat_as(0xa511_e9b3))));
    let y = owen_scrambled(
        sobol_pascal(j),
        hash32(seed.xor(index.splat_as(0x63d8_3595))),
    );
    (to_unit(x), to_unit(y))
}

/// Two independent uniform numbers for the hash `h` of (pixel, sample, pair).
#[inline(always)]
pub fn independent_2d<U: UInt>(h: U) -> (U::F, U::F) {
    let x = hash32(h.xor(h.splat_as(0x68bc_21eb)));
    let y = hash32(h.xor(h.splat_as(0x02e5_be93)));
    (to_unit(x), to_unit(y))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sobol_pascal_is_the_second_sobol_dimension() {
        // Direction numbers of x + 1: v₀ = 2³¹, vₖ = vₖ₋₁ ⊕ (vₖ₋₁ >> 1).
        let columns: Vec<u32> = std::iter::successors(Some(1u32 << 31), |v| Some(v ^ (v >> 1)))
            .take(32)
            .collect();
        for i in (0..4096u32).chain([0xffff_ffff, 0x8000_0001, 0x1234_5678]) {
            let direct = (0..32)
                .filter(|k| i >> k & 1 != 0)
                .fold(0, |v, k| v ^ columns[k]);
            assert_eq!(sobol_pascal(i).reverse_bits(), direct, "index {i}");
        }
    }

    /// Every aligned block of 2ᵐ points is a (0, m, 2)-net: one point in every
    /// elementary interval of area 2⁻ᵐ, whatever the seed.
    #[test]
    fn aligned_blocks_are_nets() {
        let m = 8;
        let n = 1u32 << m;
        for seed in [0u32, 1, 0xdead_beef, 0x1234_5678] {
            for block in [0u32, 1, 7] {
                let pts: Vec<(f32, f32)> = (0..n).map(|i| sobol_2d(block * n + i, seed)).collect();
                for bx in 0..=m {
                    let (cols, rows) = (1u32 << bx, 1u32 << (m - bx));
                    let mut seen = vec![0u32; n as usize];
                    for &(x, y) in &pts {
                        let cell = (y * rows as f32) as u32 * cols + (x * cols as f32) as u32;
                        seen[cell as usize] += 1;
                    }
                    assert!(
                        seen.iter().all(|&c| c == 1),
                        "seed {seed:#x}, block {block}, {cols}x{rows}"
                    );
                }
            }
        }
    }

    /// Different seeds give unrelated sets: the product of two sets' coordinates
    /// averages to 1/4 (sets tied by a fixed map would not).
    #[test]
    fn seeds_give_independent_sets() {
        let n = 1u32 << 12;
        for (a, b) in [(1u32, 2u32), (7, 8), (0x100, 0x101)] {
            let mut sum = [0.0f64; 4];
            for i in 0..n {
                let (x0, y0) = sobol_2d(i, hash32(a));
                let (x1, y1) = sobol_2d(i, hash32(b));
                let p = [x0 * x1, y0 * y1, x0 * y1, y0 * x1];
                for (s, v) in sum.iter_mut().zip(p) {
                    *s += v as f64;
                }
            }
            for s in sum {
                // A product of independent uniforms: mean 1/4, sd (7/144)^½ per point.
                let mean = s / n as f64;
                let se = (7.0f64 / 144.0).sqrt() / (n as f64).sqrt();
                assert!((mean - 0.25).abs() < 4.0 * se, "seeds {a}, {b}: {mean}");
            }
        }
    }
}
