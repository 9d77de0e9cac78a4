//! The brute-force oracle: every ray tests every primitive. It shares only the
//! primitive tests with the BVH, so comparing the two checks the BVH's builders
//! and traversal; it is also the baseline the BVH's speed-up is measured against.

use super::prims::{hittable_prims, PrimRay, PrimStore};
use super::{Accel, TraversalStats};
use crate::geometry::Ray;
use crate::scene::{PrimHit, PrimId, Scene};

pub struct BruteForce {
    prims: PrimStore,
}

impl BruteForce {
    pub fn new(scene: &Scene) -> Self {
        let order: Vec<PrimId> = hittable_prims(scene)
            .into_iter()
            .map(|(id, _)| id)
            .collect();
        BruteForce {
            prims: PrimStore::new(scene, &order),
        }
    }
}

impl Accel for BruteForce {
    fn intersect(&self, ray: &Ray) -> Option<PrimHit> {
        self.intersect_counted(ray, &mut TraversalStats::default())
    }

    fn occluded(&self, ray: &Ray) -> bool {
        let r = PrimRay::new(ray);
        (0..self.prims.len()).any(|i| self.prims.intersect(i, &r, ray.t_max).is_some())
    }

    fn intersect_counted(&self, ray: &Ray, stats: &mut TraversalStats) -> Option<PrimHit> {
        let r = PrimRay::new(ray);
        let mut best: Option<PrimHit> = None;
        let mut t_max = ray.t_max;
        for i in 0..self.prims.len() {
            if let Some(h) = self.prims.intersect(i, &r, t_max) {
                t_max = h.t;
                best = Some(h);
            }
        }
        stats.prims += self.prims.len() as u32;
        best
    }

    fn name(&self) -> String {
        "brute force".into()
    }

    fn memory_bytes(&self) -> usize {
        std::mem::size_of::<Self>() + self.prims.memory_bytes()
    }
}
