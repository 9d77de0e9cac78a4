//! Watertight ray-triangle intersection.

use super::Ray;
use glam::Vec3;

/// Intersects `ray` with triangle `(p0, p1, p2)`; returns `(t, b1, b2)` with
/// `t ∈ [t_min, t_max]` and barycentrics of corners 1 and 2.
pub fn intersect_triangle(_ray: &Ray, _p0: Vec3, _p1: Vec3, _p2: Vec3) -> Option<(f32, f32, f32)> {
    todo!("geometry: watertight triangle test")
}
