//! Ordered stack traversal over pair nodes: both children's boxes are tested at
//! the parent, the ray descends into the nearer child it enters and pushes the
//! farther one with its entry distance; a popped child whose entry lies beyond
//! the closest hit found since is skipped without touching its memory. Shadow
//! rays (any hit) skip the ordering: the first occluder ends the search wherever
//! it is, and the compare cost more than it saved (3% of `occluded` on CBbunny).

use super::build::MAX_DEPTH;
use super::pair_node::{ChildRef, PairRay, EXIT_SLACK};
use super::Bvh;
use crate::accel::prims::PrimRay;
use crate::accel::TraversalStats;
use crate::geometry::Ray;
use crate::scene::PrimHit;
use std::mem::MaybeUninit;

/// A pushed child and the distance at which the ray enters its box.
#[derive(Clone, Copy)]
struct Pending {
    child: ChildRef,
    entry: f32,
}

impl Bvh {
    /// The one traversal loop. `ANY` stops at the first hit (shadow rays);
    /// `COUNT` records the work done into `stats` (compiled out otherwise).
    #[inline(always)]
    pub(super) fn traverse<const ANY: bool, const COUNT: bool>(
        &self,
        ray: &Ray,
        stats: &mut TraversalStats,
    ) -> Option<PrimHit> {
        if self.prims.len() == 0 {
            return None;
        }
        let boxes = PairRay::new(ray);
        let prim_ray = PrimRay::new(ray);
        let mut t_max = ray.t_max;
        let mut best = None;
        // Left uninitialised: zeroing it cost as much as a small scene's traversal.
        let mut stack = [MaybeUninit::<Pending>::uninit(); MAX_DEPTH + 1];
        let mut sp = 0;
        let mut cur = self.root;
        loop {
            if !cur.is_leaf() {
                let node = &self.pairs[cur.index as usize];
                if COUNT {
                    stats.nodes += 2;
                }
                let hits = boxes.hits(node, t_max);
                let [c0, c1] = node.children;
                match hits.mask {
                    0 => {}
                    1 => {
                        cur = c0;
                        continue;
                    }
                    2 => {
                        cur = c1;
                        continue;
                    }
                    _ => {
                        let [e0, e1] = hits.entry;
                        let (near, far, far_entry) = if !ANY && e1 < e0 {
                            (c1, c0, e0)
                        } else {
                            (c0, c1, e1)
                        };
                        stack[sp] = MaybeUninit::new(Pending {
                            child: far,
                            entry: far_entry,
                        });
                        sp += 1;
                        cur = near;
                        continue;
                    }
                }
            } else {
                if COUNT {
                    stats.prims += cur.count;
                }
                let (first, count) = (cur.index as usize, cur.count as usize);
                if ANY {
                    if let Some(hit) = self.prims.intersect_any(first, count, &prim_ray, t_max) {
                        return Some(hit);
                    }
                } else if let Some(hit) =
                    self.prims.intersect_closest(first, count, &prim_ray, t_max)
                {
                    t_max = hit.t;
                    best = Some(hit);
                }
            }
            // Pop the next child the ray may still reach (with `ANY`, `t_max` has
            // not changed since the push, so the check always passes).
            loop {
                if sp == 0 {
                    return best;
                }
                sp -= 1;
                // SAFETY: slots below `sp` were written by a push.
                let p = unsafe { stack[sp].assume_init() };
                if ANY || p.entry <= t_max * EXIT_SLACK {
                    cur = p.child;
                    break;
                }
            }
        }
    }
}
