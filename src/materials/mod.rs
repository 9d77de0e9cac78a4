//! Materials (BSDFs) of spec §6. Each is a small self-contained unit whose
//! `eval`, `sample` and `pdf` agree; directions are in the local shading frame
//! (+z = shading normal), `wo` toward the eye, `wi` toward the light.

pub mod fresnel;
pub mod lambertian;
pub mod microfacet;
pub mod specular;

use crate::Color;
use glam::{Vec2, Vec3};
pub use microfacet::Conductor;
use std::fmt;

/// What kind of scattering (and emission) a material has, as pbrt-v4's `BxDFFlags`:
/// the integrators and the scene ask these instead of matching on variants.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct BsdfFlags {
    /// Every lobe is a delta distribution: light sampling is pointless there.
    pub delta: bool,
    /// A non-delta lobe narrow enough that BSDF sampling beats light sampling on it.
    pub glossy: bool,
    /// A broad non-delta lobe.
    pub diffuse: bool,
    /// The surface emits light itself.
    pub emissive: bool,
}

impl BsdfFlags {
    /// Nothing is scattered.
    pub fn is_black(&self) -> bool {
        !(self.delta || self.glossy || self.diffuse)
    }
}

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
    /// Its parameters are built once, by `Conductor::new`, when the material is made.
    Microfacet(Conductor),
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
            Material::Microfacet(c) => c.eval(wo, wi),
            _ => Color::ZERO,
        }
    }

    /// Solid-angle density with which `sample` returns `wi`; zero for delta lobes.
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        match *self {
            Material::Lambertian { .. } => lambertian::pdf(wo, wi),
            Material::Microfacet(c) => c.pdf(wo, wi),
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
            Material::Microfacet(c) => c.sample(wo, u),
            Material::Emission { .. } | Material::Black => None,
        }
    }

    /// What kind of scattering and emission this material has.
    pub fn flags(&self) -> BsdfFlags {
        let none = BsdfFlags::default();
        match self {
            Material::Lambertian { .. } => BsdfFlags {
                diffuse: true,
                ..none
            },
            Material::Mirror { .. } | Material::Glass { .. } | Material::Refraction { .. } => {
                BsdfFlags {
                    delta: true,
                    ..none
                }
            }
            Material::Microfacet(_) => BsdfFlags {
                glossy: true,
                ..none
            },
            Material::Emission { .. } => BsdfFlags {
                emissive: true,
                ..none
            },
            Material::Black => none,
        }
    }

    /// True when every lobe is a delta distribution (mirror, glass, refraction):
    /// light sampling is pointless there.
    pub fn is_delta(&self) -> bool {
        self.flags().delta
    }

    /// True when the material scatters no light at all (emitters, light surfaces).
    pub fn is_black(&self) -> bool {
        self.flags().is_black()
    }

    /// Radiance emitted toward local direction `wo` (front side only).
    pub fn emitted(&self, wo: Vec3) -> Color {
        match self {
            Material::Emission { radiance } if wo.z > 0.0 => *radiance,
            _ => Color::ZERO,
        }
    }
}

impl Material {
    /// The kind and every parameter, for `ember info`: `lambertian: albedo (0.5, 0.5, 0.5)`.
    pub fn describe(&self) -> String {
        use crate::color::compact as v;
        match *self {
            Material::Lambertian { albedo } => format!("{self}: albedo {}", v(albedo)),
            Material::Mirror { reflectance } => format!("{self}: reflectance {}", v(reflectance)),
            Material::Glass {
                ior,
                reflectance,
                transmittance,
            } => format!(
                "{self}: ior {ior}, reflectance {}, transmittance {}",
                v(reflectance),
                v(transmittance)
            ),
            Material::Refraction { ior, transmittance } => {
                format!("{self}: ior {ior}, transmittance {}", v(transmittance))
            }
            Material::Microfacet(c) => format!(
                "{self}: alpha {}, eta {}, k {}",
                c.alpha,
                v(c.eta()),
                v(c.k())
            ),
            Material::Emission { radiance } => format!("{self}: radiance {}", v(radiance)),
            Material::Black => format!("{self} (an area light's surface)"),
        }
    }
}

/// A dielectric index must be positive and finite for Snell's law to mean anything.
fn valid_ior(ior: f32) -> Option<f32> {
    (ior > 0.0 && ior.is_finite()).then_some(ior)
}

/// The material's kind, as the loader and `ember info` name it.
impl fmt::Display for Material {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str(match self {
            Material::Lambertian { .. } => "lambertian",
            Material::Mirror { .. } => "mirror",
            Material::Glass { .. } => "glass",
            Material::Refraction { .. } => "refraction",
            Material::Microfacet(_) => "microfacet",
            Material::Emission { .. } => "emission",
            Material::Black => "black",
        })
    }
}
