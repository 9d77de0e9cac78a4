//! Smooth (delta) interfaces: mirror, glass and refraction. The index η lies on
//! the back (−z) side and 1 on the front, as spec §6 says.

use super::{fresnel, gather_f, gather_v3, BsdfFlags, BsdfSample, Scatter};
use crate::color::{compact, luminance_l};
use crate::lanes::{Lanes, Real, V3};

/// Mirror direction of `wo` about the local normal +z.
#[inline(always)]
pub fn reflect<F: Real>(wo: V3<F>) -> V3<F> {
    V3::new(-wo.x, -wo.y, wo.z)
}

/// Indices `(ηi, ηt)` on the side of `wo` and on the other side.
#[inline(always)]
pub fn indices<F: Real>(wo: V3<F>, ior: F) -> (F, F) {
    let front = wo.z.ge(wo.z.splat_as(0.0));
    let one = ior.splat_as(1.0);
    (F::select(front, one, ior), F::select(front, ior, one))
}

/// Refracted direction of `wo` through the interface (Snell's law), and the lanes
/// where it exists (not under total internal reflection).
#[inline(always)]
pub fn refract<F: Real>(wo: V3<F>, eta_i: F, eta_t: F) -> (V3<F>, F::M) {
    let eta_ratio = eta_i / eta_t;
    let cos_i = wo.z.abs();
    let (cos_t, ok) = fresnel::refracted_cos(cos_i, eta_ratio);
    // Tangential part scales by ηi/ηt and flips, the normal part moves to the other side.
    let wi = V3::new(-eta_ratio * wo.x, -eta_ratio * wo.y, -cos_t.copysign(wo.z));
    (wi.normalize(), ok)
}

/// A dielectric index must be positive and finite for Snell's law to mean anything.
#[inline(always)]
fn valid_ior<F: Real>(ior: F) -> F::M {
    ior.gt(ior.splat_as(0.0)) & ior.is_finite()
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Mirror<F = f32> {
    pub reflectance: V3<F>,
}

impl<F: Real> Scatter<F> for Mirror<F> {
    type One = Mirror;
    const FLAGS: BsdfFlags = BsdfFlags::DELTA;

    #[inline(always)]
    fn gather<L: Lanes<F = F>>(l: L, each: &F::Array<Mirror>) -> Self {
        Mirror {
            reflectance: gather_v3(l, each, |m| m.reflectance),
        }
    }

    fn describe(m: &Mirror) -> String {
        format!("mirror: reflectance {}", compact(m.reflectance.vec3()))
    }

    #[inline(always)]
    fn sample(&self, wo: V3<F>, _u_lobe: F, _u: (F, F)) -> BsdfSample<F> {
        BsdfSample {
            wi: reflect(wo),
            weight: self.reflectance,
            pdf: wo.z.splat_as(1.0),
            valid: wo.is_finite(),
        }
    }
}

/// Smooth dielectric: reflection and refraction, weighted by the exact Fresnel term.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Glass<F = f32> {
    pub ior: F,
    pub reflectance: V3<F>,
    pub transmittance: V3<F>,
}

impl<F: Real> Scatter<F> for Glass<F> {
    type One = Glass;
    /// `u_lobe` chooses reflection or transmission.
    const FLAGS: BsdfFlags = BsdfFlags {
        chooses_lobe: true,
        ..BsdfFlags::DELTA
    };

    #[inline(always)]
    fn gather<L: Lanes<F = F>>(l: L, each: &F::Array<Glass>) -> Self {
        Glass {
            ior: gather_f(l, each, |m| m.ior),
            reflectance: gather_v3(l, each, |m| m.reflectance),
            transmittance: gather_v3(l, each, |m| m.transmittance),
        }
    }

    fn describe(m: &Glass) -> String {
        format!(
            "glass: ior {}, reflectance {}, transmittance {}",
            m.ior,
            compact(m.reflectance.vec3()),
            compact(m.transmittance.vec3())
        )
    }

