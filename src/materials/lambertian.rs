//! Two-sided Lambertian reflection, sampled by the cosine on the side of `wo`.

use super::{gather_v3, BsdfFlags, BsdfSample, Scatter};
use crate::lanes::{Lanes, Real, V3};
use crate::sampling::warps::{cosine_hemisphere_l, cosine_hemisphere_pdf_l};
use std::f32::consts::FRAC_1_PI;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lambertian<F = f32> {
    pub albedo: V3<F>,
}

impl<F: Real> Scatter<F> for Lambertian<F> {
    type One = Lambertian;
    const FLAGS: BsdfFlags = BsdfFlags::DIFFUSE;

    #[inline(always)]
    fn gather<L: Lanes<F = F>>(l: L, each: &F::Array<Lambertian>) -> Self {
        Lambertian {
            albedo: gather_v3(l, each, |m| m.albedo),
        }
    }

    fn describe(m: &Lambertian) -> String {
        format!(
            "lambertian: albedo {}",
            crate::color::compact(m.albedo.vec3())
        )
    }

    #[inline(always)]
    fn eval(&self, wo: V3<F>, wi: V3<F>) -> V3<F> {
        let zero = wo.z.splat_as(0.0);
        let f = self.albedo * wo.z.splat_as(FRAC_1_PI);
        V3::select(same_side(wo, wi), f, V3::new(zero, zero, zero))
    }

    #[inline(always)]
    fn pdf(&self, wo: V3<F>, wi: V3<F>) -> F {
        let zero = wo.z.splat_as(0.0);
        F::select(same_side(wo, wi), cosine_hemisphere_pdf_l(wi.z.abs()), zero)
    }

    #[inline(always)]
    fn sample(&self, wo: V3<F>, _u_lobe: F, u: (F, F)) -> BsdfSample<F> {
        let zero = wo.z.splat_as(0.0);
        let d = cosine_hemisphere_l(u.0, u.1);
        // On the disk's rim the direction has zero density: no sample.
        let valid = !wo.z.eq(zero) & d.z.gt(zero);
        let wi = V3::new(d.x, d.y, d.z.copysign(wo.z));
        BsdfSample {
            wi,
            // f·|cos|/pdf = (ρ/π)·|cos| / (|cos|/π).
            weight: self.albedo,
            pdf: cosine_hemisphere_pdf_l(wi.z.abs()),
            valid,
        }
    }
}

/// Strictly on the same side: directions in the tangent plane scatter nothing.
#[inline(always)]
pub(super) fn same_side<F: Real>(wo: V3<F>, wi: V3<F>) -> F::M {
    (wo.z * wi.z).gt(wo.z.splat_as(0.0))
}
