//! Collapse of the builder's binary tree into the wide traversal layout.
//!
//! Which binary nodes become wide nodes, which become leaves and which are
//! skipped (their children moved up into the parent's slots) is chosen by the
//! SAH-optimal collapse of Ylitie, Karras and Laine (2017): bottom up, every
//! binary node gets the cheapest cost of its subtree when it takes 1, 2, …,
//! [`WIDTH`] slots of its wide parent. A subtree of at most four primitives may
//! also become one leaf block. Greedy opening of the largest child, the earlier
//! rule, left many wide nodes at the bottom with two or three children (4.3 on
//! average on the 1M-triangle mesh; 78.7k nodes where this makes 52k).
//!
//! The plan is computed over subtrees in parallel; the top wide levels convert
//! their subtrees in parallel, each into its own [`Shape`] appended in slot
//! order with its indices shifted, so the layout is exactly the serial
//! depth-first one whatever the thread count; the leaf blocks are then made in
//! parallel, in that order.

use super::build_sah::{INTERSECTION_COST, TRAVERSAL_COST};
use super::huge_pages;
use super::node::BvhNode;
use super::wide::{ChildRef, WideNode, WIDTH};
use crate::accel::prims::TriBlock;
use crate::geometry::Aabb;
use crate::scene::Scene;
use rayon::prelude::*;

/// Wide levels above this depth convert their inner children in parallel
/// (at most `WIDTH²` tasks).
const PARALLEL_DEPTH: u32 = 2;

/// Subtrees of more binary nodes than this are planned in parallel.
const PARALLEL_PLAN: usize = 8192;

/// The most primitives a leaf holds: one block.
const BLOCK: u32 = 4;

/// The collapsed tree: nodes (root at 0 unless the root is a leaf), leaf blocks,
/// and the reference traversal starts from.
pub(crate) struct WideTree {
    pub nodes: Vec<WideNode>,
    pub blocks: Vec<TriBlock>,
    pub root: ChildRef,
}

/// The wide tree before its leaf blocks are made: each leaf as the range
/// `(first, count)` of primitive slots its block will hold. Blocks are much
/// bigger; they are made afterwards in parallel, straight into their vector.
#[derive(Default)]
struct Shape {
    nodes: Vec<WideNode>,
    leaves: Vec<(u32, u32)>,
}

/// Collapses the builder's depth-first binary nodes into wide nodes.
/// `order[slot]` is the primitive id in leaf slot `slot`.
pub(crate) fn collapse(nodes: &[BvhNode], scene: &Scene, order: &[u32]) -> WideTree {
    if nodes.is_empty() {
        return WideTree {
            nodes: Vec::new(),
            blocks: Vec::new(),
            root: ChildRef::default(),
        };
    }
    let mut plan = vec![Plan::default(); nodes.len()];
    plan_subtree(nodes, 0, &mut plan);
    let tree = Collapse { nodes, plan: &plan };
    let mut shape = Shape::default();
    let root = tree.child(0, 0, &mut shape);
    let mut blocks = huge_pages::huge_page_vec(shape.leaves.len());
    TriBlock::make_all(scene, &shape.leaves, order, &mut blocks);
    let nodes = huge_pages::on_huge_pages(&shape.nodes);
    WideTree {
        nodes,
        blocks,
        root,
    }
}

/// What the collapse does with one binary node.
#[derive(Clone, Copy, Default)]
struct Plan {
    /// Entry `j` says how the node fills `j + 1` slots at least cost: 0 when
    /// `j` slots do as well; otherwise the slots given to its first child. For
    /// `j = 0` (one slot): 0 for a leaf, 1 for a wide node.
    split: [u8; WIDTH],
    /// The slots given to the first child when the node is a wide node.
    node_split: u8,
    /// Primitives below the node, saturated (only "at most a block" matters).
    prims: u8,
}

/// `cost[j]`: the least SAH cost (unnormalised: areas, not probabilities) of a
/// subtree that fills at most `j + 1` slots of its parent.
type Costs = [f32; WIDTH];

