//! Materials (BSDFs) of spec §6. Each is a small self-contained unit whose
//! `eval`, `sample` and `pdf` agree; directions are in the local shading frame
//! (+z = shading normal), `wo` toward the eye, `wi` toward the light.

pub mod fresnel;
pub mod lambertian;
pub mod microfacet;
pub mod specular;

use crate::Color;
use glam::{Vec2, Vec3};
use microfacet::Conductor;

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Material {
    Lambertian {
        albedo: Color,
    },
    Mirror {
        reflectance: Color,
    },
    /// Smooth dielectric: index `ior` on the back (−z) side, 1 on the front.
    Glass {
        ior: f32,
        reflectance: Color,
        transmittance: Color,
    },
    /// Glass without its reflection.
    Refraction {
        ior: f32,
        transmittance: Color,
    },
    /// Rough conductor: Beckmann NDF, separable Smith G, exact conductor Fresnel.
    Microfacet {
        alpha: f32,
        eta: Color,
        k: Color,
    },
    /// Emits `radiance` from the front side; reflects nothing.
    Emission {
        radiance: Color,
    },
    /// Absorbs everything and emits nothing itself: the surface of an area light,
    /// whose radiance the light gives (`AreaLight::emitted`).
    Black,
}

impl Default for Material {
    fn default() -> Self {
        Material::Lambertian {
            albedo: Color::splat(0.5),
        }
    }
}

/// A direction drawn by `Material::sample`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BsdfSample {
    /// Local incident direction (unit).
    pub wi: Vec3,
    /// The estimator weight `f·|cos θi| / pdf`; for a delta lobe, the lobe's factor
    /// (e.g. `F·R` for glass reflection) divided by the probability of choosing it.
    pub weight: Color,
    /// Solid-angle pdf of `wi`; for a delta lobe, the probability of choosing that lobe.
    pub pdf: f32,
    /// True when `wi` came from a delta (specular) lobe.
    pub delta: bool,
}

impl Material {
    /// `f(wo, wi)` without the cosine; zero for delta materials.
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> Color {
        match *self {
            Material::Lambertian { albedo } => lambertian::eval(albedo, wo, wi),
            Material::Microfacet { alpha, eta, k } => Conductor::new(alpha, eta, k).eval(wo, wi),
            _ => Color::ZERO,
        }
    }

    /// Solid-angle density with which `sample` returns `wi`; zero for delta lobes.
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        match *self {
            Material::Lambertian { .. } => lambertian::pdf(wo, wi),
            Material::Microfacet { alpha, eta, k } => Conductor::new(alpha, eta, k).pdf(wo, wi),
            _ => 0.0,
        }
    }

    /// Draws `wi` given `wo`. `u_lobe` chooses a lobe, `u` the direction.
    /// `None` when nothing scatters (zero density, total internal reflection
    /// of `Refraction`, emitters, invalid parameters).
    pub fn sample(&self, wo: Vec3, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
        if !wo.is_finite() {
            return None;
        }
        match *self {
            Material::Lambertian { albedo } => lambertian::sample(albedo, wo, u),
            Material::Mirror { reflectance } => specular::sample_mirror(reflectance, wo),
            Material::Glass {
                ior,
                reflectance,
                transmittance,
            } => valid_ior(ior).and_then(|ior| {
                specular::sample_glass(ior, reflectance, transmittance, wo, u_lobe)
            }),
            Material::Refraction { ior, transmittance } => {
                valid_ior(ior).and_then(|ior| specular::sample_refraction(ior, transmittance, wo))
            }
            Material::Microfacet { alpha, eta, k } => Conductor::new(alpha, eta, k).sample(wo, u),
            Material::Emission { .. } | Material::Black => None,
        }
    }

    /// True when every lobe is a delta distribution (mirror, glass, refraction):
    /// light sampling is pointless there.
    pub fn is_delta(&self) -> bool {
        matches!(
            self,
            Material::Mirror { .. } | Material::Glass { .. } | Material::Refraction { .. }
        )
    }

    /// True when the material scatters no light at all (emitters).
    pub fn is_black(&self) -> bool {
        matches!(self, Material::Emission { .. } | Material::Black)
    }

    /// Radiance emitted toward local direction `wo` (front side only).
    pub fn emitted(&self, wo: Vec3) -> Color {
        match self {
            Material::Emission { radiance } if wo.z > 0.0 => *radiance,
            _ => Color::ZERO,
        }
    }
}

/// A dielectric index must be positive and finite for Snell's law to mean anything.
fn valid_ior(ior: f32) -> Option<f32> {
    (ior > 0.0 && ior.is_finite()).then_some(ior)
}
