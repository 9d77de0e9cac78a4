//! Sampling light *leaving* each light (pbrt-v4 `SampleLe`), for estimators whose
//! paths start on the lights (light tracing). Each sample carries
//! `β = Le·|cos θ| / (pdf_pos · pdf_dir)`: the emitted power it stands for.

use super::Light;
use crate::geometry::{Aabb, Frame};
use crate::sampling::{
    concentric_disk, uniform_cone, uniform_hemisphere, uniform_hemisphere_pdf, uniform_sphere,
    uniform_sphere_pdf,
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

/// A sphere that every light path worth tracing must enter: for caustics, the one
/// around the focusing surfaces, which a caustic path's first segment meets. Point
/// and directional lights then emit only toward it (a point light inside it emits
/// everywhere); the other lights ignore it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EmissionAim {
    pub centre: Vec3,
    pub radius: f32,
}

impl EmissionAim {
    /// The bounding sphere of `b`, widened by a thousandth so that rounding never
    /// leaves out a ray that grazes it.
    pub fn around(b: &Aabb) -> Option<Self> {
        let radius = 0.5 * b.diagonal().length() * 1.001;
        (!b.is_empty() && radius.is_finite()).then_some(EmissionAim {
            centre: b.centre(),
            radius: radius.max(1e-6),
        })
    }
}

impl Light {
    /// Whether `sample_le` reads its `u_pos` (lights of a single point do not).
    pub fn samples_position(&self) -> bool {
        match self {
            Light::Point { .. } | Light::Spot(_) | Light::Environment(_) => false,
            Light::Area(_) | Light::Directional { .. } | Light::Ambient { .. } => true,
        }
    }

