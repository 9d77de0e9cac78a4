//! Collapse of the builder's binary tree into the wide traversal layout: each
//! binary leaf (at most 4 primitives) becomes one [`TriBlock`].

use super::node::BvhNode;
use super::wide::{ChildRef, WideNode, WIDTH};
use crate::accel::prims::TriBlock;
use crate::scene::Scene;

/// The collapsed tree: nodes (root at 0 unless the root is a leaf), leaf blocks,
/// and the reference traversal starts from.
pub(crate) struct WideTree {
    pub nodes: Vec<WideNode>,
    pub blocks: Vec<TriBlock>,
    pub root: ChildRef,
}

/// Collapses the builder's depth-first binary nodes into wide nodes: each wide
/// node takes a binary node's children and keeps opening its largest inner child
/// (by surface area) until it has [`WIDTH`] children. `order[slot]` is the
/// primitive id in leaf slot `slot`.
pub(crate) fn collapse(nodes: &[BvhNode], scene: &Scene, order: &[u32]) -> WideTree {
    let mut tree = WideTree {
        nodes: Vec::with_capacity(nodes.len() / 4 + 1),
        blocks: Vec::with_capacity(nodes.len() / 2 + 1),
        root: ChildRef::default(),
    };
    let Some(root) = nodes.first() else {
        return tree;
    };
    tree.root = if root.count() > 0 {
        leaf_ref(root, scene, order, &mut tree.blocks)
    } else {
        ChildRef {
            index: convert(nodes, 0, scene, order, &mut tree),
            count: 0,
        }
    };
    tree
}

fn leaf_ref(leaf: &BvhNode, scene: &Scene, order: &[u32], blocks: &mut Vec<TriBlock>) -> ChildRef {
    let (first, count) = (leaf.offset as usize, leaf.count() as usize);
    debug_assert!(count <= 4, "leaves hold at most one block");
    blocks.push(TriBlock::new(scene, &order[first..first + count]));
    ChildRef {
        index: (blocks.len() - 1) as u32,
        count: count as u32,
    }
}

fn children_of(nodes: &[BvhNode], i: usize) -> [usize; 2] {
    [i + 1, nodes[i].offset as usize]
}

/// Emits inner node `i` (as a wide node) and its descendants; returns its index.
fn convert(nodes: &[BvhNode], i: usize, scene: &Scene, order: &[u32], tree: &mut WideTree) -> u32 {
    let mut kids: Vec<usize> = children_of(nodes, i).to_vec();
    while kids.len() < WIDTH {
        let widest = kids
            .iter()
            .enumerate()
            .filter(|(_, &k)| nodes[k].count() == 0)
            .map(|(slot, &k)| (slot, nodes[k].bounds().surface_area()))
            .fold(None, |best: Option<(usize, f32)>, (slot, a)| match best {
                Some((_, b)) if b >= a => best,
                _ => Some((slot, a)),
            });
        let Some((slot, _)) = widest else { break };
        let [a, b] = children_of(nodes, kids[slot]);
        kids[slot] = a;
        kids.insert(slot + 1, b);
    }
    let me = tree.nodes.len();
    tree.nodes.push(WideNode::default());
    let mut node = WideNode::default();
    for (slot, &k) in kids.iter().enumerate() {
        let child = &nodes[k];
        for axis in 0..3 {
            node.lo[axis][slot] = child.min[axis];
            node.hi[axis][slot] = child.max[axis];
        }
        node.children[slot] = if child.count() > 0 {
            leaf_ref(child, scene, order, &mut tree.blocks)
        } else {
            ChildRef {
                index: convert(nodes, k, scene, order, tree),
                count: 0,
            }
        };
    }
    tree.nodes[me] = node;
    me as u32
}
