//! The native BVH over triangles and spheres in one tree, built as a binary tree
//! by binned SAH (default) or the course's midpoint split, then collapsed into
//! wide SIMD nodes whose leaves are blocks of up to four primitives, copied so
//! traversal never goes through the scene's index buffers.

mod build;
mod build_midpoint;
mod build_sah;
mod collapse;
mod float_node;
mod huge_pages;
mod node;
mod quantized_node;
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
use wide::{ChildRef, FloatNode, QuantizedNode, WideNode, WIDTH};

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
    /// Whether child boxes are quantised (large trees) or `f32`.
    pub quantized: bool,
}

/// Equality compares the whole layout: two builds are equal when they produced
/// the same tree.
#[derive(PartialEq)]
pub struct Bvh {
    nodes: Nodes,
    blocks: Vec<TriBlock>,
    spheres: SphereStore,
    root: ChildRef,
    builder: BvhBuilder,
    stats: BvhStats,
}

/// The wide nodes of a tree, in the layout its size calls for.
#[derive(PartialEq)]
enum Nodes {
    Float(Vec<FloatNode>),
    Quantized(Vec<QuantizedNode>),
}

/// How a tree stores the boxes of its nodes' children.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NodeLayout {
    /// `f32` bounds ([`FloatNode`], 448 bytes a 16-wide node).
    Float,
    /// Bounds quantised to a byte per coordinate ([`QuantizedNode`], 192 bytes).
    Quantized,
}

impl NodeLayout {
    pub const ALL: [NodeLayout; 2] = [NodeLayout::Float, NodeLayout::Quantized];

    /// What [`Bvh::build`] gives a tree over `prims` primitives. Small trees stay in
    /// the caches, where `f32` boxes are quicker to test (CBbunny, 28.6k triangles:
    /// incoherent rays 8% and camera rays 20% slower with quantised nodes); large
    /// ones wait on memory, where half the bytes per node win.
    pub fn for_prims(prims: usize) -> NodeLayout {
        if prims > QUANTIZED_FROM_PRIMS {
            NodeLayout::Quantized
        } else {
            NodeLayout::Float
        }
    }
}

const QUANTIZED_FROM_PRIMS: usize = 100_000;

impl Bvh {
    /// The tree of `builder` over `scene`'s hittable primitives, in the node
    /// layout its size calls for ([`NodeLayout::for_prims`]).
    pub fn build(scene: &Scene, builder: BvhBuilder) -> Bvh {
        Self::build_as(scene, builder, None)
    }

    /// [`Bvh::build`] with the node layout chosen by the caller (the same tree,
    /// only its boxes stored otherwise): for tests and benchmarks.
    pub fn build_with_layout(scene: &Scene, builder: BvhBuilder, layout: NodeLayout) -> Bvh {
        Self::build_as(scene, builder, Some(layout))
    }

    fn build_as(scene: &Scene, builder: BvhBuilder, layout: Option<NodeLayout>) -> Bvh {
        let mut build_prims: Vec<BuildPrim> = hittable_prims_as(scene, BuildPrim::new);
        let binary = match builder {
            BvhBuilder::Sah => build_nodes(&SahBinnedBuilder::default(), &mut build_prims),
            BvhBuilder::Midpoint => build_nodes(&MidpointBuilder::default(), &mut build_prims),
        };
        let order: Vec<PrimId> = build_prims.par_iter().map(|p| p.id).collect();
        drop(build_prims);
        let (nodes, blocks, root) = match layout.unwrap_or(NodeLayout::for_prims(order.len())) {
            NodeLayout::Quantized => {
                let tree = collapse::<QuantizedNode>(&binary, scene, &order);
                (Nodes::Quantized(tree.nodes), tree.blocks, tree.root)
            }
            NodeLayout::Float => {
                let tree = collapse::<FloatNode>(&binary, scene, &order);
                (Nodes::Float(tree.nodes), tree.blocks, tree.root)
            }
        };
        let root_bounds = binary.first().map(|n| n.bounds());
        let mut bvh = Bvh {
            nodes,
            blocks,
            spheres: SphereStore::new(scene),
            root,
            builder,
            stats: BvhStats::default(),
        };
        let root_area = root_bounds.map_or(0.0, |b| b.surface_area());
        bvh.stats = match &bvh.nodes {
            Nodes::Float(nodes) => bvh.tree_stats(nodes, root_area),
            Nodes::Quantized(nodes) => bvh.tree_stats(nodes, root_area),
        };
        bvh
    }

    pub fn stats(&self) -> BvhStats {
        self.stats
    }

    fn tree_stats<N: WideNode>(&self, nodes: &[N], root_area: f32) -> BvhStats {
        let mut stats = BvhStats {
            width: WIDTH,
            quantized: matches!(self.nodes, Nodes::Quantized(_)),
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
            let node = &nodes[r.index() as usize];
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
        let nodes = match &self.nodes {
            Nodes::Float(n) => n.capacity() * std::mem::size_of::<FloatNode>(),
            Nodes::Quantized(n) => n.capacity() * std::mem::size_of::<QuantizedNode>(),
        };
        std::mem::size_of::<Self>()
            + nodes
            + self.blocks.capacity() * std::mem::size_of::<TriBlock>()
            + self.spheres.memory_bytes()
    }
}
