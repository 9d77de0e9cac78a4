//! Packet traversal: sixteen rays walk the wide tree together. At a node every
//! child box is tested against every ray still in the packet (one SIMD value per
//! child and axis); children that any ray enters are visited nearest first (by
//! the smallest entry of their rays), each with the mask of rays that enter it
//! and their entry distances, so a popped child is skipped by rays whose nearest
//! hit already lies before it. Leaves test each primitive against all their rays
//! at once. Packets that have thinned out to a few rays finish one ray at a time.

use super::build::MAX_DEPTH;
use super::wide::{ChildRef, EXIT_SLACK, WIDTH};
use super::Bvh;
use crate::accel::packet::{HitPacket, PacketHits, PacketRays, RayPacket};
use crate::accel::TraversalStats;
use crate::simd::{F32s, LaneBits, Simd, SimdTask, LANES};
use std::mem::MaybeUninit;

/// Rays left in a packet at or below which the rest is traced ray by ray.
const SINGLE_RAY_BELOW: u32 = 0;

/// Every level pushes at most `WIDTH − 1` children.
const STACK: usize = MAX_DEPTH * (WIDTH - 1) + 1;

struct Pending<S: Simd> {
    child: ChildRef,
    lanes: LaneBits,
    entry: F32s<S>,
}

impl<S: Simd> Clone for Pending<S> {
    fn clone(&self) -> Self {
        *self
    }
}
impl<S: Simd> Copy for Pending<S> {}

/// `Bvh::intersect_packet`, run with the best instruction set.
pub(super) struct IntersectPacket<'a> {
    pub bvh: &'a Bvh,
    pub rays: &'a RayPacket,
    pub active: LaneBits,
    pub hits: &'a mut HitPacket,
}

impl SimdTask for IntersectPacket<'_> {
    type Output = ();
    #[inline(always)]
    fn run<S: Simd>(self, s: S) {
        let mut found = PacketHits::new(s, self.rays);
        let done = self
            .bvh
            .traverse_packet::<S, false>(s, self.rays, self.active, &mut found);
        let mut all = *self.hits;
        found.store(&mut all);
        for i in (0..LANES).filter(|&i| self.active >> i & 1 != 0) {
            if done >> i & 1 != 0 {
                self.hits.set(i, all.hit(i));
            } else {
                // Finished on its own after the packet thinned out.
                let hit = self.bvh.traverse::<false, false>(
                    &self.rays.ray(i),
                    &mut TraversalStats::default(),
                );
                self.hits.set(i, hit);
            }
        }
    }
}

/// `Bvh::occluded_packet`, run with the best instruction set.
pub(super) struct OccludedPacket<'a> {
    pub bvh: &'a Bvh,
    pub rays: &'a RayPacket,
    pub active: LaneBits,
}

impl SimdTask for OccludedPacket<'_> {
    type Output = LaneBits;
    #[inline(always)]
    fn run<S: Simd>(self, s: S) -> LaneBits {
        let mut unused = PacketHits::new(s, self.rays);
        let occluded = self
            .bvh
            .traverse_packet::<S, true>(s, self.rays, self.active, &mut unused);
        occluded & self.active
    }
}

