//! Random numbers and the warps from `[0,1)²` to directions, each next to its pdf.

use glam::{Vec2, Vec3};
use rand_core::{RngCore, SeedableRng};
use rand_pcg::Pcg32;
use std::f32::consts::{FRAC_1_PI, PI};

/// A random stream. Seeded from (render seed, pixel, pass) or (render seed, pixel,
/// sample index) only, so an image is the same whatever the thread count or tile order.
pub struct Sampler {
    rng: Pcg32,
}

impl Sampler {
    /// The stream of sample `sample` of pixel `pixel` (row-major index in the full image).
    /// Counter-based: the PCG32 state and stream are a SplitMix64 hash of
    /// (seed, pixel, sample), so sample `S` is the same whether a render takes samples
    /// `0..N` or only `S..S+M` (`--spp-offset`), and shards of samples merge into the
    /// render of all of them.
    pub fn for_sample(seed: u64, pixel: u64, sample: u64) -> Self {
        PixelStreams::new(seed, pixel).sample(sample)
    }

    pub fn new(seed: u64, pixel: u64, pass: u64) -> Self {
        let state = splitmix64(seed ^ splitmix64(pixel.wrapping_add(0x9E37_79B9_7F4A_7C15)));
        let stream = splitmix64(pass ^ 0xD1B5_4A32_D192_ED03).wrapping_add(pixel);
        Sampler {
            rng: Pcg32::new(state, stream),
        }
    }

    pub fn from_seed(seed: u64) -> Self {
        Sampler {
            rng: Pcg32::seed_from_u64(seed),
        }
    }

    /// Uniform in `[0, 1)`.
    #[inline]
    pub fn next_f32(&mut self) -> f32 {
        (self.rng.next_u32() >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
    }

    #[inline]
    pub fn next_2d(&mut self) -> Vec2 {
        let x = self.next_f32();
        Vec2::new(x, self.next_f32())
    }
}

/// The streams of one pixel's samples (`Sampler::for_sample`), with the hash of (seed,
/// pixel) done once: a render's inner loop then hashes only the sample index.
#[derive(Clone, Copy, Debug)]
pub struct PixelStreams {
    key: u64,
}

impl PixelStreams {
    pub fn new(seed: u64, pixel: u64) -> Self {
        PixelStreams {
            key: splitmix64(splitmix64(seed) ^ pixel),
        }
    }

    /// The stream of sample `sample`: the same as `Sampler::for_sample(seed, pixel, sample)`.
    #[inline]
    pub fn sample(&self, sample: u64) -> Sampler {
        let key = splitmix64(self.key ^ sample);
        let stream = splitmix64(key ^ 0xD1B5_4A32_D192_ED03);
        Sampler {
            rng: Pcg32::new(key, stream),
        }
    }
}

#[inline]
fn splitmix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Uniform direction on the hemisphere `z > 0`.
pub fn uniform_hemisphere(u: Vec2) -> Vec3 {
    let z = u.x;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

pub fn uniform_hemisphere_pdf() -> f32 {
    0.5 * FRAC_1_PI
}

/// Uniform direction on the unit sphere.
pub fn uniform_sphere(u: Vec2) -> Vec3 {
    let z = 1.0 - 2.0 * u.x;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

pub fn uniform_sphere_pdf() -> f32 {
    0.25 * FRAC_1_PI
}

/// Shirley-Chiu concentric map of the square onto the unit disk.
pub fn concentric_disk(u: Vec2) -> Vec2 {
    let o = 2.0 * u - Vec2::ONE;
    if o.x == 0.0 && o.y == 0.0 {
        return Vec2::ZERO;
    }
    let (r, theta) = if o.x.abs() > o.y.abs() {
        (o.x, std::f32::consts::FRAC_PI_4 * (o.y / o.x))
    } else {
        (
            o.y,
            std::f32::consts::FRAC_PI_2 - std::f32::consts::FRAC_PI_4 * (o.x / o.y),
        )
    };
    r * Vec2::new(theta.cos(), theta.sin())
}

/// Cosine-weighted direction on the hemisphere `z > 0` (Malley's method).
pub fn cosine_hemisphere(u: Vec2) -> Vec3 {
    let d = concentric_disk(u);
    let z = (1.0 - d.length_squared()).max(0.0).sqrt();
    Vec3::new(d.x, d.y, z)
}

pub fn cosine_hemisphere_pdf(cos_theta: f32) -> f32 {
    cos_theta.max(0.0) * FRAC_1_PI
}

/// Veach's power heuristic (β = 2) for `nf` samples of pdf `f` against `ng` of pdf `g`.
pub fn power_heuristic(nf: f32, f_pdf: f32, ng: f32, g_pdf: f32) -> f32 {
    let f = nf * f_pdf;
    let g = ng * g_pdf;
    if f.is_infinite() {
        return 1.0;
    }
    let d = f * f + g * g;
    if d > 0.0 {
        f * f / d
    } else {
        0.0
    }
}

/// Beckmann distribution of microfacet normals,
/// `D(h) = exp(−tan²θh/α²) / (π·α²·cos⁴θh)`, 0 below the surface.
pub fn beckmann_d(h: Vec3, alpha: f32) -> f32 {
    let cos2 = h.z * h.z;
    if h.z <= 0.0 || cos2 <= 0.0 {
        return 0.0;
    }
    let tan2 = (1.0 - cos2).max(0.0) / cos2;
    let alpha2 = alpha * alpha;
    let d = (-tan2 / alpha2).exp() / (PI * alpha2 * cos2 * cos2);
    if d.is_finite() {
        d
    } else {
        0.0
    }
}

/// Microfacet normal drawn with density `D(h)·cos θh` (projected-area normalised,
/// so it integrates to 1): `tan²θ = −α²·ln(1−u)`.
pub fn beckmann_normal(u: Vec2, alpha: f32) -> Vec3 {
    let tan2 = -alpha * alpha * (1.0 - u.x).ln();
    let cos_theta = 1.0 / (1.0 + tan2).sqrt();
    let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    Vec3::new(sin_theta * phi.cos(), sin_theta * phi.sin(), cos_theta)
}

pub fn beckmann_normal_pdf(h: Vec3, alpha: f32) -> f32 {
    beckmann_d(h, alpha) * h.z.max(0.0)
}

/// Uniform point on the parallelogram `centre + s·ex + t·ey`, `s, t ∈ [−½, ½]`;
/// its area density is `1/|ex × ey|`.
pub fn uniform_parallelogram(u: Vec2, centre: Vec3, ex: Vec3, ey: Vec3) -> Vec3 {
    centre + (u.x - 0.5) * ex + (u.y - 0.5) * ey
}
