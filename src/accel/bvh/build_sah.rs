//! Binned surface-area-heuristic splits (Wald 2007): one pass over a node's
//! primitives bins their centroids on all three axes, and the cheapest of the bin
//! boundaries is taken, or a leaf when that is cheaper still. Leaves are tested a
//! block of four primitives at a time, so the cost counts blocks, not primitives.

use super::build::{partition_bounded, reduce_chunks, BuildPrim, NodeBounds, Split, SplitRule};
use crate::geometry::Aabb;
use glam::Vec3A;

pub(crate) const BINS: usize = 32;

/// Cost model constants, relative: one node visit against one leaf block test.
/// Tuned for the earlier pair-node traversal (both child boxes tested at once,
/// popped nodes never re-tested), where a visit is cheap and small leaves win: 0.8
/// took 8% fewer instructions on CBbunny and 17% fewer on CBspheres_lambertian than
/// 0.4 (the value of the one-box-per-visit traversal before it); 1.0 and 1.5 were no
/// better. Not re-tuned since the binary tree is collapsed into wide nodes (`wide.rs`).
pub(crate) const TRAVERSAL_COST: f32 = 1.0;
pub(crate) const INTERSECTION_COST: f32 = 0.8;

#[derive(Clone, Copy, Debug)]
pub(crate) struct SahBinnedBuilder {
    pub max_leaf: usize,
}

impl Default for SahBinnedBuilder {
    fn default() -> Self {
        SahBinnedBuilder { max_leaf: 4 }
    }
}

/// A bin's box in SIMD registers (`Vec3A`; the same min/max as `Aabb::union` on
/// finite input, which is all a build sees) and its primitive count.
#[derive(Clone, Copy)]
struct Bin {
    min: Vec3A,
    max: Vec3A,
    count: u32,
}

impl Bin {
    const EMPTY: Bin = Bin {
        min: Vec3A::splat(f32::INFINITY),
        max: Vec3A::splat(f32::NEG_INFINITY),
        count: 0,
    };

    #[inline(always)]
    fn union(&self, o: &Bin) -> Bin {
        Bin {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
            count: self.count + o.count,
        }
    }

    fn area_blocks(&self) -> f32 {
        Aabb::new(self.min.into(), self.max.into()).surface_area() * blocks(self.count)
    }
}

/// Leaves are tested four primitives at a time, so a leaf's cost counts blocks.
#[inline]
fn blocks(count: u32) -> f32 {
    count.div_ceil(4) as f32
}

/// Maps centroid coordinates to bins on all three axes; used for costing and for
/// partitioning so both see the same bins.
#[derive(Clone, Copy)]
struct Binning {
    min: [f32; 3],
    scale: [f32; 3],
    /// Bins in use (`≤ BINS`): small nodes use fewer, which costs them little
    /// quality and saves most of their per-node work.
    count: usize,
}

impl Binning {
    #[inline]
    fn bin(&self, p: &BuildPrim, axis: usize) -> usize {
        // `as usize` saturates (NaN → 0), so odd input cannot index out of range.
        (((p.centroid_on(axis) - self.min[axis]) * self.scale[axis]) as usize).min(self.count - 1)
    }
}

/// The bins of all three axes, `N ≥ Binning::count` of them per axis (those past
/// `count` stay empty): small nodes, which are most nodes, get small arrays, as
/// clearing 3·32 bins would cost more than binning their few primitives.
type Bins<const N: usize> = [[Bin; N]; 3];

impl SplitRule for SahBinnedBuilder {
    fn max_leaf(&self) -> usize {
        self.max_leaf
    }

    fn split(&self, prims: &mut [BuildPrim], node: &NodeBounds) -> Option<Split> {
        let leaf_cost = INTERSECTION_COST * blocks(prims.len() as u32);
        if prims.len() <= 4 {
            // One block: no split can cost less than the leaf's single block test.
            return None;
        }
        let (bounds, cb) = (&node.bounds, node.centroids);
        let extent = cb.max - cb.min;
        let count = (prims.len() / 2).clamp(8, BINS);
        let binning = Binning {
            min: cb.min.to_array(),
            scale: [0, 1, 2].map(|a| {
                if extent[a] > 0.0 {
                    count as f32 / extent[a]
                } else {
                    0.0
                }
            }),
            count,
        };
        let (cost, axis, boundary) = match count {
            ..=8 => best_split::<8>(prims, binning),
            9..=16 => best_split::<16>(prims, binning),
            _ => best_split::<BINS>(prims, binning),
        }?;
        // Relative to the parent's area; the traversal step into this node is paid either way.
        let split_cost = TRAVERSAL_COST + cost / bounds.surface_area();
        if prims.len() <= self.max_leaf && leaf_cost <= split_cost {
            return None;
        }
        let (mid, children) = partition_bounded(prims, |p| binning.bin(p, axis) < boundary);
        Some(Split {
            axis,
            mid,
            children: Some(children),
        })
    }
}

