//! Light from infinitely far along one direction: a delta in direction.

use super::Incident;
use crate::lanes::{Lanes, V3};
use crate::Color;
use glam::Vec3;

#[inline(always)]
pub fn sample_incident<L: Lanes>(l: L, direction: Vec3, irradiance: Color) -> Incident<L::F> {
    let wi = (-direction).try_normalize();
    Incident {
        wi: V3::splat(l, wi.unwrap_or(Vec3::Z)),
        dist: l.f(f32::INFINITY),
        p_light: V3::splat(l, Vec3::INFINITY),
        li: V3::splat(l, irradiance),
        pdf: l.f(1.0),
        valid: l.mask(if wi.is_some() { l.all() } else { 0 }),
    }
}
