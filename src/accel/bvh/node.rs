//! The builder's 32-byte binary BVH node. Traversal never reads it: after the build
//! the binary tree is collapsed into wide nodes (`wide.rs`) and dropped.

use crate::geometry::Aabb;
use glam::Vec3;

/// A node of the builder's flat, depth-first node array. The first child of an inner
/// node is the next node; `offset` names the second. `offset` and `count_axis` fill
/// the fourth lane after `min` and `max`, so a node is 32 bytes, two to a cache line
/// while `collapse` walks the tree.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C, align(32))]
pub(crate) struct BvhNode {
    pub min: [f32; 3],
    /// Leaf: first primitive slot. Inner: index of the second child.
    pub offset: u32,
    pub max: [f32; 3],
    /// `count << 2 | split_axis`; a count of 0 marks an inner node.
    count_axis: u32,
}

const _: () = assert!(std::mem::size_of::<BvhNode>() == 32);

impl BvhNode {
    pub fn leaf(bounds: &Aabb, first: u32, count: u32) -> Self {
        debug_assert!(count > 0 && count < 1 << 30);
        BvhNode {
            min: bounds.min.to_array(),
            offset: first,
            max: bounds.max.to_array(),
            count_axis: count << 2,
        }
    }

    pub fn inner(bounds: &Aabb, second_child: u32, axis: usize) -> Self {
        BvhNode {
            min: bounds.min.to_array(),
            offset: second_child,
            max: bounds.max.to_array(),
            count_axis: axis as u32 & 3,
        }
    }

    /// Number of primitives; 0 for an inner node.
    #[inline(always)]
    pub fn count(&self) -> u32 {
        self.count_axis >> 2
    }

    /// The split axis (traversal orders children by entry distance instead).
    #[cfg(test)]
    pub fn axis(&self) -> usize {
        (self.count_axis & 3) as usize
    }

    pub fn bounds(&self) -> Aabb {
        Aabb::new(Vec3::from_array(self.min), Vec3::from_array(self.max))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit_node() -> BvhNode {
        BvhNode::leaf(&Aabb::new(Vec3::ZERO, Vec3::ONE), 7, 3)
    }

    #[test]
    fn encodes_leaf_and_inner() {
        let n = unit_node();
        assert_eq!((n.count(), n.offset), (3, 7));
        let i = BvhNode::inner(&n.bounds(), 42, 2);
        assert_eq!((i.count(), i.offset, i.axis()), (0, 42, 2));
    }
}
