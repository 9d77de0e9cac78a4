//! Hemisphere ("ambient") light: constant radiance from every direction with
//! `ω·Y > 0`, sampled by the cosine about world +Y, which is exact importance
//! sampling for an upward-facing surface.

use super::LightSample;
use crate::geometry::Frame;
use crate::sampling::{cosine_hemisphere, cosine_hemisphere_pdf};
use crate::Color;
use glam::{Vec2, Vec3};

fn up_frame() -> Frame {
    Frame::from_normal(Vec3::Y)
}

pub fn sample_li(radiance: Color, u: Vec2) -> Option<LightSample> {
    let wi = up_frame().to_world(cosine_hemisphere(u)).normalize();
    let pdf = pdf_li(wi);
    (pdf > 0.0).then_some(LightSample {
        wi,
        dist: f32::INFINITY,
        p_light: Vec3::INFINITY,
        li: radiance,
        pdf,
        delta: false,
    })
}

pub fn pdf_li(wi: Vec3) -> f32 {
    cosine_hemisphere_pdf(wi.y)
}
