//! The native BVH over triangles and spheres in one tree, built as a binary tree
//! by binned SAH (default) or the course's midpoint split, then collapsed into
//! wide SIMD nodes whose leaves are blocks of up to four primitives, copied so
//! traversal never goes through the scene's index buffers.

mod build;
mod build_midpoint;
mod build_sah;
mod collapse;
mod huge_pages;
mod node;
mod packet;
mod traverse;
mod wide;

use super::prims::{hittable_prims_as, SphereStore, TriBlock};
use super::{Accel, BvhBuilder, TraversalStats};
use crate::geometry::Ray;
use crate::scene::{PrimHit, PrimId, Scene};
use build::{build_nodes, BuildPrim};
use build_midpoint::MidpointBuilder;
use build_sah::SahBinnedBuilder;
use collapse::collapse;
use rayon::prelude::*;
use wide::{ChildRef, WideNode, WIDTH};

/// Shape and quality of a built tree (the wide traversal layout), for `ember
/// info` and benchmarks.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BvhStats {
    /// Wide inner nodes.
    pub nodes: usize,
    /// Leaves (one block of at most 4 primitives each).
    pub leaves: usize,
    /// Primitives referenced by leaves (degenerate ones are left out).
    pub prims: usize,
    /// Longest root-to-leaf path, counted in nodes (a lone leaf has depth 1).
    pub max_depth: usize,
    /// Expected cost of a random ray that hits the root box: a wide node visit
    /// costs [`build_sah::TRAVERSAL_COST`], a leaf block test
    /// [`build_sah::INTERSECTION_COST`].
    pub sah_cost: f32,
    /// Children per node.
    pub width: usize,
}

/// Equality compares the whole layout: two builds are equal when they produced
/// the same tree.
#[derive(PartialEq)]
pub struct Bvh {
    nodes: Vec<WideNode>,
    blocks: Vec<TriBlock>,
    spheres: SphereStore,
    root: ChildRef,
    builder: BvhBuilder,
    stats: BvhStats,
}

impl Bvh {
    pub fn build(scene: &Scene, builder: BvhBuilder) -> Bvh {
        let mut build_prims: Vec<BuildPrim> = hittable_prims_as(scene, BuildPrim::new);
        let binary = match builder {
            BvhBuilder::Sah => build_nodes(&SahBinnedBuilder::default(), &mut build_prims),
            BvhBuilder::Midpoint => build_nodes(&MidpointBuilder::default(), &mut build_prims),
        };
        let order: Vec<PrimId> = build_prims.par_iter().map(|p| p.id).collect();
        drop(build_prims);
        let tree = collapse(&binary, scene, &order);
        let root_bounds = binary.first().map(|n| n.bounds());
        let mut bvh = Bvh {
            nodes: tree.nodes,
            blocks: tree.blocks,
            spheres: SphereStore::new(scene),
            root: tree.root,
            builder,
            stats: BvhStats::default(),
        };
        bvh.stats = bvh.tree_stats(root_bounds.map_or(0.0, |b| b.surface_area()));
        bvh
    }

    pub fn stats(&self) -> BvhStats {
        self.stats
    }

    fn tree_stats(&self, root_area: f32) -> BvhStats {
        let mut stats = BvhStats {
            width: WIDTH,
            ..BvhStats::default()
        };
        if self.blocks.is_empty() {
            return stats;
        }
        let rel = |a: f32| {
            if root_area > 0.0 {
                f64::from(a / root_area)
            } else {
                0.0
            }
        };
        let mut cost = 0.0f64;
        let mut stack = vec![(self.root, 1usize, 1.0f64)];
        while let Some((r, depth, area)) = stack.pop() {
            stats.max_depth = stats.max_depth.max(depth);
            if r.is_leaf() {
                stats.leaves += 1;
                stats.prims += r.count() as usize;
                cost += area * f64::from(build_sah::INTERSECTION_COST);
                continue;
            }
            stats.nodes += 1;
            cost += area * f64::from(build_sah::TRAVERSAL_COST);
            let node = &self.nodes[r.index() as usize];
            for c in 0..node.len() {
                let b = node.child_bounds(c);
                stack.push((node.child(c), depth + 1, rel(b.surface_area())));
            }
        }
        stats.sah_cost = if root_area > 0.0 { cost as f32 } else { 0.0 };
        stats
    }
}

impl Accel for Bvh {
    fn intersect(&self, ray: &Ray) -> Option<PrimHit> {
        self.traverse::<false, false>(ray, &mut TraversalStats::default())
    }

    fn occluded(&self, ray: &Ray) -> bool {
        self.traverse::<true, false>(ray, &mut TraversalStats::default())
            .is_some()
    }

    fn intersect_packet(
        &self,
        rays: &crate::accel::RayPacket,
        active: crate::lanes::LaneBits,
        hits: &mut crate::accel::HitPacket,
    ) {
        crate::lanes::dispatch(packet::IntersectPacket {
            bvh: self,
            rays,
            active,
            hits,
        })
    }

    fn occluded_packet(
        &self,
        rays: &crate::accel::RayPacket,
        active: crate::lanes::LaneBits,
    ) -> crate::lanes::LaneBits {
        crate::lanes::dispatch(packet::OccludedPacket {
            bvh: self,
            rays,
            active,
        })
    }

    fn intersect_counted(&self, ray: &Ray, stats: &mut TraversalStats) -> Option<PrimHit> {
        self.traverse::<false, true>(ray, stats)
    }

    fn name(&self) -> String {
        match self.builder {
            BvhBuilder::Sah => "native BVH (binned SAH)".into(),
            BvhBuilder::Midpoint => "native BVH (midpoint)".into(),
        }
    }

    fn bvh_stats(&self) -> Option<BvhStats> {
        Some(self.stats)
    }

    /// Only what traversal reads: nodes, leaf blocks and spheres.
    fn memory_bytes(&self) -> usize {
        std::mem::size_of::<Self>()
            + self.nodes.capacity() * std::mem::size_of::<WideNode>()
            + self.blocks.capacity() * std::mem::size_of::<TriBlock>()
            + self.spheres.memory_bytes()
    }
}
