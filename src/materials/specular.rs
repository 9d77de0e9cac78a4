//! Smooth (delta) interfaces: mirror, glass and refraction. The index η lies on
//! the back (−z) side and 1 on the front, as spec §6 says.

use super::{fresnel, BsdfSample};
use crate::color::luminance;
use crate::Color;
use glam::Vec3;

/// Mirror direction of `wo` about the local normal +z.
#[inline]
pub fn reflect(wo: Vec3) -> Vec3 {
    Vec3::new(-wo.x, -wo.y, wo.z)
}

/// Indices `(ηi, ηt)` on the side of `wo` and on the other side.
#[inline]
pub fn indices(wo: Vec3, ior: f32) -> (f32, f32) {
    if wo.z >= 0.0 {
        (1.0, ior)
    } else {
        (ior, 1.0)
    }
}

/// Refracted direction of `wo` through the interface (Snell's law), or `None`
/// under total internal reflection.
pub fn refract(wo: Vec3, eta_i: f32, eta_t: f32) -> Option<Vec3> {
    let eta_ratio = eta_i / eta_t;
    let cos_i = wo.z.abs();
    let cos_t = fresnel::refracted_cos(cos_i, eta_ratio)?;
    // Tangential part scales by ηi/ηt and flips, the normal part moves to the other side.
    let wi = Vec3::new(-eta_ratio * wo.x, -eta_ratio * wo.y, -cos_t.copysign(wo.z));
    Some(wi.normalize())
}

pub fn sample_mirror(reflectance: Color, wo: Vec3) -> Option<BsdfSample> {
    Some(BsdfSample {
        wi: reflect(wo),
        weight: reflectance,
        pdf: 1.0,
        delta: true,
    })
}

/// Picks reflection with probability `F·lum(R) / (F·lum(R) + (1−F)·lum(T))`,
/// i.e. proportional to each lobe's contribution (this is F when R and T are
/// alike), so a lobe that carries nothing is never chosen. The weight is the
/// lobe's factor divided by that probability.
pub fn sample_glass(
    ior: f32,
    reflectance: Color,
    transmittance: Color,
    wo: Vec3,
    u_lobe: f32,
) -> Option<BsdfSample> {
    let (eta_i, eta_t) = indices(wo, ior);
    let f = fresnel::dielectric(wo.z.abs(), eta_i, eta_t);
    let refracted = if f < 1.0 {
        refract(wo, eta_i, eta_t)
    } else {
        None
    };
    let Some(wt) = refracted else {
        // Total internal reflection: F = 1, reflection is the only lobe.
        return sample_mirror(reflectance, wo);
    };
    let p_reflect_unnorm = f * luminance(reflectance).max(0.0);
    let p_refract_unnorm = (1.0 - f) * luminance(transmittance).max(0.0);
    let total = p_reflect_unnorm + p_refract_unnorm;
    if total.is_nan() || total <= 0.0 {
        return None;
    }
    let p_reflect = p_reflect_unnorm / total;
    if u_lobe < p_reflect {
        Some(BsdfSample {
            wi: reflect(wo),
            weight: reflectance * (f / p_reflect),
            pdf: p_reflect,
            delta: true,
        })
    } else {
        let p_refract = 1.0 - p_reflect;
        let scale = (eta_i / eta_t) * (eta_i / eta_t);
        Some(BsdfSample {
            wi: wt,
            weight: transmittance * ((1.0 - f) * scale / p_refract),
            pdf: p_refract,
            delta: true,
        })
    }
}

/// Transmission only, without a Fresnel factor (spec: `T·(ηi/ηt)²`); total
/// internal reflection ends the path.
pub fn sample_refraction(ior: f32, transmittance: Color, wo: Vec3) -> Option<BsdfSample> {
    let (eta_i, eta_t) = indices(wo, ior);
    let wi = refract(wo, eta_i, eta_t)?;
    let scale = (eta_i / eta_t) * (eta_i / eta_t);
    Some(BsdfSample {
        wi,
        weight: transmittance * scale,
        pdf: 1.0,
        delta: true,
    })
}
