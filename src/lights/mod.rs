//! Lights of spec §5. Each can be sampled from shading points (`sample_incident`)
//! and evaluated for MIS when a ray finds it (`pdf_incident`), written once over the
//! lane type; `sample_li` and `pdf_li` are the one-path forms.

pub mod ambient;
pub mod area;
pub mod directional;
pub mod emit;
pub mod environment;
pub mod point;
pub mod spot;

use crate::color::luminance;
use crate::lanes::{per_lane, per_lane_v3, LaneMask, Lanes, One, Real, LANES, V3};
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

/// Incident light drawn by `Light::sample_li` (one path).
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

/// Incident light drawn by `Light::sample_incident`, per lane: a [`LightSample`] in
/// each lane of `valid`.
#[derive(Clone, Copy, Debug)]
pub struct Incident<F: Real> {
    pub wi: V3<F>,
    pub dist: F,
    pub p_light: V3<F>,
    pub li: V3<F>,
    pub pdf: F,
    pub valid: F::M,
}

impl<F: Real> Incident<F> {
    /// Lanes of `s`, each from its own one-path sample (`None`: not valid).
    #[inline(always)]
    fn per_lane(like: F, mut s: impl FnMut(usize) -> Option<LightSample>) -> Self {
        let mut a: [Option<LightSample>; LANES] = [None; LANES];
        for (i, v) in a.iter_mut().enumerate().take(F::WIDTH) {
            *v = s(i);
        }
        let get = |f: fn(&LightSample) -> Vec3| {
            per_lane_v3(like, |i| a[i].as_ref().map_or(Vec3::ZERO, f))
        };
        let valid_bits = (0..F::WIDTH)
            .filter(|&i| a[i].is_some())
            .fold(0, |m, i| m | 1 << i);
        let valid = like.eq(like).from_bits_as(valid_bits);
        Incident {
            wi: get(|s| s.wi),
            dist: per_lane(like, |i| a[i].map_or(0.0, |s| s.dist)),
            p_light: get(|s| s.p_light),
            li: get(|s| s.li),
            pdf: per_lane(like, |i| a[i].map_or(0.0, |s| s.pdf)),
            valid,
        }
    }
}

impl Light {
    /// The kind's name, for messages: `area`, `point`, …
    pub fn kind(&self) -> &'static str {
        match self {
            Light::Area(_) => "area",
            Light::Point { .. } => "point",
            Light::Spot(_) => "spot",
            Light::Directional { .. } => "directional",
            Light::Ambient { .. } => "ambient",
            Light::Environment(_) => "environment map",
        }
    }

    pub fn is_delta(&self) -> bool {
        match self {
            Light::Point { .. } | Light::Spot(_) | Light::Directional { .. } => true,
            Light::Area(_) | Light::Ambient { .. } | Light::Environment(_) => false,
        }
    }

    /// True for a light that surrounds the scene (ambient, environment map), which
    /// light sampling alone covers poorly (near the horizon, or between a map's
    /// bright spots), so MIS is the better default.
    pub fn is_environment(&self) -> bool {
        match self {
            Light::Ambient { .. } | Light::Environment(_) => true,
            Light::Area(_) | Light::Point { .. } | Light::Spot(_) | Light::Directional { .. } => {
                false
            }
        }
    }

    /// Draws a direction toward the light from points `p`, per lane; lanes that
    /// receive nothing from their sample (behind an area light, degenerate light) are
    /// not `valid`.
    #[inline(always)]
    pub fn sample_incident<L: Lanes>(&self, l: L, p: V3<L::F>, u: (L::F, L::F)) -> Incident<L::F> {
        match self {
            Light::Area(a) => a.sample_incident(l, p, u),
            Light::Point {
                position,
                intensity,
            } => point::sample_incident(l, *position, *intensity, p),
            Light::Spot(s) => s.sample_incident(l, p),
            Light::Directional {
                direction,
                irradiance,
            } => directional::sample_incident(l, *direction, *irradiance),
            Light::Ambient { radiance } => ambient::sample_incident(l, *radiance, u),
            Light::Environment(env) => {
                let (u0, u1) = (u.0.to_array(), u.1.to_array());
                Incident::per_lane(u.0, |i| env.sample_li(Vec2::new(u0[i], u1[i])))
            }
        }
    }

    /// Solid-angle pdf with which `sample_incident(p, ·)` returns `wi`, per lane (0
    /// for delta lights).
    #[inline(always)]
    pub fn pdf_incident<L: Lanes>(&self, l: L, p: V3<L::F>, wi: V3<L::F>) -> L::F {
        match self {
            Light::Area(a) => a.pdf_incident(l, p, wi),
            Light::Ambient { .. } => ambient::pdf_incident(wi),
            Light::Environment(env) => {
                let wi_l = wi.to_arrays();
                per_lane(wi.x, |i| {
                    env.pdf_li(Vec3::new(wi_l[0][i], wi_l[1][i], wi_l[2][i]))
                })
            }
            Light::Point { .. } | Light::Spot(_) | Light::Directional { .. } => l.f(0.0),
        }
    }

    /// Radiance an escaping ray in unit direction `w` receives from this light
    /// (ambient and environment lights only), per lane.
    #[inline(always)]
    pub fn le_escaped_l<L: Lanes>(&self, l: L, w: V3<L::F>) -> V3<L::F> {
        let zero = V3::splat(l, Vec3::ZERO);
        match self {
            Light::Ambient { radiance } => {
                V3::select(w.y.gt(l.f(0.0)), V3::splat(l, *radiance), zero)
            }
            Light::Environment(env) => {
                let w_l = w.to_arrays();
                per_lane_v3(w.x, |i| env.le(Vec3::new(w_l[0][i], w_l[1][i], w_l[2][i])))
            }
            Light::Area(_) | Light::Point { .. } | Light::Spot(_) | Light::Directional { .. } => {
                zero
            }
        }
    }

    /// `sample_incident` for one path.
    pub fn sample_li(&self, p: Vec3, u: Vec2) -> Option<LightSample> {
        let s = self.sample_incident(One, p.into(), (u.x, u.y));
        s.valid.then(|| LightSample {
            wi: s.wi.vec3(),
            dist: s.dist,
            p_light: s.p_light.vec3(),
            li: s.li.vec3(),
            pdf: s.pdf,
            delta: self.is_delta(),
        })
    }

    /// `pdf_incident` for one path.
    pub fn pdf_li(&self, p: Vec3, wi: Vec3) -> f32 {
        self.pdf_incident(One, p.into(), wi.into())
    }

    /// `le_escaped_l` for one path.
    pub fn le_escaped(&self, w: Vec3) -> Color {
        self.le_escaped_l(One, w.into()).vec3()
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

    /// The area light this is, if it is one.
    pub fn as_area(&self) -> Option<&AreaLight> {
        match self {
            Light::Area(a) => Some(a),
            _ => None,
        }
    }
}
