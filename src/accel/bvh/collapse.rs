//! Collapse of the builder's binary tree into the wide traversal layout: each
//! binary leaf (at most 4 primitives) becomes one [`TriBlock`].
//!
//! The top wide levels convert their subtrees in parallel, each into its own
//! [`Shape`] appended in slot order with its indices shifted, so the layout is
//! exactly the serial depth-first one whatever the thread count; the leaf
//! blocks are then made in parallel, in that order.

use super::node::BvhNode;
use super::wide::{ChildRef, WideNode, WIDTH};
use crate::accel::prims::TriBlock;
use crate::scene::Scene;
use rayon::prelude::*;

/// Wide levels above this depth convert their inner children in parallel
/// (at most `WIDTH²` tasks).
const PARALLEL_DEPTH: u32 = 2;

/// The collapsed tree: nodes (root at 0 unless the root is a leaf), leaf blocks,
/// and the reference traversal starts from.
pub(crate) struct WideTree {
    pub nodes: Vec<WideNode>,
    pub blocks: Vec<TriBlock>,
    pub root: ChildRef,
}

/// The wide tree before its leaf blocks are made: each leaf as the range
/// `(first, count)` of primitive slots its block will hold. Blocks are 20 times
/// bigger; they are made afterwards in parallel, straight into their vector.
struct Shape {
    nodes: Vec<WideNode>,
    leaves: Vec<(u32, u32)>,
}

impl Shape {
    fn new() -> Self {
        Shape {
            nodes: Vec::new(),
            leaves: Vec::new(),
        }
    }
}

/// Collapses the builder's depth-first binary nodes into wide nodes: each wide
/// node takes a binary node's children and keeps opening its largest inner child
/// (by surface area) until it has [`WIDTH`] children. `order[slot]` is the
/// primitive id in leaf slot `slot`.
pub(crate) fn collapse(nodes: &[BvhNode], scene: &Scene, order: &[u32]) -> WideTree {
    let mut shape = Shape::new();
    let Some(root) = nodes.first() else {
        return WideTree {
            nodes: Vec::new(),
            blocks: Vec::new(),
            root: ChildRef::default(),
        };
    };
    let root = if root.count() > 0 {
        leaf_ref(root, &mut shape.leaves)
    } else {
        ChildRef {
            index: convert(nodes, 0, 0, &mut shape),
            count: 0,
        }
    };
    let blocks = shape
        .leaves
        .par_iter()
        .map(|&(first, count)| {
            let (first, count) = (first as usize, count as usize);
            TriBlock::new(scene, &order[first..first + count])
        })
        .collect();
    WideTree {
        nodes: shape.nodes,
        blocks,
        root,
    }
}

fn leaf_ref(leaf: &BvhNode, leaves: &mut Vec<(u32, u32)>) -> ChildRef {
    debug_assert!(leaf.count() <= 4, "leaves hold at most one block");
    leaves.push((leaf.offset, leaf.count()));
    ChildRef {
        index: (leaves.len() - 1) as u32,
        count: leaf.count(),
    }
}

fn children_of(nodes: &[BvhNode], i: usize) -> [usize; 2] {
    [i + 1, nodes[i].offset as usize]
}

/// The binary nodes that become the children of the wide node for inner node
/// `i`, in order, and how many there are.
fn wide_children(nodes: &[BvhNode], i: usize) -> ([usize; WIDTH], usize) {
    // Each child's surface area, or -1 for a leaf (never opened), computed once.
    let area = |k: usize| {
        if nodes[k].count() == 0 {
            nodes[k].bounds().surface_area()
        } else {
            -1.0
        }
    };
    let mut kids = [0; WIDTH];
    let mut areas = [0.0f32; WIDTH];
    [kids[0], kids[1]] = children_of(nodes, i);
    [areas[0], areas[1]] = [area(kids[0]), area(kids[1])];
    let mut len = 2;
    while len < WIDTH {
        // The first of the largest inner children (areas are never NaN on finite input).
        let mut widest = None;
        for (slot, &a) in areas[..len].iter().enumerate() {
            if a >= 0.0 && widest.is_none_or(|(_, b)| a > b) {
                widest = Some((slot, a));
            }
        }
        let Some((slot, _)) = widest else { break };
        let [a, b] = children_of(nodes, kids[slot]);
        kids.copy_within(slot + 1..len, slot + 2);
        areas.copy_within(slot + 1..len, slot + 2);
        [kids[slot], kids[slot + 1]] = [a, b];
        [areas[slot], areas[slot + 1]] = [area(a), area(b)];
        len += 1;
    }
    (kids, len)
}

/// Emits inner node `i` (as a wide node at wide depth `depth`) and its
/// descendants; returns its index.
fn convert(nodes: &[BvhNode], i: usize, depth: u32, tree: &mut Shape) -> u32 {
    let (kids, len) = wide_children(nodes, i);
    let kids = &kids[..len];
    let me = tree.nodes.len();
    tree.nodes.push(WideNode::default());
    let mut node = WideNode::default();
    for (slot, &k) in kids.iter().enumerate() {
        let child = &nodes[k];
        for axis in 0..3 {
            node.lo[axis][slot] = child.min[axis];
            node.hi[axis][slot] = child.max[axis];
        }
    }
    if depth < PARALLEL_DEPTH {
        let subtrees: Vec<Option<Shape>> = kids
            .par_iter()
            .map(|&k| (nodes[k].count() == 0).then(|| subtree(nodes, k, depth + 1)))
            .collect();
        for (slot, (&k, sub)) in kids.iter().zip(subtrees).enumerate() {
            node.children[slot] = match sub {
                Some(sub) => append_shifted(tree, sub),
                None => leaf_ref(&nodes[k], &mut tree.leaves),
            };
        }
    } else {
        for (slot, &k) in kids.iter().enumerate() {
            let child = &nodes[k];
            node.children[slot] = if child.count() > 0 {
                leaf_ref(child, &mut tree.leaves)
            } else {
                ChildRef {
                    index: convert(nodes, k, depth + 1, tree),
                    count: 0,
                }
            };
        }
    }
    tree.nodes[me] = node;
    me as u32
}

/// Inner node `i` and its descendants as a tree of their own (indices from 0).
fn subtree(nodes: &[BvhNode], i: usize, depth: u32) -> Shape {
    let mut tree = Shape::new();
    convert(nodes, i, depth, &mut tree);
    tree
}

/// Appends `sub` (converted on its own) to `tree`, shifting its node and block
/// indices; returns the reference to its root.
fn append_shifted(tree: &mut Shape, sub: Shape) -> ChildRef {
    let node_shift = tree.nodes.len() as u32;
    let block_shift = tree.leaves.len() as u32;
    tree.nodes.extend(sub.nodes.into_iter().map(|mut node| {
        for c in &mut node.children {
            if c.is_leaf() {
                c.index += block_shift;
            } else if *c != ChildRef::default() {
                c.index += node_shift;
            }
        }
        node
    }));
    tree.leaves.extend(sub.leaves);
    ChildRef {
        index: node_shift,
        count: 0,
    }
}
