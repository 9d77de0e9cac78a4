//! Collapse of the builder's binary tree into the wide traversal layout: each
//! binary leaf (at most 4 primitives) becomes one [`TriBlock`].
//!
//! The top wide levels convert their subtrees in parallel, each into its own
//! [`WideTree`] appended in slot order with its indices shifted, so the layout
//! is exactly the serial depth-first one whatever the thread count.

use super::node::BvhNode;
use super::wide::{ChildRef, WideNode, WIDTH};
use crate::accel::prims::TriBlock;
use crate::scene::Scene;
use rayon::prelude::*;

/// Wide levels above this depth convert their inner children in parallel
/// (at most `WIDTH³` tasks).
const PARALLEL_DEPTH: u32 = 3;

/// The collapsed tree: nodes (root at 0 unless the root is a leaf), leaf blocks,
/// and the reference traversal starts from.
pub(crate) struct WideTree {
    pub nodes: Vec<WideNode>,
    pub blocks: Vec<TriBlock>,
    pub root: ChildRef,
}

/// What every step of the collapse reads.
#[derive(Clone, Copy)]
struct Source<'a> {
    nodes: &'a [BvhNode],
    scene: &'a Scene,
    /// `order[slot]` is the primitive id in leaf slot `slot`.
    order: &'a [u32],
}

/// Collapses the builder's depth-first binary nodes into wide nodes: each wide
/// node takes a binary node's children and keeps opening its largest inner child
/// (by surface area) until it has [`WIDTH`] children. `order[slot]` is the
/// primitive id in leaf slot `slot`.
pub(crate) fn collapse(nodes: &[BvhNode], scene: &Scene, order: &[u32]) -> WideTree {
    // Guesses from the primitive count: leaves hold about 3.8 primitives on
    // meshes, wide nodes about 4 children.
    let mut tree = WideTree {
        nodes: Vec::with_capacity(order.len() / 8 + 1),
        blocks: Vec::with_capacity(order.len() / 3 + 1),
        root: ChildRef::default(),
    };
    let Some(root) = nodes.first() else {
        return tree;
    };
    let src = Source {
        nodes,
        scene,
        order,
    };
    tree.root = if root.count() > 0 {
        leaf_ref(root, src, &mut tree.blocks)
    } else {
        ChildRef {
            index: convert(src, 0, 0, &mut tree),
            count: 0,
        }
    };
    tree
}

fn leaf_ref(leaf: &BvhNode, src: Source, blocks: &mut Vec<TriBlock>) -> ChildRef {
    let (first, count) = (leaf.offset as usize, leaf.count() as usize);
    debug_assert!(count <= 4, "leaves hold at most one block");
    blocks.push(TriBlock::new(src.scene, &src.order[first..first + count]));
    ChildRef {
        index: (blocks.len() - 1) as u32,
        count: count as u32,
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
fn convert(src: Source, i: usize, depth: u32, tree: &mut WideTree) -> u32 {
    let (kids, len) = wide_children(src.nodes, i);
    let kids = &kids[..len];
    let me = tree.nodes.len();
    tree.nodes.push(WideNode::default());
    let mut node = WideNode::default();
    for (slot, &k) in kids.iter().enumerate() {
        let child = &src.nodes[k];
        for axis in 0..3 {
            node.lo[axis][slot] = child.min[axis];
            node.hi[axis][slot] = child.max[axis];
        }
    }
    if depth < PARALLEL_DEPTH {
        let subtrees: Vec<Option<WideTree>> = kids
            .par_iter()
            .map(|&k| (src.nodes[k].count() == 0).then(|| subtree(src, k, depth + 1)))
            .collect();
        for (slot, (&k, sub)) in kids.iter().zip(subtrees).enumerate() {
            node.children[slot] = match sub {
                Some(sub) => append_shifted(tree, sub),
                None => leaf_ref(&src.nodes[k], src, &mut tree.blocks),
            };
        }
    } else {
        for (slot, &k) in kids.iter().enumerate() {
            let child = &src.nodes[k];
            node.children[slot] = if child.count() > 0 {
                leaf_ref(child, src, &mut tree.blocks)
            } else {
                ChildRef {
                    index: convert(src, k, depth + 1, tree),
                    count: 0,
                }
            };
        }
    }
    tree.nodes[me] = node;
    me as u32
}

/// Inner node `i` and its descendants as a tree of their own (indices from 0).
fn subtree(src: Source, i: usize, depth: u32) -> WideTree {
    let mut tree = WideTree {
        nodes: Vec::new(),
        blocks: Vec::new(),
        root: ChildRef::default(),
    };
    convert(src, i, depth, &mut tree);
    tree
}

/// Appends `sub` (converted on its own) to `tree`, shifting its node and block
/// indices; returns the reference to its root.
fn append_shifted(tree: &mut WideTree, sub: WideTree) -> ChildRef {
    let node_shift = tree.nodes.len() as u32;
    let block_shift = tree.blocks.len() as u32;
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
    tree.blocks.extend(sub.blocks);
    ChildRef {
        index: node_shift,
        count: 0,
    }
}
