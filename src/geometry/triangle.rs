//! Watertight ray-triangle intersection (Woop, Benthin and Wald 2013, as in
//! pbrt-v4 `IntersectTriangle`).
//!
//! The ray is sheared so that it points along +z from the origin; the test then
//! works in 2-D on the sheared corners. Every corner is transformed by exactly the
//! same operations whichever triangle it belongs to, so the edge functions of a
//! shared edge are exact negatives of each other and no ray slips between two
//! triangles. Edge functions that round to zero are recomputed in `f64`, where the
//! products are exact, so rays through edges and vertices are decided exactly.
//!
//! The work that depends only on the ray (axis permutation, shear) lives in
//! [`TriangleRay`], built once per ray; corners live transposed in
//! [`PackedTriangle`] so that one SIMD lane handles one corner.

use super::ray::gamma;
use super::Ray;
use glam::{Vec3, Vec4, Vec4Swizzles};

/// A triangle hit: parametric distance and barycentrics of corners 1 and 2.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriangleHit {
    pub t: f32,
    pub b1: f32,
    pub b2: f32,
}

/// The per-ray part of the watertight test: permutation `kx, ky, kz` (with `kz`
/// the dominant axis of `d`) and the shear taking `d` to `+z`.
#[derive(Clone, Copy, Debug)]
pub struct TriangleRay {
    kx: usize,
    ky: usize,
    kz: usize,
    /// Origin components on the permuted axes, splatted over the corner lanes.
    ox: Vec4,
    oy: Vec4,
    oz: Vec4,
    sx: Vec4,
    sy: Vec4,
    sz: Vec4,
    pub t_min: f32,
}

impl TriangleRay {
    pub fn new(ray: &Ray) -> Self {
        let ad = ray.d.abs();
        // pbrt's MaxComponentIndex, so ties pick the same axis as the reference.
        let kz = if ad.x > ad.y {
            if ad.x > ad.z {
                0
            } else {
                2
            }
        } else if ad.y > ad.z {
            1
        } else {
            2
        };
        let kx = if kz == 2 { 0 } else { kz + 1 };
        let ky = if kx == 2 { 0 } else { kx + 1 };
        let (d, o) = (ray.d, ray.o);
        TriangleRay {
            kx,
            ky,
            kz,
            ox: Vec4::splat(o[kx]),
            oy: Vec4::splat(o[ky]),
            oz: Vec4::splat(o[kz]),
            sx: Vec4::splat(-d[kx] / d[kz]),
            sy: Vec4::splat(-d[ky] / d[kz]),
            sz: Vec4::splat(1.0 / d[kz]),
            t_min: ray.t_min,
        }
    }
}

/// A triangle stored transposed: `rows[a]` holds axis `a` of corners 0, 1, 2 in
/// lanes 0, 1, 2 (lane 3 is zero). 48 bytes, one aligned load per axis.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(16))]
pub struct PackedTriangle {
    rows: [Vec4; 3],
}

impl PackedTriangle {
    pub fn new(p0: Vec3, p1: Vec3, p2: Vec3) -> Self {
        PackedTriangle {
            rows: [
                Vec4::new(p0.x, p1.x, p2.x, 0.0),
                Vec4::new(p0.y, p1.y, p2.y, 0.0),
                Vec4::new(p0.z, p1.z, p2.z, 0.0),
            ],
        }
    }

    /// Corners in their original order.
    pub fn corners(&self) -> [Vec3; 3] {
        let [x, y, z] = self.rows;
        [
            Vec3::new(x.x, y.x, z.x),
            Vec3::new(x.y, y.y, z.y),
            Vec3::new(x.z, y.z, z.z),
        ]
    }

    /// The watertight test for `t ∈ [ray.t_min, t_max]`; hits closer than the
    /// triangle's own rounding error (`t ≤ δt`, pbrt's conservative bound) are
    /// rejected, so a ray spawned from this triangle by `offset_ray_origin` never
    /// finds it again. Degenerate triangles must be filtered out beforehand
    /// (see [`triangle_is_hittable`]).
    #[inline(always)]
    pub fn intersect(&self, ray: &TriangleRay, t_max: f32) -> Option<TriangleHit> {
        let xk = self.rows[ray.kx] - ray.ox;
        let yk = self.rows[ray.ky] - ray.oy;
        let zk = self.rows[ray.kz] - ray.oz;
        let xt = xk + ray.sx * zk;
        let yt = yk + ray.sy * zk;
        // Lane i: e_i = x_{i+1}·y_{i+2} − y_{i+1}·x_{i+2}.
        let mut e = xt.yzxw() * yt.zxyw() - yt.yzxw() * xt.zxyw();
        let neg = e.cmplt(Vec4::ZERO).bitmask() & 7;
        let pos = e.cmpgt(Vec4::ZERO).bitmask() & 7;
        // Rounding is monotonic, so a non-zero f32 edge function already has the
        // exact sign: mixed non-zero signs are a certain miss.
        if neg != 0 && pos != 0 {
            return None;
        }
        if neg | pos != 7 {
            e = exact_edge_functions(xt, yt);
            let neg = e.cmplt(Vec4::ZERO).bitmask() & 7;
            let pos = e.cmpgt(Vec4::ZERO).bitmask() & 7;
            if neg != 0 && pos != 0 {
                return None;
            }
        }
        let det = e.x + e.y + e.z;
        if det == 0.0 {
            return None;
        }
        let zt = ray.sz * zk;
        let t_scaled = e.x * zt.x + e.y * zt.y + e.z * zt.z;
        let inv_det = 1.0 / det;
        let t = t_scaled * inv_det;
        // Written so that NaN (a zero direction) fails.
        if !(t >= ray.t_min && t <= t_max) {
            return None;
        }
        if t <= conservative_t_bound(xt, yt, zt, e, inv_det) {
            return None;
        }
        Some(TriangleHit {
            t,
            b1: e.y * inv_det,
            b2: e.z * inv_det,
        })
    }
}

