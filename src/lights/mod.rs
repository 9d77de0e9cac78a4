//! Lights of spec §5. Each can be sampled from a shading point (`sample_li`) and
//! evaluated for MIS when a ray finds it (`pdf_li`).

use crate::Color;
use glam::{Vec2, Vec3};

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Light {
    /// One-sided rectangle `centre + s·ex + t·ey`, `s,t ∈ [−½,½]`, emitting `radiance` toward `normal`.
    Area {
        centre: Vec3,
        ex: Vec3,
        ey: Vec3,
        normal: Vec3,
        area: f32,
        radiance: Color,
    },
    /// Isotropic point light of radiant intensity `intensity` (W/sr).
    Point { position: Vec3, intensity: Color },
    /// Light travelling along unit `direction`; `irradiance` on a surface facing it.
    Directional { direction: Vec3, irradiance: Color },
    /// Constant radiance from the upper hemisphere (world +Y).
    Ambient { radiance: Color },
}

/// Incident light drawn by `Light::sample_li`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightSample {
    /// Unit world direction from the shading point toward the light.
    pub wi: Vec3,
    /// Distance to the sampled point (infinite for directional and ambient lights).
    pub dist: f32,
    /// Point on the light (finite lights), for the shadow ray.
    pub p_light: Vec3,
    /// Incident radiance (delta lights: the irradiance-like factor the estimator multiplies by).
    pub li: Color,
    /// Solid-angle pdf of `wi` (1 for delta lights).
    pub pdf: f32,
    pub delta: bool,
}

impl Light {
    pub fn is_delta(&self) -> bool {
        matches!(self, Light::Point { .. } | Light::Directional { .. })
    }

    pub fn sample_li(&self, _p: Vec3, _u: Vec2) -> Option<LightSample> {
        todo!("lights: sample_li")
    }

    /// Solid-angle pdf with which `sample_li(p, ·)` returns `wi` (0 for delta lights).
    pub fn pdf_li(&self, _p: Vec3, _wi: Vec3) -> f32 {
        todo!("lights: pdf_li")
    }

    /// Radiance an escaping ray in direction `w` receives from this light (ambient only).
    pub fn le_escaped(&self, w: Vec3) -> Color {
        match self {
            Light::Ambient { radiance } if w.y > 0.0 => *radiance,
            _ => Color::ZERO,
        }
    }
}
