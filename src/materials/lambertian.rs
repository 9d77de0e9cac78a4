//! Two-sided Lambertian reflection, sampled by the cosine on the side of `wo`.

use super::BsdfSample;
use crate::sampling::{cosine_hemisphere, cosine_hemisphere_pdf};
use crate::Color;
use glam::{Vec2, Vec3};
use std::f32::consts::FRAC_1_PI;

pub fn eval(albedo: Color, wo: Vec3, wi: Vec3) -> Color {
    if same_side(wo, wi) {
        albedo * FRAC_1_PI
    } else {
        Color::ZERO
    }
}

pub fn pdf(wo: Vec3, wi: Vec3) -> f32 {
    if same_side(wo, wi) {
        cosine_hemisphere_pdf(wi.z.abs())
    } else {
        0.0
    }
}

pub fn sample(albedo: Color, wo: Vec3, u: Vec2) -> Option<BsdfSample> {
    if wo.z == 0.0 {
        return None;
    }
    let mut wi = cosine_hemisphere(u);
    if wi.z <= 0.0 {
        // On the disk's rim: a zero-density direction.
        return None;
    }
    wi.z = wi.z.copysign(wo.z);
    Some(BsdfSample {
        wi,
        // f·|cos|/pdf = (ρ/π)·|cos| / (|cos|/π).
        weight: albedo,
        pdf: cosine_hemisphere_pdf(wi.z.abs()),
        delta: false,
    })
}

/// Strictly on the same side: directions in the tangent plane scatter nothing.
pub(super) fn same_side(wo: Vec3, wi: Vec3) -> bool {
    wo.z * wi.z > 0.0
}