/// Edge functions in `f64`, where products of two floats are exact: used when an
/// f32 edge function rounded to zero, i.e. the ray passes (nearly) through an edge.
#[cold]
#[inline(never)]
fn exact_edge_functions(xt: Vec4, yt: Vec4) -> Vec4 {
    let x = xt.to_array().map(f64::from);
    let y = yt.to_array().map(f64::from);
    let e = |i: usize, j: usize| (x[i] * y[j] - y[i] * x[j]) as f32;
    Vec4::new(e(1, 2), e(2, 0), e(0, 1), 0.0)
}

/// pbrt-v4's bound `δt` on the rounding error of `t`: a hit at `t ≤ δt` may lie
/// behind the origin.
#[inline(always)]
fn conservative_t_bound(xt: Vec4, yt: Vec4, zt: Vec4, e: Vec4, inv_det: f32) -> f32 {
    let max3 = |v: Vec4| {
        let a = v.abs();
        a.x.max(a.y).max(a.z)
    };
    let max_zt = max3(zt);
    let max_xt = max3(xt);
    let max_yt = max3(yt);
    let max_e = max3(e);
    let delta_z = gamma(3) * max_zt;
    let delta_x = gamma(5) * (max_xt + max_zt);
    let delta_y = gamma(5) * (max_yt + max_zt);
    let delta_e = 2.0 * (gamma(2) * max_xt * max_yt + delta_y * max_xt + delta_x * max_yt);
    3.0 * (gamma(3) * max_e * max_zt + delta_e * max_zt + delta_z * max_e) * inv_det.abs()
}

/// Whether a triangle can ever be hit: finite corners and a non-zero area, the
/// same criterion as pbrt (zero-area triangles would give meaningless edge tests).
pub fn triangle_is_hittable(p0: Vec3, p1: Vec3, p2: Vec3) -> bool {
    let finite = p0.is_finite() && p1.is_finite() && p2.is_finite();
    finite && (p2 - p0).cross(p1 - p0).length_squared() != 0.0
}

/// Intersects `ray` with triangle `(p0, p1, p2)`; returns `(t, b1, b2)` with
/// `t ∈ [t_min, t_max]` and barycentrics of corners 1 and 2.
pub fn intersect_triangle(ray: &Ray, p0: Vec3, p1: Vec3, p2: Vec3) -> Option<(f32, f32, f32)> {
    if !triangle_is_hittable(p0, p1, p2) {
        return None;
    }
    let tri = PackedTriangle::new(p0, p1, p2);
    tri.intersect(&TriangleRay::new(ray), ray.t_max)
        .map(|h| (h.t, h.b1, h.b2))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tri() -> [Vec3; 3] {
        [
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        ]
    }

    #[test]
    fn hits_interior_with_barycentrics() {
        let [a, b, c] = tri();
        let ray = Ray::new(Vec3::new(0.25, 0.5, 2.0), Vec3::new(0.0, 0.0, -1.0));
        let (t, b1, b2) = intersect_triangle(&ray, a, b, c).expect("hit");
        assert_eq!(t, 2.0);
        assert!((b1 - 0.25).abs() < 1e-6 && (b2 - 0.5).abs() < 1e-6);
    }

    #[test]
    fn respects_interval_and_backside() {
        let [a, b, c] = tri();
        let mut ray = Ray::new(Vec3::new(0.25, 0.25, 2.0), Vec3::new(0.0, 0.0, -1.0));
        ray.t_max = 1.5;
        assert!(intersect_triangle(&ray, a, b, c).is_none());
        ray.t_max = f32::INFINITY;
        ray.t_min = 2.5;
        assert!(intersect_triangle(&ray, a, b, c).is_none());
        let behind = Ray::new(Vec3::new(0.25, 0.25, 2.0), Vec3::new(0.0, 0.0, 1.0));
        assert!(intersect_triangle(&behind, a, b, c).is_none());
        let from_below = Ray::new(Vec3::new(0.25, 0.25, -2.0), Vec3::new(0.0, 0.0, 1.0));
        assert!(intersect_triangle(&from_below, a, b, c).is_some());
    }

    #[test]
    fn misses_outside_and_degenerate() {
        let [a, b, c] = tri();
        let ray = Ray::new(Vec3::new(0.75, 0.75, 2.0), Vec3::new(0.0, 0.0, -1.0));
        assert!(intersect_triangle(&ray, a, b, c).is_none());
        let through = Ray::new(Vec3::new(0.5, 0.0, 2.0), Vec3::new(0.0, 0.0, -1.0));
        assert!(intersect_triangle(&through, a, b, a + 2.0 * (b - a)).is_none());
        let zero_dir = Ray::new(Vec3::new(0.25, 0.25, 2.0), Vec3::ZERO);
        assert!(intersect_triangle(&zero_dir, a, b, c).is_none());
    }

    #[test]
    fn edge_and_vertex_rays_hit() {
        let [a, b, c] = tri();
        for p in [a, b, c, 0.5 * (a + b), 0.5 * (b + c), 0.5 * (a + c)] {
            let ray = Ray::new(p + Vec3::new(0.0, 0.0, 3.0), Vec3::new(0.0, 0.0, -1.0));
            assert!(intersect_triangle(&ray, a, b, c).is_some(), "{p}");
        }
    }
}
