//! Light from infinitely far along one direction: a delta in direction.

use super::LightSample;
use crate::Color;
use glam::Vec3;

pub fn sample_li(direction: Vec3, irradiance: Color) -> Option<LightSample> {
    let wi = (-direction).try_normalize()?;
    Some(LightSample {
        wi,
        dist: f32::INFINITY,
        p_light: Vec3::INFINITY,
        li: irradiance,
        pdf: 1.0,
        delta: true,
    })
}
