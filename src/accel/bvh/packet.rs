//! Packet traversal: sixteen rays walk the wide tree together. At a node every
//! child box is tested against every ray still in the packet (one SIMD value per
//! child and axis); children that any ray enters are visited nearest first (by
//! the smallest entry of their rays), each with the mask of rays that enter it
//! and their entry distances, so a popped child is skipped by rays whose nearest
//! hit already lies before it. Leaves test each primitive against all their rays
//! at once. Packets that have thinned out to a few rays finish one ray at a time.

#[cfg(target_arch = "x86_64")]
use super::wide::{Avx2Boxes, Avx512Boxes};
use super::wide::{ChildRef, ScalarBoxes, EXIT_SLACK, WIDTH};
use super::Bvh;
use crate::accel::TraversalStats;
use crate::geometry::Ray;
use crate::lanes::rays::{HitPacket, PacketHits, PacketRays, RayPacket};
use crate::lanes::{F32s, LaneBits, Mask, Simd, SimdTask};
use std::mem::MaybeUninit;

/// Rays left in a packet at or below which the rest is traced ray by ray. Measured
/// on CBbunny and CBspheres_lambertian (480×360, 64 spp, `-m 5`, AMD EPYC, 2 threads):
/// 2 renders 2–4 % faster than 4, 6 and 8 slower (8: −5 %), 16 (always alone) −20 %
/// (bunny) and −44 % (spheres). Again after the node test lost its branches
/// (CBbunny, 128 spp): 1 and 3 took 1.6 % and 2.5 % longer than 2.
const SINGLE_RAY_BELOW: u32 = 2;

/// Entries of the packet stack (each a lane value: 64 bytes of entry distances).
/// Every level pushes at most `WIDTH − 1` children, so this holds trees up to
/// [`PACKET_DEPTH`] levels deep; deeper (degenerate) trees are traced ray by ray.
/// Sized for the tree rather than for `MAX_DEPTH`, the stack stays a few pages:
/// a larger frame is probed page by page on every call.
const STACK: usize = 256;
const PACKET_DEPTH: usize = (STACK - 1) / (WIDTH - 1);

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
        self.bvh
            .traverse_packet::<S, false>(s, self.rays, self.active, &mut found);
        found.store(s, self.active, self.hits);
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
        self.bvh
            .traverse_packet::<S, true>(s, self.rays, self.active, &mut unused)
            & self.active
    }
}

impl Bvh {
    /// With `ANY` false: the nearest hits of the lanes of `active`, into `hits`.
    /// With `ANY`: returns the lanes that are occluded.
    #[inline(always)]
    fn traverse_packet<S: Simd, const ANY: bool>(
        &self,
        s: S,
        packet: &RayPacket,
        active: LaneBits,
        hits: &mut PacketHits<S>,
    ) -> LaneBits {
        if self.blocks.is_empty() || active == 0 {
            return 0;
        }
        if self.stats.max_depth > PACKET_DEPTH {
            return self.finish_alone::<S, ANY>(s, packet, self.root, active, hits);
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
                lanes &= entry.le(hits.t_max * slack).bits();
            }
            if lanes == 0 {
                continue;
            }
            if lanes.count_ones() <= SINGLE_RAY_BELOW {
                occluded |= self.finish_alone::<S, ANY>(s, packet, child, lanes, hits);
                if ANY && active & !occluded == 0 {
                    return occluded;
                }
                continue;
            }
            if child.is_leaf() {
                let block = &self.blocks[child.index() as usize];
                let hit = block.intersect_packet::<S, ANY>(s, &self.spheres, &rays, lanes, hits);
                if ANY {
                    occluded |= hit;
                    if active & !occluded == 0 {
                        return occluded;
                    }
                }
                continue;
            }
            let node = &self.nodes[child.index() as usize];
            // Every child's test first, without a branch, so the tests overlap; then
            // the entered children, nearest last (pushed last, popped first).
            // (Left uninitialised: only the entries of tested children are read.)
            let mut entry_of = [MaybeUninit::<F32s<S>>::uninit(); WIDTH];
            let mut entered_by = [0 as LaneBits; WIDTH];
            let mut children: u32 = 0;
            for c in 0..node.len() {
                let (entered, t0) = node.hits_packet(s, &rays, c, hits.t_max);
                let entered = entered & lanes;
                entry_of[c] = MaybeUninit::new(t0);
                entered_by[c] = entered;
                children |= u32::from(entered != 0) << c;
            }
            let mut order = [(0.0f32, 0u8, 0 as LaneBits); WIDTH];
            let mut n = 0;
            while children != 0 {
                let c = children.trailing_zeros() as usize;
                children &= children - 1;
                let entered = entered_by[c];
                let key = if ANY {
                    0.0
                } else {
                    // SAFETY: child `c` was tested above.
                    unsafe { entry_of[c].assume_init() }.reduce_min(Mask::from_bits(s, entered))
                };
                // Insertion by decreasing key.
                let mut j = n;
                while j > 0 && order[j - 1].0 < key {
                    order[j] = order[j - 1];
                    j -= 1;
                }
                order[j] = (key, c as u8, entered);
                n += 1;
            }
            for &(_, c, entered) in &order[..n] {
                stack[sp] = MaybeUninit::new(Pending {
                    child: node.child(c as usize),
                    lanes: entered,
                    // SAFETY: child `c` was tested above.
                    entry: unsafe { entry_of[c as usize].assume_init() },
                });
                sp += 1;
            }
        }
        occluded
    }

    /// The lanes `lanes` of the subtree `child`, one ray at a time (a packet that
    /// has thinned out to a few rays costs more as a packet): nearer hits go into
    /// `hits`; with `ANY`, returns the lanes occluded.
    #[inline(always)]
    fn finish_alone<S: Simd, const ANY: bool>(
        &self,
        s: S,
        packet: &RayPacket,
        child: ChildRef,
        lanes: LaneBits,
        hits: &mut PacketHits<S>,
    ) -> LaneBits {
        let t_max = hits.t_max.to_array();
        let mut occluded = 0;
        let mut rest = lanes;
        while rest != 0 {
            let i = rest.trailing_zeros() as usize;
            rest &= rest - 1;
            let ray = Ray {
                t_max: t_max[i],
                ..packet.ray(i)
            };
            let mut stats = TraversalStats::default();
            let hit = if S::AVX512 {
                #[cfg(target_arch = "x86_64")]
                {
                    self.traverse_from::<Avx512Boxes, ANY, false>(&ray, child, &mut stats)
                }
                #[cfg(not(target_arch = "x86_64"))]
                unreachable!()
            } else if S::AVX2 {
                #[cfg(target_arch = "x86_64")]
                {
                    self.traverse_from::<Avx2Boxes, ANY, false>(&ray, child, &mut stats)
                }
                #[cfg(not(target_arch = "x86_64"))]
                unreachable!()
            } else {
                self.traverse_from::<ScalarBoxes, ANY, false>(&ray, child, &mut stats)
            };
            if let Some(h) = hit {
                if ANY {
                    occluded |= 1 << i;
                } else {
                    hits.record_lane(s, i, h);
                }
            }
        }
        occluded
    }
}
