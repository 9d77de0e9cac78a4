//! Hemisphere ("ambient") light: constant radiance from every direction with
//! `ω·Y > 0`, sampled by the cosine about world +Y, which is exact importance
//! sampling for an upward-facing surface.

use super::Incident;
use crate::geometry::Frame;
use crate::lanes::{Lanes, Real, V3};
use crate::sampling::warps::{cosine_hemisphere_l, cosine_hemisphere_pdf_l};
use crate::Color;
use glam::Vec3;

#[inline(always)]
pub fn sample_incident<L: Lanes>(l: L, radiance: Color, u: (L::F, L::F)) -> Incident<L::F> {
    let up = Frame::around(V3::splat(l, Vec3::Y));
    let wi = up.world(cosine_hemisphere_l(u.0, u.1)).normalize();
    let pdf = pdf_incident(wi);
    Incident {
        wi,
        dist: l.f(f32::INFINITY),
        p_light: V3::splat(l, Vec3::INFINITY),
        li: V3::splat(l, radiance),
        pdf,
        valid: pdf.gt(l.f(0.0)),
    }
}

#[inline(always)]
pub fn pdf_incident<F: Real>(wi: V3<F>) -> F {
    cosine_hemisphere_pdf_l(wi.y)
}
