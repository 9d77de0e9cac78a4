//! Lights of spec §5. Each can be sampled from a shading point (`sample_li`) and
//! evaluated for MIS when a ray finds it (`pdf_li`).

pub mod ambient;
pub mod area;
pub mod directional;
pub mod emit;
pub mod environment;
pub mod point;
pub mod spot;

use crate::color::luminance;
use crate::Color;
pub use area::AreaLight;
pub use environment::EnvironmentMap;
use glam::{Vec2, Vec3};
pub use spot::SpotLight;
use std::f32::consts::PI;
use std::sync::Arc;

#[derive(Clone, Debug, PartialEq)]
pub enum Light {
    /// One-sided parallelogram owning its surface and its radiance.
    Area(AreaLight),
    /// Isotropic point light of radiant intensity `intensity` (W/sr).
    Point { position: Vec3, intensity: Color },
    /// Point light whose intensity falls off away from its axis (COLLADA `<spot>`).
    Spot(SpotLight),
    /// Light travelling along unit `direction`; `irradiance` on a surface facing it.
    Directional { direction: Vec3, irradiance: Color },
    /// Constant radiance from the upper hemisphere (world +Y).
    Ambient { radiance: Color },
    /// Radiance from every direction, read from a latitude-longitude map (`-e`).
    Environment(Arc<EnvironmentMap>),
}

/// Incident light drawn by `Light::sample_li`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightSample {
    /// Unit world direction from the shading point toward the light.
    pub wi: Vec3,
    /// Distance to the sampled point (infinite for directional and ambient lights).
    pub dist: f32,
    /// Point on the light, for the shadow ray (finite lights; infinite for
    /// directional and ambient lights, whose shadow rays use `dist`).
    pub p_light: Vec3,
    /// Incident radiance (delta lights: the irradiance-like factor the estimator multiplies by).
    pub li: Color,
    /// Solid-angle pdf of `wi` (1 for delta lights).
    pub pdf: f32,
    pub delta: bool,
}

impl Light {
    pub fn is_delta(&self) -> bool {
        matches!(
            self,
            Light::Point { .. } | Light::Spot(_) | Light::Directional { .. }
        )
    }

    /// True for a light that surrounds the scene (ambient, environment map), which
    /// light sampling alone covers poorly (near the horizon, or between a map's
    /// bright spots), so MIS is the better default.
    pub fn is_environment(&self) -> bool {
        matches!(self, Light::Ambient { .. } | Light::Environment(_))
    }

    /// Draws a direction toward the light from `p`; `None` when `p` receives
    /// nothing from that sample (behind an area light, degenerate light).
    pub fn sample_li(&self, p: Vec3, u: Vec2) -> Option<LightSample> {
        match *self {
            Light::Area(a) => a.sample_li(p, u),
            Light::Point {
                position,
                intensity,
            } => point::sample_li(position, intensity, p),
            Light::Spot(s) => s.sample_li(p),
            Light::Directional {
                direction,
                irradiance,
            } => directional::sample_li(direction, irradiance),
            Light::Ambient { radiance } => ambient::sample_li(radiance, u),
            Light::Environment(ref env) => env.sample_li(u),
        }
    }

    /// Solid-angle pdf with which `sample_li(p, ·)` returns `wi` (0 for delta lights).
    pub fn pdf_li(&self, p: Vec3, wi: Vec3) -> f32 {
        match *self {
            Light::Area(a) => a.pdf_li(p, wi),
            Light::Ambient { .. } => ambient::pdf_li(wi),
            Light::Environment(ref env) => env.pdf_li(wi),
            Light::Point { .. } | Light::Spot(_) | Light::Directional { .. } => 0.0,
        }
    }

    /// Distance from `p` along unit `wi` to the emitting front of an area light
    /// (`None` for a miss, a hit from behind, or another kind of light).
    pub fn intersect_area(&self, p: Vec3, wi: Vec3) -> Option<f32> {
        self.as_area()?.intersect(p, wi)
    }

    /// Whether the line from surface point `p` along unit `w` meets this light (always,
    /// for lights without a shape). A ray spawned at `p` starts off the surface, by `p`'s
    /// rounding error (pbrt's `OffsetRayOrigin`: a few ulps of the coordinates), on a
    /// parallel line that much closer to what it finds: an area light seen from there
    /// covers more directions than from `p` (stability case 5). A light found by such a
    /// ray counts only if this test, relative to the light, says `p` sees it too.
    pub fn seen_along(&self, p: Vec3, w: Vec3) -> bool {
        match self {
            Light::Area(a) => a.intersect(p, w).is_some(),
            _ => true,
        }
    }

    /// Approximate emitted power (luminance), for choosing lights in proportion to
    /// it. Infinite lights count what crosses a disk of radius `scene_radius`.
    pub fn power(&self, scene_radius: f32) -> f32 {
        let disk = PI * scene_radius * scene_radius;
        let value = match *self {
            // Lambertian emitter: π·L per unit area.
            Light::Area(a) => PI * a.area() * luminance(a.radiance),
            Light::Point { intensity, .. } => 4.0 * PI * luminance(intensity),
            Light::Spot(s) => s.solid_angle_weight() * luminance(s.intensity),
            Light::Directional { irradiance, .. } => disk * luminance(irradiance),
            // Half of pbrt's uniform-sphere 4π·πr²·L.
            Light::Ambient { radiance } => 2.0 * PI * disk * luminance(radiance),
            Light::Environment(ref env) => disk * env.luminance_integral(),
        };
        if value.is_finite() {
            value.max(0.0)
        } else {
            0.0
        }
    }

    /// Radiance an escaping ray in unit direction `w` receives from this light
    /// (ambient and environment lights only).
    pub fn le_escaped(&self, w: Vec3) -> Color {
        match self {
            Light::Ambient { radiance } if w.y > 0.0 => *radiance,
            Light::Environment(env) => env.le(w),
            _ => Color::ZERO,
        }
    }

    /// The area light this is, if it is one.
    pub fn as_area(&self) -> Option<&AreaLight> {
        match self {
            Light::Area(a) => Some(a),
            _ => None,
        }
    }
}
