//! Primitive storage shared by the BVH leaves and the brute-force oracle: the
//! hittable primitives of a scene, in an order chosen by the structure, with the
//! triangle corners copied next to each other so tests never chase scene indices.

use crate::geometry::sphere::{
    intersect_sphere, intersect_sphere_lanes, intersect_sphere_leaving, sphere_is_hittable,
};
use crate::geometry::triangle::{
    triangle_is_hittable, Edges, PackedTriangle, Triangle4, TriangleRay,
};
use crate::geometry::{Aabb, Ray};
use crate::lanes::rays::{PacketHits, PacketRays};
use crate::lanes::{F32s, LaneBits, Simd, U32s};
use crate::scene::{PrimHit, PrimId, Scene};
use glam::Vec3;
use rayon::prelude::*;

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
/// leave `tris[i]` unused and are tested by `spheres`.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct PrimStore {
    tris: Vec<PackedTriangle>,
    ids: Vec<PrimId>,
    spheres: SphereStore,
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
            spheres: SphereStore::new(scene),
        }
    }

    pub fn len(&self) -> usize {
        self.ids.len()
    }

    pub fn memory_bytes(&self) -> usize {
        self.tris.capacity() * std::mem::size_of::<PackedTriangle>()
            + self.ids.capacity() * std::mem::size_of::<PrimId>()
            + self.spheres.memory_bytes()
    }

    /// Tests slot `i` for a hit with `t ≤ t_max`.
    #[inline(always)]
    pub fn intersect(&self, i: usize, r: &PrimRay, t_max: f32) -> Option<PrimHit> {
        self.intersect_slot(&self.tris[i], self.ids[i], r, t_max)
    }

    #[inline(always)]
    fn intersect_slot(
        &self,
        tri: &PackedTriangle,
        prim: PrimId,
        r: &PrimRay,
        t_max: f32,
    ) -> Option<PrimHit> {
        if prim < self.spheres.num_triangles {
            if prim == r.ray.skip {
                return None;
            }
            let h = tri.intersect(&r.tri, t_max)?;
            Some(PrimHit {
                t: h.t,
                prim,
                b1: h.b1,
                b2: h.b2,
            })
        } else {
            self.spheres.intersect(prim, r.ray, t_max)
        }
    }
}

/// A BVH leaf: up to four primitives, the triangles among them stored as one
/// [`Triangle4`] and tested together; sphere lanes (rare) are tested one by one.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(16))]
pub(crate) struct TriBlock {
    tris: Triangle4,
    ids: [PrimId; 4],
    tri_lanes: u32,
    sphere_lanes: u32,
}

/// The spheres a leaf's sphere lanes refer to (ids `≥ num_triangles`).
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct SphereStore {
    spheres: Vec<(Vec3, f32)>,
    num_triangles: u32,
}

impl SphereStore {
    pub fn new(scene: &Scene) -> Self {
        SphereStore {
            spheres: scene.spheres.iter().map(|s| (s.centre, s.radius)).collect(),
            num_triangles: scene.triangles.len() as u32,
        }
    }

    pub fn memory_bytes(&self) -> usize {
        self.spheres.capacity() * std::mem::size_of::<(Vec3, f32)>()
    }

    /// Sphere `prim` on `ray`; a ray spawned from it (its `skip`) can only reach
    /// its far side.
    #[inline(never)]
    fn intersect(&self, prim: PrimId, ray: &Ray, t_max: f32) -> Option<PrimHit> {
        let (centre, radius) = self.spheres[(prim - self.num_triangles) as usize];
        let ray = Ray { t_max, ..*ray };
        let t = if prim == ray.skip {
            intersect_sphere_leaving(&ray, centre, radius)?
        } else {
            intersect_sphere(&ray, centre, radius)?
        };
        Some(PrimHit {
            t,
            prim,
            b1: 0.0,
            b2: 0.0,
        })
    }
}

