//! Ray-sphere intersection, robust for rays starting inside.

use super::Ray;
use glam::Vec3;

/// Nearest `t ∈ [t_min, t_max]` where `ray` meets the sphere's surface.
pub fn intersect_sphere(_ray: &Ray, _centre: Vec3, _radius: f32) -> Option<f32> {
    todo!("geometry: sphere test")
}
