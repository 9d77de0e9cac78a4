//! Binned surface-area-heuristic splits (Wald 2007): centroids are binned along
//! each axis and the cheapest of the bin boundaries is taken, or a leaf when
//! that is cheaper still.

use super::build::{centroid_bounds, partition, reduce_chunks, BuildPrim, Split, SplitRule};
use crate::geometry::Aabb;

pub(crate) const BINS: usize = 32;

/// Cost model constants, relative: one node visit against one primitive test.
/// With pair nodes (both child boxes tested at once, popped nodes never
/// re-tested) a visit is cheap, and small leaves win: 0.8 took 8% fewer
/// instructions on CBbunny and 17% fewer on CBspheres_lambertian than 0.4
/// (the value tuned for the old one-box-per-visit traversal); 1.0 and 1.5 were
/// no better.
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

    fn area_count(&self) -> f32 {
        self.bounds.surface_area() * self.count as f32
    }
}

/// Maps a centroid coordinate to its bin; used for costing and for partitioning
/// so both see the same bins.
#[derive(Clone, Copy)]
struct Binning {
    axis: usize,
    min: f32,
    scale: f32,
}

impl Binning {
    #[inline]
    fn bin(&self, p: &BuildPrim) -> usize {
        // `as usize` saturates (NaN → 0), so odd input cannot index out of range.
        (((p.centroid[self.axis] - self.min) * self.scale) as usize).min(BINS - 1)
    }
}

impl SplitRule for SahBinnedBuilder {
    fn max_leaf(&self) -> usize {
        self.max_leaf
    }

    fn split(&self, prims: &mut [BuildPrim], bounds: &Aabb) -> Option<Split> {
        let cb = centroid_bounds(prims);
        let mut best: Option<(f32, Binning, usize)> = None;
        for axis in 0..3 {
            let extent = cb.max[axis] - cb.min[axis];
            if extent.is_nan() || extent <= 0.0 {
                continue;
            }
            let binning = Binning {
                axis,
                min: cb.min[axis],
                scale: BINS as f32 / extent,
            };
            if let Some((cost, boundary)) = best_boundary(prims, binning) {
                if best.is_none_or(|(c, _, _)| cost < c) {
                    best = Some((cost, binning, boundary));
                }
            }
        }
        let (cost, binning, boundary) = best?;
        // Relative to the parent's area; the traversal step into this node is paid either way.
        let split_cost = TRAVERSAL_COST + cost / bounds.surface_area();
        let leaf_cost = INTERSECTION_COST * prims.len() as f32;
        if prims.len() <= self.max_leaf && leaf_cost <= split_cost {
            return None;
        }
        let mid = partition(prims, |p| binning.bin(p) < boundary);
        Some(Split {
            axis: binning.axis,
            mid,
        })
    }
}

fn fill_bins(prims: &[BuildPrim], binning: Binning) -> [Bin; BINS] {
    let mut bins = [Bin::EMPTY; BINS];
    for p in prims {
        let b = &mut bins[binning.bin(p)];
        b.bounds = b.bounds.union(&p.bounds);
        b.count += 1;
    }
    bins
}

fn merge_bins(mut a: [Bin; BINS], b: [Bin; BINS]) -> [Bin; BINS] {
    for (x, y) in a.iter_mut().zip(&b) {
        *x = x.union(y);
    }
    a
}

/// Cheapest boundary `k` (bins `< k` go left) as `(Σ area·count·C_isect, k)`.
fn best_boundary(prims: &[BuildPrim], binning: Binning) -> Option<(f32, usize)> {
    let bins = reduce_chunks(prims, |c| fill_bins(c, binning), merge_bins);
    // right[k]: the union of bins k.. (k ≥ 1).
    let mut right = [Bin::EMPTY; BINS];
    let mut acc = Bin::EMPTY;
    for k in (1..BINS).rev() {
        acc = acc.union(&bins[k]);
        right[k] = acc;
    }
    let mut left = Bin::EMPTY;
    let mut best: Option<(f32, usize)> = None;
    for k in 1..BINS {
        left = left.union(&bins[k - 1]);
        if left.count == 0 || right[k].count == 0 {
            continue;
        }
        let cost = INTERSECTION_COST * (left.area_count() + right[k].area_count());
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
            axis: 1,
            min: -1.0,
            scale: BINS as f32 / 2.0,
        };
        let serial = fill_bins(&prims, binning);
        for threads in [1, 3] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let bins =
                pool.install(|| reduce_chunks(&prims, |c| fill_bins(c, binning), merge_bins));
            for (p, s) in bins.iter().zip(&serial) {
                assert_eq!(p.count, s.count);
                assert_eq!(p.bounds, s.bounds);
            }
        }
        assert_eq!(serial.iter().map(|b| b.count).sum::<u32>(), 50_000);
    }
}
