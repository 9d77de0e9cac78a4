//! Primitive storage shared by the BVH leaves and the brute-force oracle: the
//! hittable primitives of a scene, in an order chosen by the structure, with the
//! triangle corners copied next to each other so tests never chase scene indices.

use crate::geometry::sphere::{intersect_sphere, sphere_is_hittable};
use crate::geometry::triangle::{triangle_is_hittable, PackedTriangle, TriangleRay};
use crate::geometry::{Aabb, Ray};
use crate::scene::{PrimHit, PrimId, Scene};
use glam::Vec3;

/// One ray's per-ray setup for every primitive test.
pub(crate) struct PrimRay<'a> {
    pub ray: &'a Ray,
    pub tri: TriangleRay,
}

impl<'a> PrimRay<'a> {
    #[inline]
    pub fn new(ray: &'a Ray) -> Self {
        PrimRay {
            ray,
            tri: TriangleRay::new(ray),
        }
    }
}

/// Primitives in structure order. Slot `i` holds primitive `ids[i]`; triangle
/// slots carry their corners in `tris[i]`, sphere slots (ids `≥ num_triangles`)
/// leave `tris[i]` unused and read the (few) spheres from `spheres`.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct PrimStore {
    tris: Vec<PackedTriangle>,
    ids: Vec<PrimId>,
    spheres: Vec<(Vec3, f32)>,
    num_triangles: u32,
}

impl PrimStore {
    /// Stores `order` (primitive ids) in that order.
    pub fn new(scene: &Scene, order: &[PrimId]) -> Self {
        let ntri = scene.triangles.len();
        let unused = PackedTriangle::new(Vec3::ZERO, Vec3::ZERO, Vec3::ZERO);
        let tris = order
            .iter()
            .map(|&id| {
                if (id as usize) < ntri {
                    let [p0, p1, p2] = scene.triangle_positions(id as usize);
                    PackedTriangle::new(p0, p1, p2)
                } else {
                    unused
                }
            })
            .collect();
        PrimStore {
            tris,
            ids: order.to_vec(),
            spheres: scene.spheres.iter().map(|s| (s.centre, s.radius)).collect(),
            num_triangles: ntri as u32,
        }
    }

    pub fn len(&self) -> usize {
        self.ids.len()
    }

    pub fn memory_bytes(&self) -> usize {
        self.tris.capacity() * std::mem::size_of::<PackedTriangle>()
            + self.ids.capacity() * std::mem::size_of::<PrimId>()
            + self.spheres.capacity() * std::mem::size_of::<(Vec3, f32)>()
    }

    /// Tests slot `i` for a hit with `t ≤ t_max`.
    #[inline(always)]
    pub fn intersect(&self, i: usize, r: &PrimRay, t_max: f32) -> Option<PrimHit> {
        self.intersect_slot(&self.tris[i], self.ids[i], r, t_max)
    }

    /// Closest hit with `t ≤ t_max` among `count` slots from `first` (a leaf).
    #[inline(always)]
    pub fn intersect_closest(
        &self,
        first: usize,
        count: usize,
        r: &PrimRay,
        mut t_max: f32,
    ) -> Option<PrimHit> {
        let mut best = None;
        // One bounds check per leaf instead of two per primitive.
        let ids = &self.ids[first..first + count];
        let tris = &self.tris[first..first + count];
        for (tri, &prim) in tris.iter().zip(ids) {
            if let Some(hit) = self.intersect_slot(tri, prim, r, t_max) {
                t_max = hit.t;
                best = Some(hit);
            }
        }
        best
    }

    /// Some hit with `t ≤ t_max` among `count` slots from `first` (a leaf).
    #[inline(always)]
    pub fn intersect_any(
        &self,
        first: usize,
        count: usize,
        r: &PrimRay,
        t_max: f32,
    ) -> Option<PrimHit> {
        let ids = &self.ids[first..first + count];
        let tris = &self.tris[first..first + count];
        tris.iter()
            .zip(ids)
            .find_map(|(tri, &prim)| self.intersect_slot(tri, prim, r, t_max))
    }

    #[inline(always)]
    fn intersect_slot(
        &self,
        tri: &PackedTriangle,
        prim: PrimId,
        r: &PrimRay,
        t_max: f32,
    ) -> Option<PrimHit> {
        if prim < self.num_triangles {
            let h = tri.intersect(&r.tri, t_max)?;
            Some(PrimHit {
                t: h.t,
                prim,
                b1: h.b1,
                b2: h.b2,
            })
        } else {
            self.intersect_sphere(prim, r.ray, t_max)
        }
    }

    #[inline(never)]
    fn intersect_sphere(&self, prim: PrimId, ray: &Ray, t_max: f32) -> Option<PrimHit> {
        let (centre, radius) = self.spheres[(prim - self.num_triangles) as usize];
        let ray = Ray { t_max, ..*ray };
        let t = intersect_sphere(&ray, centre, radius)?;
        Some(PrimHit {
            t,
            prim,
            b1: 0.0,
            b2: 0.0,
        })
    }
}

/// Ids of the primitives that can ever be hit (finite, non-degenerate), with
/// their bounds. Both the BVH and the brute-force oracle start from this list,
/// so they agree on what exists.
pub(crate) fn hittable_prims(scene: &Scene) -> Vec<(PrimId, Aabb)> {
    let ntri = scene.triangles.len();
    (0..scene.num_prims())
        .filter(|&i| {
            if i < ntri {
                let in_range = scene.triangles[i]
                    .v
                    .iter()
                    .all(|&k| (k as usize) < scene.positions.len());
                if !in_range {
                    return false;
                }
                let [p0, p1, p2] = scene.triangle_positions(i);
                triangle_is_hittable(p0, p1, p2)
            } else {
                let s = &scene.spheres[i - ntri];
                sphere_is_hittable(s.centre, s.radius)
            }
        })
        .map(|i| (i as PrimId, scene.prim_bounds(i as PrimId)))
        .collect()
}
