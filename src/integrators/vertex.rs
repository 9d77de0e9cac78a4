//! What the path tracer and the light tracer do alike at a surface: the vertex they
//! meet there (its BSDF, shading frame and the direction back along the ray), the
//! next direction drawn from it, and the count of bounces that picks each bounce's
//! sample dimensions. Written once here so the two estimators cannot drift apart.

use super::path::geometrically_consistent;
use super::PathSettings;
use crate::geometry::Frame;
use crate::lanes::{each_lane, LaneBits, LaneMask, Lanes, Real, UInt, LANES, V3};
use crate::materials::{BsdfLanes, BsdfSample};
use crate::scene::{Hits, Scene};
use glam::Vec2;

/// A scattering vertex of the lanes of a kernel.
pub(super) struct Vertex<L: Lanes> {
    pub hit: Hits<L>,
    pub bsdf: BsdfLanes<L>,
    pub frame: Frame<L::F>,
    /// Back along the arriving ray: in the world, and in the shading frame.
    pub wo_world: V3<L::F>,
    pub wo: V3<L::F>,
}

impl<L: Lanes> Vertex<L> {
    /// The vertex at the hits of `lanes`, reached along the unit direction `w`.
    #[inline(always)]
    pub fn new(l: L, scene: &Scene, lanes: LaneBits, hit: Hits<L>, w: V3<L::F>) -> Self {
        let uv = (hit.uv.0.to_array(), hit.uv.1.to_array());
        let bsdf = BsdfLanes::gather(l, lanes, |i| {
            scene.bsdf_at(hit.material[i], Vec2::new(uv.0[i], uv.1[i]))
        });
        let frame = Frame::around(hit.ns);
        let wo_world = -w;
        let wo = frame.local(wo_world);
        Vertex {
            hit,
            bsdf,
            frame,
            wo_world,
            wo,
        }
    }

    /// The next direction, drawn from the BSDF (`u_lobe` picks the lobe, `u` the
    /// direction): the sample, its world direction, and the lanes of `lanes` where it
    /// is valid and leaves on the side of the geometric surface the BSDF chose (so
    /// shading normals cannot leak light).
    #[inline(always)]
    pub fn sample_next(
        &self,
        l: L,
        lanes: LaneBits,
        u_lobe: L::F,
        u: (L::F, L::F),
    ) -> (BsdfSample<L::F>, V3<L::F>, LaneBits) {
        let bs = self.bsdf.sample(l, self.wo, u_lobe, u);
        let wi_world = self.frame.world(bs.wi);
        let reflect = (bs.wi.z * self.wo.z).gt(l.f(0.0));
        let consistent = geometrically_consistent(self.hit.ng, self.wo_world, wi_world, reflect);
        let go = (bs.valid & consistent).bits() & lanes;
        (bs, wi_world, go)
    }
}

/// Per material: whether it scatters light at all. A path ends on one that does not.
pub(super) struct Scattering(Vec<bool>);

impl Scattering {
    pub fn of(scene: &Scene) -> Self {
        Scattering(scene.materials.iter().map(|m| m.scatters()).collect())
    }

    /// The lanes of `lanes` whose material scatters nothing.
    #[inline(always)]
    pub fn dark(&self, material: &[u32; LANES], lanes: LaneBits) -> LaneBits {
        each_lane(lanes)
            .filter(|&i| !self.0[material[i] as usize])
            .fold(0, |m, i| m | 1 << i)
    }
}

/// How deep each lane's path is: its scattering events so far, and the first
/// dimension pair of its current bounce (each bounce draws its own pairs).
#[derive(Clone, Copy)]
pub(super) struct Depth<L: Lanes> {
    /// Small integers, exact as floats.
    pub bounces: L::F,
    pub pair_base: L::U,
}

impl<L: Lanes> Depth<L> {
    #[inline(always)]
    pub fn new(l: L) -> Self {
        Depth {
            bounces: l.f(0.0),
            pair_base: l.u(0),
        }
    }

    /// Lanes `m` start a path: no bounce yet, the first bounce's pairs from `base`.
    #[inline(always)]
    pub fn start(&mut self, l: L, m: L::M, base: u32) {
        self.bounces = L::F::select(m, l.f(0.0), self.bounces);
        self.pair_base = L::U::select(m, l.u(base), self.pair_base);
    }

    /// Lanes `m` scatter once more. The first bounce's pairs start at the base; each
    /// later one moves it on by `per_bounce`.
    #[inline(always)]
    pub fn advance(&mut self, l: L, m: L::M, per_bounce: u32) {
        self.bounces = L::F::select(m, self.bounces + l.f(1.0), self.bounces);
        let moved = m & self.bounces.gt(l.f(1.0));
        let next_base = self.pair_base.wrapping_add(l.u(per_bounce));
        self.pair_base = L::U::select(moved, next_base, self.pair_base);
    }

    /// The lanes of `lanes` where light found after this many bounces counts.
    #[inline(always)]
    pub fn counts(&self, l: L, s: &PathSettings, lanes: LaneBits) -> LaneBits {
        s.counts_l(l, self.bounces).bits() & lanes
    }

    /// The lanes of `lanes` at the depth cap.
    #[inline(always)]
    pub fn at_cap(&self, l: L, s: &PathSettings, lanes: LaneBits) -> LaneBits {
        self.bounces.ge(l.f(s.max_depth as f32)).bits() & lanes
    }
}