/// A planned subtree: its costs, and how many slots it can fill at most (its
/// binary leaves, at most [`WIDTH`]); more slots cost what that many do.
struct Planned {
    costs: Costs,
    slots: usize,
}

/// Plans binary node `i` and its subtree, whose plans are `plan` (the subtree's
/// nodes are the contiguous range starting at `i`).
fn plan_subtree(nodes: &[BvhNode], i: usize, plan: &mut [Plan]) -> Planned {
    let node = &nodes[i];
    let area = node.bounds().surface_area();
    if node.count() > 0 {
        plan[0] = Plan {
            prims: node.count() as u8,
            ..Plan::default()
        };
        return Planned {
            costs: [area * INTERSECTION_COST; WIDTH],
            slots: 1,
        };
    }
    let [first, second] = children_of(nodes, i);
    let parallel = plan.len() > PARALLEL_PLAN;
    let (own, below) = plan.split_at_mut(1);
    let (first_plan, second_plan) = below.split_at_mut(second - first);
    let (a, b) = if parallel {
        rayon::join(
            || plan_subtree(nodes, first, first_plan),
            || plan_subtree(nodes, second, second_plan),
        )
    } else {
        (
            plan_subtree(nodes, first, first_plan),
            plan_subtree(nodes, second, second_plan),
        )
    };
    let prims = first_plan[0].prims.saturating_add(second_plan[0].prims);
    let (p, planned) = plan_node(area, prims, &a, &b);
    own[0] = p;
    planned
}

/// The plan of an inner node of surface area `area` over `prims` primitives,
/// whose children are `a` and `b`.
fn plan_node(area: f32, prims: u8, a: &Planned, b: &Planned) -> (Plan, Planned) {
    let slots = (a.slots + b.slots).min(WIDTH);
    // shared[j], with the slots of the first child: j + 1 slots split between
    // both, each child given no more than it can fill.
    let mut shared = [(f32::INFINITY, 0u8); WIDTH];
    for (j, slot) in shared.iter_mut().enumerate().take(slots).skip(1) {
        // The best so far in locals: through the array, each update waited on the last.
        let mut best = (f32::INFINITY, 0u8);
        for k in j.saturating_sub(b.slots)..j.min(a.slots) {
            let cost = a.costs[k] + b.costs[j - 1 - k];
            // The first split counts even at an infinite or NaN cost, so a split
            // is always chosen.
            if cost < best.0 || best.1 == 0 {
                best = (cost, k as u8 + 1);
            }
        }
        *slot = best;
    }
    let full = shared[slots - 1];
    let mut plan = Plan {
        node_split: full.1,
        prims,
        ..Plan::default()
    };
    let mut costs = [0.0; WIDTH];
    let wide_node = area * TRAVERSAL_COST + full.0;
    let leaf = if u32::from(prims) <= BLOCK {
        area * INTERSECTION_COST
    } else {
        f32::INFINITY
    };
    costs[0] = wide_node.min(leaf);
    // More than a block's primitives is always a wide node, whatever the costs say
    // (they are infinite where areas overflow).
    plan.split[0] = u8::from(u32::from(prims) > BLOCK || leaf > wide_node);
    for j in 1..slots {
        if shared[j].0 < costs[j - 1] {
            costs[j] = shared[j].0;
            plan.split[j] = shared[j].1;
        } else {
            costs[j] = costs[j - 1];
        }
    }
    // More slots than the subtree can fill cost what it costs in all it can.
    let filled = costs[slots - 1];
    costs[slots..].fill(filled);
    (plan, Planned { costs, slots })
}

fn children_of(nodes: &[BvhNode], i: usize) -> [usize; 2] {
    [i + 1, nodes[i].offset as usize]
}

/// The binary tree and its plan, converted top down.
struct Collapse<'a> {
    nodes: &'a [BvhNode],
    plan: &'a [Plan],
}

/// Up to [`WIDTH`] binary nodes that fill the slots of one wide node.
struct Slots {
    nodes: [usize; WIDTH],
    len: usize,
}

