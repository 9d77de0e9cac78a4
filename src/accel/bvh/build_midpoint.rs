//! The course's split: the midpoint of the centroid bounds along their longest axis.

use super::build::{median_split, partition_bounded, BuildPrim, NodeBounds, Split, SplitRule};

#[derive(Clone, Copy, Debug)]
pub(crate) struct MidpointBuilder {
    /// The course's default `max_leaf_size`.
    pub max_leaf: usize,
}

impl Default for MidpointBuilder {
    fn default() -> Self {
        MidpointBuilder { max_leaf: 4 }
    }
}

impl SplitRule for MidpointBuilder {
    fn max_leaf(&self) -> usize {
        self.max_leaf
    }

    fn split(&self, prims: &mut [BuildPrim], node: &NodeBounds) -> Option<Split> {
        if prims.len() <= self.max_leaf {
            return None;
        }
        let cb = node.centroids;
        let axis = cb.max_axis();
        let extent = cb.max[axis] - cb.min[axis];
        if extent.is_nan() || extent <= 0.0 {
            // All centroids equal: nothing separates them; the skeleton halves the node.
            return None;
        }
        let mid_value = 0.5 * (cb.min[axis] + cb.max[axis]);
        let (mid, children) = partition_bounded(prims, |p| p.centroid_on(axis) < mid_value);
        if mid == 0 || mid == prims.len() {
            // Bounds one float apart: the midpoint rounds onto an end.
            return Some(median_split(prims, &cb));
        }
        Some(Split {
            axis,
            mid,
            children: Some(children),
        })
    }
}
