//! Sampling light *leaving* each light (pbrt-v4 `SampleLe`), for estimators whose
//! paths start on the lights (light tracing). Each sample carries
//! `β = Le·|cos θ| / (pdf_pos · pdf_dir)`: the emitted power it stands for.

use super::Light;
use crate::geometry::{Aabb, Frame};
use crate::sampling::{
    concentric_disk, uniform_hemisphere, uniform_hemisphere_pdf, uniform_sphere, uniform_sphere_pdf,
};
use crate::Color;
use glam::{Vec2, Vec3};
use std::f32::consts::PI;

/// A ray of emitted light drawn by `Light::sample_le`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EmissionSample {
    /// Ray origin (moved off the light's own surface for area lights).
    pub origin: Vec3,
    /// The sampled point on an area light's surface, which `origin` was moved off:
    /// where the ray's line starts (see `Scene::on_line`).
    pub on_surface: Option<Vec3>,
    /// Unit direction of travel.
    pub dir: Vec3,
    /// `Le·|cos θ| / (pdf_pos·pdf_dir)`; the light's selection probability is not included.
    pub beta: Color,
}

impl Light {
    /// Draws a point and a direction of emitted light. Lights at infinity (directional,
    /// ambient) emit through a disk of the radius of `bounds`' bounding sphere, facing the
    /// direction of travel, just outside that sphere. `None` for degenerate lights.
    pub fn sample_le(&self, bounds: &Aabb, u_pos: Vec2, u_dir: Vec2) -> Option<EmissionSample> {
        let s = match *self {
            // Environment maps do not start light paths (yet): the CLI refuses
            // light tracing with -e and `light_tracing::warnings` says so.
            Light::Environment(_) => return None,
            Light::Area(a) => a.sample_le(u_pos, u_dir),
            Light::Point {
                position,
                intensity,
            } => EmissionSample {
                origin: position,
                on_surface: None,
                dir: uniform_sphere(u_dir),
                beta: intensity / uniform_sphere_pdf(),
            },
            Light::Spot(s) => s.sample_le(u_dir)?,
            Light::Directional {
                direction,
                irradiance,
            } => disk_emission(bounds, direction, irradiance, u_pos, 1.0),
            Light::Ambient { radiance } => {
                // Light arrives from ω (ω·Y > 0) and travels along −ω.
                let omega = Frame::from_normal(Vec3::Y).to_world(uniform_hemisphere(u_dir));
                disk_emission(
                    bounds,
                    -omega.normalize(),
                    radiance,
                    u_pos,
                    1.0 / uniform_hemisphere_pdf(),
                )
            }
        };
        (s.dir.is_finite() && s.origin.is_finite() && crate::color::is_finite(s.beta)).then_some(s)
    }
}

/// Parallel light travelling along `dir` through a disk of the scene's bounding radius
/// `r`: pdf_pos = 1/(πr²), so β = `value`·πr²·`dir_weight`.
fn disk_emission(
    bounds: &Aabb,
    dir: Vec3,
    value: Color,
    u: Vec2,
    dir_weight: f32,
) -> EmissionSample {
    let (c, r) = if bounds.is_empty() {
        (Vec3::ZERO, 1.0)
    } else {
        (bounds.centre(), 0.5 * bounds.diagonal().length().max(1e-6))
    };
    let frame = Frame::from_normal(dir);
    let d = concentric_disk(u) * r;
    EmissionSample {
        origin: c - 1.01 * r * dir + frame.s.vec3() * d.x + frame.t.vec3() * d.y,
        on_surface: None,
        dir,
        beta: value * (PI * r * r * dir_weight),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The mean β of a light's emission samples is its total power (Lambertian area:
    /// π·A·L, point: 4π·I).
    #[test]
    fn beta_is_emitted_power() {
        let b = Aabb::new(Vec3::splat(-1.0), Vec3::splat(1.0));
        let area = Light::Area(super::super::AreaLight {
            centre: Vec3::Y,
            ex: Vec3::X * 0.5,
            ey: Vec3::Z * 2.0,
            normal: -Vec3::Y,
            radiance: Color::splat(3.0),
        });
        let s = area
            .sample_le(&b, Vec2::new(0.3, 0.7), Vec2::new(0.2, 0.9))
            .unwrap();
        assert!((s.beta.x - PI * 3.0).abs() < 1e-4);
        assert!(s.dir.y < 0.0 && s.origin.y < 1.0 && s.on_surface.unwrap().y == 1.0);
        let point = Light::Point {
            position: Vec3::ZERO,
            intensity: Color::splat(2.0),
        };
        let s = point
            .sample_le(&b, Vec2::ZERO, Vec2::new(0.4, 0.1))
            .unwrap();
        assert!((s.beta.x - 8.0 * PI).abs() < 1e-3);
        assert!((s.dir.length() - 1.0).abs() < 1e-5);
    }
}