impl TriBlock {
    /// The blocks of `leaves` into `blocks` (emptied first, its capacity kept when
    /// it suffices), in parallel: leaf `(first, count)` holds the primitives
    /// `order[first..first + count]`. Leaves follow the tree, so their triangles
    /// are scattered over the scene: each run of leaves asks the cache for the
    /// triangles of the leaves a few steps ahead, and for their corners once the
    /// triangles are in.
    pub fn make_all(
        scene: &Scene,
        leaves: &[(u32, u32)],
        order: &[PrimId],
        blocks: &mut Vec<TriBlock>,
    ) {
        const RUN: usize = 512;
        const AHEAD: usize = 16;
        let ids = |l: usize| {
            let (first, count) = leaves[l];
            &order[first as usize..(first + count) as usize]
        };
        blocks.clear();
        blocks.reserve_exact(leaves.len());
        blocks.spare_capacity_mut()[..leaves.len()]
            .par_chunks_mut(RUN)
            .enumerate()
            .for_each(|(run, out)| {
                let start = run * RUN;
                for (k, slot) in out.iter_mut().enumerate() {
                    let l = start + k;
                    if l + AHEAD < leaves.len() {
                        ask_cache_for_triangles(scene, ids(l + AHEAD), false);
                    }
                    if l + AHEAD / 2 < leaves.len() {
                        ask_cache_for_triangles(scene, ids(l + AHEAD / 2), true);
                    }
                    slot.write(TriBlock::new(scene, ids(l)));
                }
            });
        // SAFETY: the loop above wrote every one of the first `leaves.len()` slots.
        unsafe { blocks.set_len(leaves.len()) };
    }

    /// The primitives `ids` (at most four, hittable) of `scene`.
    pub fn new(scene: &Scene, ids: &[PrimId]) -> Self {
        let ntri = scene.triangles.len();
        let mut corners = [[Vec3::ZERO; 3]; 4];
        let mut block_ids = [0; 4];
        let (mut tri_lanes, mut sphere_lanes) = (0, 0);
        for (lane, &id) in ids.iter().enumerate() {
            block_ids[lane] = id;
            if (id as usize) < ntri {
                corners[lane] = scene.triangle_positions(id as usize);
                tri_lanes |= 1 << lane;
            } else {
                sphere_lanes |= 1 << lane;
            }
        }
        TriBlock {
            tris: Triangle4::new(&corners),
            ids: block_ids,
            tri_lanes,
            sphere_lanes,
        }
    }

    /// The nearest hit with `t ≤ t_max` that beats the best so far (`t_max` itself
    /// from primitive `best_id`): nearer, or as near with a lower primitive id, so
    /// ties do not depend on the order in which leaves are visited.
    #[inline(always)]
    pub fn intersect_closest(
        &self,
        spheres: &SphereStore,
        r: &PrimRay,
        mut t_max: f32,
        mut best_id: PrimId,
    ) -> Option<PrimHit> {
        let h = self.tris.intersect(&r.tri, t_max, self.tri_lanes(r));
        let mut best = None;
        let beats = |t: f32, id: PrimId, t_max: f32, best_id: PrimId| {
            t < t_max || (t == t_max && id < best_id)
        };
        if self.sphere_lanes == 0 {
            let mut mask = h.mask;
            while mask != 0 {
                let lane = mask.trailing_zeros() as usize;
                mask &= mask - 1;
                if beats(h.t[lane], self.ids[lane], t_max, best_id) {
                    t_max = h.t[lane];
                    best_id = self.ids[lane];
                    best = Some(self.hit(&h, lane));
                }
            }
            return best;
        }
        for lane in 0..4 {
            let hit = if h.mask & 1 << lane != 0 {
                Some(self.hit(&h, lane))
            } else if self.sphere_lanes & 1 << lane != 0 {
                spheres.intersect(self.ids[lane], r.ray, t_max)
            } else {
                None
            };
            if let Some(hit) = hit.filter(|h| beats(h.t, h.prim, t_max, best_id)) {
                (t_max, best_id) = (hit.t, hit.prim);
                best = Some(hit);
            }
        }
        best
    }

    /// Some hit with `t ≤ t_max`.
    #[inline(always)]
    pub fn intersect_any(&self, spheres: &SphereStore, r: &PrimRay, t_max: f32) -> Option<PrimHit> {
        let h = self.tris.intersect(&r.tri, t_max, self.tri_lanes(r));
        if h.mask != 0 {
            return Some(self.hit(&h, h.mask.trailing_zeros() as usize));
        }
        let mut lanes = self.sphere_lanes;
        while lanes != 0 {
            let lane = lanes.trailing_zeros() as usize;
            lanes &= lanes - 1;
            if let Some(hit) = spheres.intersect(self.ids[lane], r.ray, t_max) {
                return Some(hit);
            }
        }
        None
    }

