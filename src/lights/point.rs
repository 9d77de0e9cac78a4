//! Isotropic point light: a delta in position, irradiance falls off as 1/d².

use super::Incident;
use crate::lanes::{Lanes, Real, V3};
use crate::Color;
use glam::Vec3;

#[inline(always)]
pub fn sample_incident<L: Lanes>(
    l: L,
    position: Vec3,
    intensity: Color,
    p: V3<L::F>,
) -> Incident<L::F> {
    let position = V3::splat(l, position);
    let to_light = position - p;
    let dist2 = to_light.length_squared();
    let dist = dist2.sqrt();
    let li = V3::splat(l, intensity) / dist2;
    Incident {
        wi: to_light / dist,
        dist,
        p_light: position,
        li,
        pdf: l.f(1.0),
        valid: dist.gt(l.f(0.0)) & dist.is_finite() & li.is_finite(),
    }
}
