//! Warps from `[0,1)²` to points and directions, each next to its density, over any
//! lane type. The `glam` functions at the end are the one-path forms for callers
//! outside the transport (tests, benchmarks).

use crate::lanes::math::{sin_cos_quarter, sin_cos_turns};
use crate::lanes::{Real, V3};
use glam::{Vec2, Vec3};
use std::f32::consts::{FRAC_1_PI, FRAC_PI_4};

/// Shirley-Chiu concentric map of the square onto the unit disk. The angle is
/// measured from the nearer axis (`|φ| ≤ π/4`), where the quarter polynomials need
/// no range reduction.
#[inline(always)]
pub fn concentric_disk_l<F: Real>(u1: F, u2: F) -> (F, F) {
    let (ox, oy) = (
        u1.splat_as(2.0) * u1 - u1.splat_as(1.0),
        u1.splat_as(2.0) * u2 - u1.splat_as(1.0),
    );
    let centre = ox.eq(u1.splat_as(0.0)) & oy.eq(u1.splat_as(0.0));
    let x_major = ox.abs().gt(oy.abs());
    let r = F::select(x_major, ox, oy);
    let ratio = F::select(x_major, oy / ox, ox / oy);
    let (sin, cos) = sin_cos_quarter(u1.splat_as(FRAC_PI_4) * ratio);
    let x = F::select(x_major, r * cos, r * sin);
    let y = F::select(x_major, r * sin, r * cos);
    (
        F::select(centre, u1.splat_as(0.0), x),
        F::select(centre, u1.splat_as(0.0), y),
    )
}

/// Cosine-weighted direction on the hemisphere `z ≥ 0` (Malley's method).
#[inline(always)]
pub fn cosine_hemisphere_l<F: Real>(u1: F, u2: F) -> V3<F> {
    let (x, y) = concentric_disk_l(u1, u2);
    let z = (u1.splat_as(1.0) - (x * x + y * y))
        .max(u1.splat_as(0.0))
        .sqrt();
    V3::new(x, y, z)
}

#[inline(always)]
pub fn cosine_hemisphere_pdf_l<F: Real>(cos_theta: F) -> F {
    cos_theta.max(cos_theta.splat_as(0.0)) * cos_theta.splat_as(FRAC_1_PI)
}

/// Uniform direction on the hemisphere `z ≥ 0`.
#[inline(always)]
pub fn uniform_hemisphere_l<F: Real>(u1: F, u2: F) -> V3<F> {
    let z = u1;
    let r = (u1.splat_as(1.0) - z * z).max(u1.splat_as(0.0)).sqrt();
    let (sin, cos) = sin_cos_turns(u2);
    V3::new(r * cos, r * sin, z)
}

/// Uniform direction on the unit sphere.
#[inline(always)]
pub fn uniform_sphere_l<F: Real>(u1: F, u2: F) -> V3<F> {
    let z = u1.splat_as(1.0) - u1.splat_as(2.0) * u1;
    let r = (u1.splat_as(1.0) - z * z).max(u1.splat_as(0.0)).sqrt();
    let (sin, cos) = sin_cos_turns(u2);
    V3::new(r * cos, r * sin, z)
}

/// Uniform point on the parallelogram `s·ex + t·ey`, `s, t ∈ [−½, ½]`, relative to
/// its centre; its area density is `1/|ex × ey|`.
#[inline(always)]
pub fn uniform_parallelogram_l<F: Real>(u1: F, u2: F, ex: V3<F>, ey: V3<F>) -> V3<F> {
    let half = u1.splat_as(0.5);
    ex * (u1 - half) + ey * (u2 - half)
}

pub fn uniform_hemisphere_pdf() -> f32 {
    0.5 * FRAC_1_PI
}

pub fn uniform_sphere_pdf() -> f32 {
    0.25 * FRAC_1_PI
}

pub fn concentric_disk(u: Vec2) -> Vec2 {
    let (x, y) = concentric_disk_l(u.x, u.y);
    Vec2::new(x, y)
}

pub fn cosine_hemisphere(u: Vec2) -> Vec3 {
    cosine_hemisphere_l(u.x, u.y).vec3()
}

pub fn cosine_hemisphere_pdf(cos_theta: f32) -> f32 {
    cosine_hemisphere_pdf_l(cos_theta)
}

pub fn uniform_hemisphere(u: Vec2) -> Vec3 {
    uniform_hemisphere_l(u.x, u.y).vec3()
}

pub fn uniform_sphere(u: Vec2) -> Vec3 {
    uniform_sphere_l(u.x, u.y).vec3()
}

/// Uniform direction in the cone about +Z of `cos θ ≥ 1 − one_minus_cos_max` (given
/// as that difference, which stays exact for narrow cones); its pdf is
/// `1/(2π·one_minus_cos_max)`.
pub fn uniform_cone(u: Vec2, one_minus_cos_max: f32) -> Vec3 {
    let cos_theta = 1.0 - u.x * one_minus_cos_max;
    let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
    let phi = 2.0 * std::f32::consts::PI * u.y;
    Vec3::new(sin_theta * phi.cos(), sin_theta * phi.sin(), cos_theta)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;
    use std::f32::consts::PI;

    #[test]
    fn concentric_disk_keeps_the_angle_and_radius_of_the_square() {
        let mut rng = Rng::from_seed(3);
        for _ in 0..10_000 {
            let u = rng.next_2d();
            let d = concentric_disk(u);
            let o = 2.0 * u - Vec2::ONE;
            let r = o.x.abs().max(o.y.abs());
            assert!((d.length() - r).abs() < 1e-6, "{u:?}");
            let theta = if o.x.abs() > o.y.abs() {
                FRAC_PI_4 * (o.y / o.x) + if o.x < 0.0 { PI } else { 0.0 }
            } else {
                std::f32::consts::FRAC_PI_2 - FRAC_PI_4 * (o.x / o.y)
                    + if o.y < 0.0 { PI } else { 0.0 }
            };
            let want = Vec2::new(theta.cos(), theta.sin()) * r;
            assert!((d - want).length() < 2e-6, "{u:?}: {d:?} vs {want:?}");
        }
    }

    #[test]
    fn sphere_directions_are_unit_and_cover_the_sphere() {
        let mut rng = Rng::from_seed(4);
        let mut octants = [0u32; 8];
        for _ in 0..8000 {
            let w = uniform_sphere(rng.next_2d());
            assert!((w.length() - 1.0).abs() < 1e-5);
            let k =
                (w.x > 0.0) as usize | ((w.y > 0.0) as usize) << 1 | ((w.z > 0.0) as usize) << 2;
            octants[k] += 1;
        }
        assert!(
            octants.iter().all(|&c| (850..1150).contains(&c)),
            "{octants:?}"
        );
    }
}
