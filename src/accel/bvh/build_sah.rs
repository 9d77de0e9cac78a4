//! Binned surface-area-heuristic splits (Wald 2007): one pass over a node's
//! primitives bins their centroids on all three axes, and the cheapest of the bin
//! boundaries is taken, or a leaf when that is cheaper still. Leaves are tested a
//! block of four primitives at a time, so the cost counts blocks, not primitives.

use super::build::{centroid_bounds, partition, reduce_chunks, BuildPrim, Split, SplitRule};
use crate::geometry::Aabb;

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

#[derive(Clone, Copy)]
struct Bin {
    bounds: Aabb,
    count: u32,
}

impl Bin {
    const EMPTY: Bin = Bin {
        bounds: Aabb::EMPTY,
        count: 0,
    };

    fn union(&self, o: &Bin) -> Bin {
        Bin {
            bounds: self.bounds.union(&o.bounds),
            count: self.count + o.count,
        }
    }

    fn area_blocks(&self) -> f32 {
        self.bounds.surface_area() * blocks(self.count)
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

type Bins = [[Bin; BINS]; 3];

impl SplitRule for SahBinnedBuilder {
    fn max_leaf(&self) -> usize {
        self.max_leaf
    }

    fn split(&self, prims: &mut [BuildPrim], bounds: &Aabb) -> Option<Split> {
        let leaf_cost = INTERSECTION_COST * blocks(prims.len() as u32);
        if prims.len() <= 4 {
            // One block: no split can cost less than the leaf's single block test.
            return None;
        }
        let cb = centroid_bounds(prims);
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
        // One pass over the primitives fills the bins of all three axes.
        let bins = reduce_chunks(prims, |c| fill_bins(c, binning), merge_bins);
        let mut best: Option<(f32, usize, usize)> = None;
        for (axis, axis_bins) in bins.iter().enumerate() {
            if binning.scale[axis] == 0.0 {
                continue;
            }
            if let Some((cost, boundary)) = best_boundary(&axis_bins[..count]) {
                if best.is_none_or(|(c, _, _)| cost < c) {
                    best = Some((cost, axis, boundary));
                }
            }
        }
        let (cost, axis, boundary) = best?;
        // Relative to the parent's area; the traversal step into this node is paid either way.
        let split_cost = TRAVERSAL_COST + cost / bounds.surface_area();
        if prims.len() <= self.max_leaf && leaf_cost <= split_cost {
            return None;
        }
        let mid = partition(prims, |p| binning.bin(p, axis) < boundary);
        Some(Split { axis, mid })
    }
}

fn fill_bins(prims: &[BuildPrim], binning: Binning) -> Bins {
    let mut bins = [[Bin::EMPTY; BINS]; 3];
    for p in prims {
        for (axis, axis_bins) in bins.iter_mut().enumerate() {
            let b = &mut axis_bins[binning.bin(p, axis)];
            b.bounds = b.bounds.union(&p.bounds);
            b.count += 1;
        }
    }
    bins
}

fn merge_bins(mut a: Bins, b: Bins) -> Bins {
    for (xa, ya) in a.iter_mut().zip(&b) {
        for (x, y) in xa.iter_mut().zip(ya) {
            *x = x.union(y);
        }
    }
    a
}

/// Cheapest boundary `k` (bins `< k` go left) as `(Σ area·blocks·C_isect, k)`.
fn best_boundary(bins: &[Bin]) -> Option<(f32, usize)> {
    // right[k]: the union of bins k.. (k ≥ 1).
    let mut right = [Bin::EMPTY; BINS];
    let mut acc = Bin::EMPTY;
    for k in (1..bins.len()).rev() {
        acc = acc.union(&bins[k]);
        right[k] = acc;
    }
    let mut left = Bin::EMPTY;
    let mut best: Option<(f32, usize)> = None;
    for k in 1..bins.len() {
        left = left.union(&bins[k - 1]);
        if left.count == 0 || right[k].count == 0 {
            continue;
        }
        let cost = INTERSECTION_COST * (left.area_blocks() + right[k].area_blocks());
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
        let serial = fill_bins(&prims, binning);
        for threads in [1, 3] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let bins =
                pool.install(|| reduce_chunks(&prims, |c| fill_bins(c, binning), merge_bins));
            for (p, s) in bins.iter().flatten().zip(serial.iter().flatten()) {
                assert_eq!(p.count, s.count);
                assert_eq!(p.bounds, s.bounds);
            }
        }
        for axis_bins in &serial {
            assert_eq!(axis_bins.iter().map(|b| b.count).sum::<u32>(), 50_000);
        }
    }
}
