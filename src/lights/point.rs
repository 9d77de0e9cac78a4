//! Isotropic point light: a delta in position, irradiance falls off as 1/d².

use super::LightSample;
use crate::Color;
use glam::Vec3;

pub fn sample_li(position: Vec3, intensity: Color, p: Vec3) -> Option<LightSample> {
    let to_light = position - p;
    let dist2 = to_light.length_squared();
    let dist = dist2.sqrt();
    if !(dist > 0.0 && dist.is_finite()) {
        return None;
    }
    let li = intensity / dist2;
    crate::color::is_finite(li).then_some(LightSample {
        wi: to_light / dist,
        dist,
        p_light: position,
        li,
        pdf: 1.0,
        delta: true,
    })
}
