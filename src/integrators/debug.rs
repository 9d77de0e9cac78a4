//! The course's Part 1-2 views: shading normals and BVH traversal cost.

use crate::accel::{Accel, TraversalStats};
use crate::geometry::Ray;
use crate::scene::Scene;
use crate::Color;

/// `0.5·n + 0.5` of the shading normal at the first hit; black on a miss.
pub fn normal_color(scene: &Scene, accel: &dyn Accel, ray: &Ray) -> Color {
    match accel.intersect(ray) {
        Some(h) => 0.5 * scene.interaction(ray, &h).ns + Color::splat(0.5),
        None => Color::ZERO,
    }
}

/// Nodes visited plus primitives tested by the camera ray.
pub fn traversal_cost(accel: &dyn Accel, ray: &Ray) -> f32 {
    let mut stats = TraversalStats::default();
    accel.intersect_counted(ray, &mut stats);
    (stats.nodes + stats.prims) as f32
}