    /// Draws a point and a direction of emitted light. Lights at infinity (directional,
    /// ambient) emit through a disk of the radius of `bounds`' bounding sphere, facing the
    /// direction of travel, just outside that sphere; with an `aim`, point and
    /// directional lights emit only toward it. `None` for degenerate lights.
    pub fn sample_le(
        &self,
        bounds: &Aabb,
        aim: Option<EmissionAim>,
        u_pos: Vec2,
        u_dir: Vec2,
    ) -> Option<EmissionSample> {
        let s = match *self {
            // Environment maps do not start light paths (yet): the CLI refuses
            // light tracing with -e and `light_tracing::warnings` says so.
            Light::Environment(_) => return None,
            Light::Area(a) => a.sample_le(u_pos, u_dir),
            Light::Point {
                position,
                intensity,
            } => match aim.and_then(|a| cone_toward(position, a)) {
                // Uniform in the cone that holds the sphere: pdf 1/(2π(1 − cos θmax)).
                Some((axis, one_minus_cos)) => EmissionSample {
                    origin: position,
                    on_surface: None,
                    dir: Frame::from_normal(axis).to_world(uniform_cone(u_dir, one_minus_cos)),
                    beta: intensity * (2.0 * PI * one_minus_cos),
                },
                None => EmissionSample {
                    origin: position,
                    on_surface: None,
                    dir: uniform_sphere(u_dir),
                    beta: intensity / uniform_sphere_pdf(),
                },
            },
            Light::Spot(s) => s.sample_le(u_dir)?,
            Light::Directional {
                direction,
                irradiance,
            } => disk_emission(bounds, aim, direction, irradiance, u_pos, 1.0),
            Light::Ambient { radiance } => {
                // Light arrives from ω (ω·Y > 0) and travels along −ω.
                let omega = Frame::from_normal(Vec3::Y).to_world(uniform_hemisphere(u_dir));
                disk_emission(
                    bounds,
                    None,
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

/// The axis toward `aim` from `p` and `1 − cos θmax` of the cone that holds it
/// (computed from sin²θmax, exact for narrow cones); `None` when `p` is inside.
fn cone_toward(p: Vec3, aim: EmissionAim) -> Option<(Vec3, f32)> {
    let to = aim.centre - p;
    let d = to.length();
    let sin2 = (aim.radius / d).powi(2);
    (d > aim.radius && sin2.is_finite()).then(|| (to / d, sin2 / (1.0 + (1.0 - sin2).sqrt())))
}

/// Parallel light travelling along `dir` through a disk facing it of the radius `r`
/// of `aim` (default: `bounds`' bounding sphere), on the line through its centre and
/// starting just outside `bounds`' bounding sphere: pdf_pos = 1/(πr²), so
/// β = `value`·πr²·`dir_weight`.
fn disk_emission(
    bounds: &Aabb,
    aim: Option<EmissionAim>,
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
    let (centre, radius) = aim.map_or((c, r), |a| (a.centre, a.radius));
    // Back from the disk's centre far enough to leave the scene's sphere.
    let back = 1.01 * ((centre - c).length() + r);
    let frame = Frame::from_normal(dir);
    let d = concentric_disk(u) * radius;
    EmissionSample {
        origin: centre - back * dir + frame.s.vec3() * d.x + frame.t.vec3() * d.y,
        on_surface: None,
        dir,
        beta: value * (PI * radius * radius * dir_weight),
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
            .sample_le(&b, None, Vec2::new(0.3, 0.7), Vec2::new(0.2, 0.9))
            .unwrap();
        assert!((s.beta.x - PI * 3.0).abs() < 1e-4);
        assert!(s.dir.y < 0.0 && s.origin.y < 1.0 && s.on_surface.unwrap().y == 1.0);
        let point = Light::Point {
            position: Vec3::ZERO,
            intensity: Color::splat(2.0),
        };
        let s = point
            .sample_le(&b, None, Vec2::ZERO, Vec2::new(0.4, 0.1))
            .unwrap();
        assert!((s.beta.x - 8.0 * PI).abs() < 1e-3);
        assert!((s.dir.length() - 1.0).abs() < 1e-5);
    }

    /// Aimed at a sphere, a point light outside it emits only into the cone that holds
    /// the sphere, carrying that cone's share of its power, and a directional light
    /// only through a disk of the sphere's radius, starting outside the scene.
    #[test]
    fn aimed_emission_meets_the_sphere_and_carries_its_share() {
        let b = Aabb::new(Vec3::splat(-4.0), Vec3::splat(4.0));
        let aim = EmissionAim {
            centre: Vec3::new(1.0, 0.5, 0.0),
            radius: 0.5,
        };
        let meets = |o: Vec3, d: Vec3| {
            let t = (aim.centre - o).dot(d).max(0.0);
            (o + t * d - aim.centre).length() <= aim.radius * (1.0 + 1e-4)
        };
        let point = Light::Point {
            position: Vec3::new(-2.0, 0.5, 0.0),
            intensity: Color::splat(2.0),
        };
        let sun = Light::Directional {
            direction: Vec3::new(1.0, -1.0, 0.5).normalize(),
            irradiance: Color::splat(3.0),
        };
        // sin θmax = 0.5/3: 1 − cos θmax = 1 − √(35/36).
        let cone = 2.0 * PI * (1.0 - (35.0f32 / 36.0).sqrt());
        for k in 0..64 {
            let u = Vec2::new((k % 8) as f32 / 8.0 + 0.06, (k / 8) as f32 / 8.0 + 0.03);
            let v = Vec2::new(u.y, 1.0 - u.x);
            let s = point.sample_le(&b, Some(aim), u, v).unwrap();
            assert!(meets(s.origin, s.dir), "{s:?}");
            assert!((s.beta.x - 2.0 * cone).abs() < 1e-4 * s.beta.x, "{s:?}");
            let s = sun.sample_le(&b, Some(aim), u, v).unwrap();
            assert!(meets(s.origin, s.dir), "{s:?}");
            assert!((s.origin - b.centre()).length() > 0.5 * b.diagonal().length());
            assert!((s.beta.x - 3.0 * PI * 0.25).abs() < 1e-5, "{s:?}");
        }
        // From inside the sphere a point light emits everywhere.
        let inside = Light::Point {
            position: aim.centre,
            intensity: Color::ONE,
        };
        let s = inside.sample_le(&b, Some(aim), Vec2::new(0.3, 0.2), Vec2::new(0.9, 0.4));
        assert!((s.unwrap().beta.x - 4.0 * PI).abs() < 1e-4);
    }
}