    /// The packet version of [`intersect_closest`](Self::intersect_closest) (`ANY`
    /// false: nearer hits go into `hits`) and of [`intersect_any`](Self::intersect_any)
    /// (`ANY`: stops once every lane of `lanes` hit). Returns the lanes that hit.
    #[inline(always)]
    pub fn intersect_packet<S: Simd, const ANY: bool>(
        &self,
        s: S,
        spheres: &SphereStore,
        rays: &PacketRays<S>,
        lanes: LaneBits,
        hits: &mut PacketHits<S>,
    ) -> LaneBits {
        // Every triangle's edge functions first, without a branch on any outcome,
        // so the tests overlap; then the rest of each test in order.
        let mut edges = [Edges::none(s); 4];
        let mut tris = self.tri_lanes;
        while tris != 0 {
            let lane = tris.trailing_zeros() as usize;
            tris &= tris - 1;
            // A ray never meets the triangle it left.
            let own = rays.skip.eq(U32s::splat(s, self.ids[lane])).bits();
            edges[lane] = rays.tri.edges(s, &self.tris.corners(lane), lanes & !own);
        }
        let mut found = 0;
        let mut rest = self.tri_lanes | self.sphere_lanes;
        while rest != 0 {
            let lane = rest.trailing_zeros() as usize;
            rest &= rest - 1;
            let id = self.ids[lane];
            let todo = if ANY { lanes & !found } else { lanes };
            let (hit, t, b1, b2) = if self.tri_lanes >> lane & 1 != 0 {
                let mut edges = edges[lane];
                edges.restrict(todo);
                rays.tri
                    .finish(s, &self.tris.corners(lane), &edges, hits.t_max)
            } else {
                let own = rays.skip.eq(U32s::splat(s, id));
                let (centre, radius) = spheres.spheres[(id - spheres.num_triangles) as usize];
                let (hit, t) = intersect_sphere_lanes(
                    s, rays.o, rays.d, centre, radius, hits.t_max, own, todo,
                );
                let zero = F32s::splat(s, 0.0);
                (hit, t, zero, zero)
            };
            found |= hit;
            if ANY {
                if lanes & !found == 0 {
                    break;
                }
            } else if hit != 0 {
                hits.record(s, hit, t, id, b1, b2);
            }
        }
        found
    }

    /// The triangle lanes to test: all but the triangle the ray left (`skip`).
    #[inline(always)]
    fn tri_lanes(&self, r: &PrimRay) -> u32 {
        let skip = r.ray.skip;
        let same = |lane: usize| u32::from(self.ids[lane] == skip) << lane;
        self.tri_lanes & !(same(0) | same(1) | same(2) | same(3))
    }

    #[inline(always)]
    fn hit(&self, h: &crate::geometry::triangle::Hits4, lane: usize) -> PrimHit {
        PrimHit {
            t: h.t[lane],
            prim: self.ids[lane],
            b1: h.b1[lane],
            b2: h.b2[lane],
        }
    }
}

/// Prefetches the index records of the triangles among `ids`, or with
/// `corners`, their corner positions (reading the records, which should be in
/// the cache by then).
#[inline(always)]
fn ask_cache_for_triangles(scene: &Scene, ids: &[PrimId], corners: bool) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        let prefetch = |p: *const i8| {
            // SAFETY: a prefetch never faults; the addresses are in bounds anyway.
            unsafe { _mm_prefetch::<_MM_HINT_T0>(p) }
        };
        for &id in ids {
            let Some(t) = scene.triangles.get(id as usize) else {
                continue;
            };
            if !corners {
                prefetch((t as *const crate::scene::Triangle).cast());
                continue;
            }
            for &v in &t.v {
                if let Some(p) = scene.positions.get(v as usize) {
                    prefetch((p as *const Vec3).cast());
                }
            }
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = (scene, ids, corners);
}

/// Ids of the primitives that can ever be hit (finite, non-degenerate), with
/// their bounds. Both the BVH and the brute-force oracle start from this list,
/// so they agree on what exists.
pub(crate) fn hittable_prims(scene: &Scene) -> Vec<(PrimId, Aabb)> {
    hittable_prims_as(scene, |id, bounds| (id, bounds))
}

/// [`hittable_prims`] made into records by `record(id, bounds)` on the way (no
/// list in between); in parallel, one pass over the scene, the list in id order.
pub(crate) fn hittable_prims_as<T: Send>(
    scene: &Scene,
    record: impl Fn(PrimId, Aabb) -> T + Sync,
) -> Vec<T> {
    let n = scene.num_prims();
    let (mut records, mut hittable) = (Vec::with_capacity(n), Vec::with_capacity(n));
    // Each primitive's check and bounds read the same memory, while it is cached.
    (0..n)
        .into_par_iter()
        .map(|i| {
            let h = is_hittable(scene, i);
            let bounds = if h {
                scene.prim_bounds(i as PrimId)
            } else {
                Aabb::EMPTY
            };
            (record(i as PrimId, bounds), h)
        })
        .unzip_into_vecs(&mut records, &mut hittable);
    if hittable.iter().all(|&h| h) {
        return records;
    }
    records
        .into_par_iter()
        .zip(hittable)
        .filter_map(|(r, h)| h.then_some(r))
        .collect()
}

fn is_hittable(scene: &Scene, i: usize) -> bool {
    let ntri = scene.triangles.len();
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
}