impl Bvh {
    /// With `ANY` false: nearest hits of the lanes of `active` into `hits`; returns
    /// the lanes it finished (the others must be traced alone). With `ANY`:
    /// returns the occluded lanes (it finishes every lane).
    #[inline(always)]
    fn traverse_packet<S: Simd, const ANY: bool>(
        &self,
        s: S,
        packet: &RayPacket,
        active: LaneBits,
        hits: &mut PacketHits<S>,
    ) -> LaneBits {
        if self.blocks.is_empty() || active == 0 {
            return if ANY { 0 } else { active };
        }
        let rays = PacketRays::new(s, packet);
        let zero = F32s::splat(s, 0.0);
        let slack = F32s::splat(s, EXIT_SLACK);
        // Left uninitialised: its size (a lane value per entry) would cost more to
        // zero than a small scene's traversal.
        let mut stack = [const { MaybeUninit::<Pending<S>>::uninit() }; STACK];
        stack[0] = MaybeUninit::new(Pending {
            child: self.root,
            lanes: active,
            entry: zero,
        });
        let mut sp = 1;
        let mut occluded: LaneBits = 0;
        // Lanes left to finish one by one (closest hit only).
        let mut alone: LaneBits = 0;
        while sp > 0 {
            sp -= 1;
            // SAFETY: entries below `sp` were written by a push.
            let Pending {
                child,
                mut lanes,
                entry,
            } = unsafe { stack[sp].assume_init() };
            if ANY {
                lanes &= !occluded;
            } else {
                lanes &= entry.le(hits.t_max * slack).bits() & !alone;
            }
            if lanes == 0 {
                continue;
            }
            if !ANY && lanes.count_ones() <= SINGLE_RAY_BELOW && child != self.root {
                alone |= lanes;
                continue;
            }
            if child.is_leaf() {
                let block = &self.blocks[child.index as usize];
                let hit = block.intersect_packet::<S, ANY>(s, &self.spheres, &rays, lanes, hits);
                if ANY {
                    occluded |= hit;
                    if active & !occluded == 0 {
                        return occluded;
                    }
                }
                continue;
            }
            let node = &self.nodes[child.index as usize];
            let mut order = [(0.0f32, 0usize, 0 as LaneBits, zero); WIDTH];
            let mut n = 0;
            for c in 0..WIDTH {
                if node.lo[0][c] > node.hi[0][c] {
                    continue; // an empty slot
                }
                let (entered, t0) = box_test(s, &rays, node, c, hits.t_max);
                let entered = entered & lanes;
                if entered != 0 {
                    let key = if ANY { 0.0 } else { nearest(t0, entered) };
                    order[n] = (key, c, entered, t0);
                    n += 1;
                }
            }
            // Farthest pushed first, so the nearest is popped next.
            if !ANY {
                order[..n].sort_unstable_by(|a, b| b.0.total_cmp(&a.0));
            }
            for &(_, c, entered, t0) in &order[..n] {
                stack[sp] = MaybeUninit::new(Pending {
                    child: node.children[c],
                    lanes: entered,
                    entry: t0,
                });
                sp += 1;
            }
        }
        if ANY {
            occluded
        } else {
            active & !alone
        }
    }
}

/// The slab test of child `c` against every lane, as `Avx2Boxes` does it for one
/// ray: the lanes that enter it before their `t_max`, and their entry distances.
#[inline(always)]
fn box_test<S: Simd>(
    s: S,
    rays: &PacketRays<S>,
    node: &super::wide::WideNode,
    c: usize,
    t_max: F32s<S>,
) -> (LaneBits, F32s<S>) {
    let o = [rays.o.x, rays.o.y, rays.o.z];
    let mut t0 = F32s::splat(s, 0.0);
    let mut t1 = t_max;
    for a in 0..3 {
        let (lo, hi) = (F32s::splat(s, node.lo[a][c]), F32s::splat(s, node.hi[a][c]));
        let near = F32s::select(rays.neg[a], hi, lo);
        let far = F32s::select(rays.neg[a], lo, hi);
        t0 = ((near - o[a]) * rays.inv[a]).max(t0);
        t1 = ((far - o[a]) * rays.inv[a]).min(t1);
    }
    (t0.le(t1 * F32s::splat(s, EXIT_SLACK)).bits(), t0)
}

/// The smallest entry distance among `lanes`.
#[inline(always)]
fn nearest<S: Simd>(t0: F32s<S>, lanes: LaneBits) -> f32 {
    let t = t0.to_array();
    let mut best = f32::INFINITY;
    let mut rest = lanes;
    while rest != 0 {
        let i = rest.trailing_zeros() as usize;
        rest &= rest - 1;
        best = best.min(t[i]);
    }
    best
}
