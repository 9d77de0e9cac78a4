//! Closed forms the light and transport tests compare against.

use glam::Vec3;

/// Lambert's closed form for the irradiance at `p` (normal `n`) from a uniformly
/// emitting polygon of radiance `radiance` fully above the receiver's horizon:
/// `E = L/2 · Σ Θi · (n · normalize(vi × vi+1))`.
pub fn polygon_irradiance(p: Vec3, n: Vec3, vertices: &[Vec3], radiance: f64) -> f64 {
    let v: Vec<_> = vertices
        .iter()
        .map(|q| (*q - p).as_dvec3().normalize())
        .collect();
    let n = n.as_dvec3();
    let sum: f64 = (0..v.len())
        .map(|i| {
            let (a, b) = (v[i], v[(i + 1) % v.len()]);
            a.angle_between(b) * n.dot(a.cross(b).normalize())
        })
        .sum();
    0.5 * radiance * sum.abs()
}
