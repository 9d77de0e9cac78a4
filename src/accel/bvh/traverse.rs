//! Ordered stack traversal: near child first by the ray's direction sign on the
//! node's split axis, far child on a fixed-size stack.

use super::build::MAX_DEPTH;
use super::node::RayBox;
use super::Bvh;
use crate::accel::prims::PrimRay;
use crate::accel::TraversalStats;
use crate::geometry::Ray;
use crate::scene::PrimHit;

impl Bvh {
    /// The one traversal loop. `ANY` stops at the first hit (shadow rays);
    /// `COUNT` records the work done into `stats` (compiled out otherwise).
    #[inline(always)]
    pub(super) fn traverse<const ANY: bool, const COUNT: bool>(
        &self,
        ray: &Ray,
        stats: &mut TraversalStats,
    ) -> Option<PrimHit> {
        if self.nodes.is_empty() {
            return None;
        }
        let boxes = RayBox::new(ray);
        let prim_ray = PrimRay::new(ray);
        let mut t_max = ray.t_max;
        let mut best = None;
        let mut stack = [0u32; MAX_DEPTH + 1];
        let mut sp = 0;
        let mut index = 0usize;
        loop {
            let node = &self.nodes[index];
            if COUNT {
                stats.nodes += 1;
            }
            if boxes.hits(node, t_max) {
                let count = node.count() as usize;
                if count == 0 {
                    let (near, far) = if boxes.dir_negative(node.axis()) {
                        (node.offset as usize, index + 1)
                    } else {
                        (index + 1, node.offset as usize)
                    };
                    stack[sp] = far as u32;
                    sp += 1;
                    index = near;
                    continue;
                }
                let first = node.offset as usize;
                if COUNT {
                    stats.prims += count as u32;
                }
                for slot in first..first + count {
                    if let Some(hit) = self.prims.intersect(slot, &prim_ray, t_max) {
                        if ANY {
                            return Some(hit);
                        }
                        t_max = hit.t;
                        best = Some(hit);
                    }
                }
            }
            if sp == 0 {
                return best;
            }
            sp -= 1;
            index = stack[sp] as usize;
        }
    }
}