/// The cheapest bin boundary over the three axes, as `(cost, axis, boundary)`.
fn best_split<const N: usize>(
    prims: &[BuildPrim],
    binning: Binning,
) -> Option<(f32, usize, usize)> {
    // One pass over the primitives fills the bins of all three axes.
    let bins = reduce_chunks(prims, |c| fill_bins::<N>(c, binning), merge_bins);
    let mut best: Option<(f32, usize, usize)> = None;
    for (axis, axis_bins) in bins.iter().enumerate() {
        if binning.scale[axis] == 0.0 {
            continue;
        }
        if let Some((cost, boundary)) = best_boundary(&axis_bins[..binning.count]) {
            if best.is_none_or(|(c, _, _)| cost < c) {
                best = Some((cost, axis, boundary));
            }
        }
    }
    best
}

/// Bins every primitive on all three axes. The bin indices are computed for the
/// three axes at once with the same operations as [`Binning::bin`] (lane by lane,
/// the same bits), so partitioning sees the same bins.
fn fill_bins<const N: usize>(prims: &[BuildPrim], binning: Binning) -> Bins<N> {
    let mut bins = [[Bin::EMPTY; N]; 3];
    let origin = Vec3A::from_array(binning.min);
    let scale = Vec3A::from_array(binning.scale);
    let last = binning.count - 1;
    for p in prims {
        let (lo, hi) = (Vec3A::from(p.bounds.min), Vec3A::from(p.bounds.max));
        let k = ((lo + hi) * 0.5 - origin) * scale;
        for (axis, axis_bins) in bins.iter_mut().enumerate() {
            // `as usize` saturates (NaN → 0), as in `Binning::bin`.
            let b = &mut axis_bins[(k[axis] as usize).min(last)];
            b.min = b.min.min(lo);
            b.max = b.max.max(hi);
            b.count += 1;
        }
    }
    bins
}

fn merge_bins<const N: usize>(mut a: Bins<N>, b: Bins<N>) -> Bins<N> {
    for (xa, ya) in a.iter_mut().zip(&b) {
        for (x, y) in xa.iter_mut().zip(ya) {
            *x = x.union(y);
        }
    }
    a
}

/// Cheapest boundary `k` (bins `< k` go left) as `(Σ area·blocks·C_isect, k)`.
fn best_boundary(bins: &[Bin]) -> Option<(f32, usize)> {
    // right[k]: count and area·blocks of the union of bins k.. (k ≥ 1).
    let mut right = [(0u32, 0.0f32); BINS];
    let mut acc = Bin::EMPTY;
    for k in (1..bins.len()).rev() {
        acc = acc.union(&bins[k]);
        right[k] = (acc.count, acc.area_blocks());
    }
    let mut left = Bin::EMPTY;
    let mut best: Option<(f32, usize)> = None;
    for k in 1..bins.len() {
        left = left.union(&bins[k - 1]);
        let (right_count, right_cost) = right[k];
        if left.count == 0 || right_count == 0 {
            continue;
        }
        let cost = INTERSECTION_COST * (left.area_blocks() + right_cost);
        if best.is_none_or(|(c, _)| cost < c) {
            best = Some((cost, k));
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Sampler;
    use glam::Vec3;

    #[test]
    fn parallel_binning_matches_serial_at_any_thread_count() {
        let mut rng = Sampler::from_seed(3);
        let mut point = || Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0 - 1.0;
        let prims: Vec<BuildPrim> = (0..50_000)
            .map(|id| {
                let (a, b) = (point(), point() * 0.01);
                BuildPrim::new(
                    id,
                    Aabb::EMPTY.union(&Aabb {
                        min: a,
                        max: a + b.abs(),
                    }),
                )
            })
            .collect();
        let binning = Binning {
            min: [-1.0; 3],
            scale: [BINS as f32 / 2.0; 3],
            count: BINS,
        };
        let serial = fill_bins::<BINS>(&prims, binning);
        for threads in [1, 3] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let bins = pool
                .install(|| reduce_chunks(&prims, |c| fill_bins::<BINS>(c, binning), merge_bins));
            for (p, s) in bins.iter().flatten().zip(serial.iter().flatten()) {
                assert_eq!(p.count, s.count);
                assert_eq!((p.min, p.max), (s.min, s.max));
            }
        }
        // The SIMD bin indices are `Binning::bin`'s.
        for p in prims.iter().take(2000) {
            for (axis, axis_bins) in fill_bins::<BINS>(std::slice::from_ref(p), binning)
                .iter()
                .enumerate()
            {
                assert_eq!(axis_bins[binning.bin(p, axis)].count, 1);
            }
        }
        for axis_bins in &serial {
            assert_eq!(axis_bins.iter().map(|b| b.count).sum::<u32>(), 50_000);
        }
    }
}
