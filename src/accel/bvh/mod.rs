//! The native BVH: a flat array of 32-byte nodes over triangles and spheres in
//! one tree, built by binned SAH (default) or the course's midpoint split.
//! Leaves reference a copy of the primitives in leaf order, so traversal reads
//! memory front to back and never goes through the scene's index buffers.

mod build;
mod build_midpoint;
mod build_sah;
mod node;
mod pair_node;
mod traverse;

use super::prims::{hittable_prims, PrimStore};
use super::{Accel, BvhBuilder, TraversalStats};
use crate::geometry::Ray;
use crate::scene::{PrimHit, PrimId, Scene};
use build::{build_nodes, BuildPrim};
use build_midpoint::MidpointBuilder;
use build_sah::SahBinnedBuilder;
use node::BvhNode;
use pair_node::{pair_nodes, ChildRef, PairNode};

/// Shape and quality of a built tree, for `ember info` and benchmarks.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BvhStats {
    pub nodes: usize,
    pub leaves: usize,
    /// Primitives referenced by leaves (degenerate ones are left out).
    pub prims: usize,
    /// Longest root-to-leaf path, counted in nodes (a lone leaf has depth 1).
    pub max_depth: usize,
    /// Expected cost of a random ray that hits the root box, with the SAH
    /// builder's cost constants (a node visit costs 1, a primitive test 0.8).
    pub sah_cost: f32,
}

/// Equality compares the whole layout: two builds are equal when they produced
/// the same tree.
#[derive(PartialEq)]
pub struct Bvh {
    /// The builder's nodes, kept for statistics.
    nodes: Vec<BvhNode>,
    /// The same tree in traversal layout, and where traversal starts.
    pairs: Vec<PairNode>,
    root: ChildRef,
    prims: PrimStore,
    builder: BvhBuilder,
    stats: BvhStats,
}

impl Bvh {
    pub fn build(scene: &Scene, builder: BvhBuilder) -> Bvh {
        let mut build_prims: Vec<BuildPrim> = hittable_prims(scene)
            .into_iter()
            .map(|(id, bounds)| BuildPrim::new(id, bounds))
            .collect();
        let nodes = match builder {
            BvhBuilder::Sah => build_nodes(&SahBinnedBuilder::default(), &mut build_prims),
            BvhBuilder::Midpoint => build_nodes(&MidpointBuilder::default(), &mut build_prims),
        };
        let mut nodes = nodes;
        nodes.shrink_to_fit();
        let order: Vec<PrimId> = build_prims.iter().map(|p| p.id).collect();
        let prims = PrimStore::new(scene, &order);
        let stats = tree_stats(&nodes);
        let (pairs, root) = pair_nodes(&nodes);
        Bvh {
            nodes,
            pairs,
            root,
            prims,
            builder,
            stats,
        }
    }

    pub fn stats(&self) -> BvhStats {
        self.stats
    }
}

fn tree_stats(nodes: &[BvhNode]) -> BvhStats {
    let mut stats = BvhStats::default();
    let Some(root) = nodes.first() else {
        return stats;
    };
    let root_area = root.bounds().surface_area();
    let mut stack = vec![(0usize, 1usize)];
    let mut cost = 0.0f64;
    while let Some((i, depth)) = stack.pop() {
        let n = &nodes[i];
        let rel_area = f64::from(n.bounds().surface_area() / root_area);
        stats.nodes += 1;
        stats.max_depth = stats.max_depth.max(depth);
        if n.count() > 0 {
            stats.leaves += 1;
            stats.prims += n.count() as usize;
            cost += rel_area * f64::from(build_sah::INTERSECTION_COST) * f64::from(n.count());
        } else {
            cost += rel_area * f64::from(build_sah::TRAVERSAL_COST);
            stack.push((i + 1, depth + 1));
            stack.push((n.offset as usize, depth + 1));
        }
    }
    stats.sah_cost = if root_area > 0.0 { cost as f32 } else { 0.0 };
    stats
}

impl Accel for Bvh {
    fn intersect(&self, ray: &Ray) -> Option<PrimHit> {
        self.traverse::<false, false>(ray, &mut TraversalStats::default())
    }

    fn occluded(&self, ray: &Ray) -> bool {
        self.traverse::<true, false>(ray, &mut TraversalStats::default())
            .is_some()
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

    fn memory_bytes(&self) -> usize {
        std::mem::size_of::<Self>()
            + self.nodes.capacity() * std::mem::size_of::<BvhNode>()
            + self.pairs.capacity() * std::mem::size_of::<PairNode>()
            + self.prims.memory_bytes()
    }
}