    /// Picks reflection with probability `F·lum(R) / (F·lum(R) + (1−F)·lum(T))`,
    /// i.e. proportional to each lobe's contribution (this is F when R and T are
    /// alike), so a lobe that carries nothing is never chosen. The weight is the
    /// lobe's factor divided by that probability. Under total internal reflection
    /// reflection is the only lobe.
    #[inline(always)]
    fn sample(&self, wo: V3<F>, u_lobe: F, _u: (F, F)) -> BsdfSample<F> {
        let (eta_i, eta_t) = indices(wo, self.ior);
        let f = fresnel::dielectric(wo.z.abs(), eta_i, eta_t);
        let (wt, refracts) = refract(wo, eta_i, eta_t);
        let tir = !(f.lt(wo.z.splat_as(1.0)) & refracts);
        let p_reflect_unnorm = f * luminance_l(self.reflectance).max(wo.z.splat_as(0.0));
        let p_refract_unnorm =
            (wo.z.splat_as(1.0) - f) * luminance_l(self.transmittance).max(wo.z.splat_as(0.0));
        let total = p_reflect_unnorm + p_refract_unnorm;
        let p_reflect = p_reflect_unnorm / total;
        let reflects = tir | u_lobe.lt(p_reflect);
        let p_refract = wo.z.splat_as(1.0) - p_reflect;
        let scale = (eta_i / eta_t) * (eta_i / eta_t);
        let w_reflect = self.reflectance * (f / p_reflect);
        let w_refract = self.transmittance * ((wo.z.splat_as(1.0) - f) * scale / p_refract);
        BsdfSample {
            wi: V3::select(reflects, reflect(wo), wt),
            weight: V3::select(
                tir,
                self.reflectance,
                V3::select(reflects, w_reflect, w_refract),
            ),
            pdf: F::select(
                tir,
                wo.z.splat_as(1.0),
                F::select(reflects, p_reflect, p_refract),
            ),
            valid: valid_ior(self.ior) & wo.is_finite() & (tir | total.gt(wo.z.splat_as(0.0))),
        }
    }

    /// Refraction compresses radiance by `(ηi/ηt)²`; importance is not compressed.
    #[inline(always)]
    fn radiance_scale(&self, wo: V3<F>, wi: V3<F>) -> F {
        transmission_scale(self.ior, wo, wi)
    }
}

/// Glass without its reflection: transmission only, without a Fresnel factor (spec:
/// `T·(ηi/ηt)²`); total internal reflection ends the path.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Refraction<F = f32> {
    pub ior: F,
    pub transmittance: V3<F>,
}

impl<F: Real> Scatter<F> for Refraction<F> {
    type One = Refraction;
    const FLAGS: BsdfFlags = BsdfFlags::DELTA;

    #[inline(always)]
    fn gather<L: Lanes<F = F>>(l: L, each: &F::Array<Refraction>) -> Self {
        Refraction {
            ior: gather_f(l, each, |m| m.ior),
            transmittance: gather_v3(l, each, |m| m.transmittance),
        }
    }

    fn describe(m: &Refraction) -> String {
        let t = compact(m.transmittance.vec3());
        format!("refraction: ior {}, transmittance {t}", m.ior)
    }

    #[inline(always)]
    fn sample(&self, wo: V3<F>, _u_lobe: F, _u: (F, F)) -> BsdfSample<F> {
        let (eta_i, eta_t) = indices(wo, self.ior);
        let (wi, refracts) = refract(wo, eta_i, eta_t);
        let scale = (eta_i / eta_t) * (eta_i / eta_t);
        BsdfSample {
            wi,
            weight: self.transmittance * scale,
            pdf: wo.z.splat_as(1.0),
            valid: valid_ior(self.ior) & wo.is_finite() & refracts,
        }
    }

    #[inline(always)]
    fn radiance_scale(&self, wo: V3<F>, wi: V3<F>) -> F {
        transmission_scale(self.ior, wo, wi)
    }
}

/// `(ηi/ηt)²` for a transmission from `wo`'s side to `wi`'s, 1 for a reflection.
#[inline(always)]
fn transmission_scale<F: Real>(ior: F, wo: V3<F>, wi: V3<F>) -> F {
    let (eta_i, eta_t) = indices(wo, ior);
    let transmitted = (wo.z * wi.z).lt(wo.z.splat_as(0.0));
    F::select(
        transmitted,
        (eta_i / eta_t) * (eta_i / eta_t),
        wo.z.splat_as(1.0),
    )
}