impl Collapse<'_> {
    /// The reference to binary node `m` as one slot at wide depth `depth`: a leaf
    /// or a wide node, converted with its descendants into `shape`.
    fn child(&self, m: usize, depth: u32, shape: &mut Shape) -> ChildRef {
        if self.is_leaf(m) {
            self.leaf(m, &mut shape.leaves)
        } else {
            ChildRef::node(self.convert(m, depth, shape))
        }
    }

    /// The leaf holding every primitive under `m` (a contiguous range of slots
    /// starting at its leftmost binary leaf).
    fn leaf(&self, m: usize, leaves: &mut Vec<(u32, u32)>) -> ChildRef {
        let mut first = m;
        while self.nodes[first].count() == 0 {
            first += 1;
        }
        let count = u32::from(self.plan[m].prims);
        debug_assert!(count <= BLOCK);
        leaves.push((self.nodes[first].offset, count));
        ChildRef::leaf((leaves.len() - 1) as u32, count)
    }

    /// The slots node `m` fills when given `slots` of them, appended to `out`.
    fn expand(&self, m: usize, slots: usize, out: &mut Slots) {
        let plan = &self.plan[m];
        let mut j = slots - 1;
        while j > 0 && plan.split[j] == 0 {
            j -= 1;
        }
        if j == 0 {
            out.nodes[out.len] = m;
            out.len += 1;
            return;
        }
        let k = plan.split[j] as usize;
        let [first, second] = children_of(self.nodes, m);
        self.expand(first, k, out);
        self.expand(second, j + 1 - k, out);
    }

    /// Emits binary inner node `i` as a wide node at wide depth `depth`, with its
    /// descendants; returns its index.
    fn convert(&self, i: usize, depth: u32, shape: &mut Shape) -> u32 {
        let mut slots = Slots {
            nodes: [0; WIDTH],
            len: 0,
        };
        let k = self.plan[i].node_split as usize;
        let [first, second] = children_of(self.nodes, i);
        self.expand(first, k, &mut slots);
        self.expand(second, WIDTH - k, &mut slots);
        let kids = &slots.nodes[..slots.len];
        let me = shape.nodes.len();
        // A placeholder until the children's references are known.
        shape.nodes.push(WideNode::default());
        let mut children = [(Aabb::EMPTY, ChildRef::default()); WIDTH];
        if depth < PARALLEL_DEPTH {
            let subtrees: Vec<Shape> = kids
                .par_iter()
                .map(|&k| {
                    let mut sub = Shape::default();
                    if !self.is_leaf(k) {
                        self.convert(k, depth + 1, &mut sub);
                    }
                    sub
                })
                .collect();
            for (slot, (&k, sub)) in kids.iter().zip(subtrees).enumerate() {
                children[slot].1 = if self.is_leaf(k) {
                    self.leaf(k, &mut shape.leaves)
                } else {
                    append_shifted(shape, sub)
                };
            }
        } else {
            for (slot, &k) in kids.iter().enumerate() {
                children[slot].1 = self.child(k, depth + 1, shape);
            }
        }
        for (slot, &k) in kids.iter().enumerate() {
            children[slot].0 = self.nodes[k].bounds();
        }
        shape.nodes[me] = WideNode::new(&children[..kids.len()]);
        me as u32
    }

    /// Whether the plan makes `m`, in one slot, a leaf.
    fn is_leaf(&self, m: usize) -> bool {
        self.nodes[m].count() > 0 || self.plan[m].split[0] == 0
    }
}

/// Appends `sub` (converted on its own) to `shape`, shifting its node and block
/// indices; returns the reference to its root.
fn append_shifted(shape: &mut Shape, sub: Shape) -> ChildRef {
    let node_shift = shape.nodes.len() as u32;
    let block_shift = shape.leaves.len() as u32;
    shape.nodes.extend(sub.nodes.into_iter().map(|mut node| {
        for c in node.children_mut() {
            *c = c.shifted(if c.is_leaf() { block_shift } else { node_shift });
        }
        node
    }));
    shape.leaves.extend(sub.leaves);
    ChildRef::node(node_shift)
}
