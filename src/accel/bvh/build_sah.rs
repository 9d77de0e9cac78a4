//! Binned surface-area-heuristic splits (Wald 2007): one pass over a node's
//! primitives bins their centroids on all three axes, and the cheapest of the bin
//! boundaries is taken, or a leaf when that is cheaper still. Leaves are tested a
//! block of four primitives at a time, so the cost counts blocks, not primitives.

use super::build::{
    partition_bounded, reduce_chunks, BuildPrim, NodeBounds, Split, SplitRule, PARALLEL_REDUCE,
};
#[cfg(test)]
use crate::geometry::Aabb;
use glam::{BVec4A, Vec3A, Vec4};

pub(crate) const BINS: usize = 32;

/// Cost model constants, relative: one node visit against one leaf block test.
/// Tuned for the earlier pair-node traversal (both child boxes tested at once,
/// popped nodes never re-tested), where a visit is cheap and small leaves win: 0.8
/// took 8% fewer instructions on CBbunny and 17% fewer on CBspheres_lambertian than
/// 0.4 (the value of the one-box-per-visit traversal before it); 1.0 and 1.5 were no
/// better. Since leaves hold one block at most, the binary splits depend only on
/// areas and counts, not on these constants; the wide collapse (`collapse.rs`)
/// weighs them against each other. Neither 0.5 nor 1.2 for the block test
/// changed a node of the 1M-mesh or CBbunny trees (8 wide, SAH-optimal collapse).
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

    #[cfg(test)]
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
    /// The bin of `p` on `axis`: the scalar reference that [`bin_indices`] (for
    /// binning) and [`Binning::below`] (for partitioning) are tested against.
    #[cfg(test)]
    fn bin(&self, p: &BuildPrim, axis: usize) -> usize {
        bin_index(
            (p.centroid_on(axis) - self.min[axis]) * self.scale[axis],
            self.count - 1,
        )
    }

    /// `self.bin(p, axis) < boundary` for a boundary in `1..count`, without the
    /// conversion: for `x ≥ 0` and a whole `b`, `trunc(x) < b` exactly when
    /// `x < b`, and `f32::max` maps NaN to 0 as the conversion does.
    #[inline(always)]
    fn below(&self, p: &BuildPrim, axis: usize, boundary: usize) -> bool {
        let k = (p.centroid_on(axis) - self.min[axis]) * self.scale[axis];
        k.max(0.0) < boundary as f32
    }
}

/// Bin of the scaled coordinate `k`, clamped to `[0, last]` (`as` saturates,
/// NaN → 0, so odd input cannot index out of range).
#[cfg(test)]
fn bin_index(k: f32, last: usize) -> usize {
    (k as i32).clamp(0, last as i32) as usize
}

/// [`bin_index`] on three axes at once: clamping before the truncation instead
/// of after gives the same bins (`max(k, 0)` maps NaN to 0, as `maxps` returns
/// its second operand then), and truncates all three lanes in one instruction.
#[inline(always)]
fn bin_indices(k: Vec3A, last: usize) -> [usize; 3] {
    let k = k.max(Vec3A::ZERO).min(Vec3A::splat(last as f32));
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_mm_cvtsi128_si32, _mm_cvttps_epi32, _mm_shuffle_epi32};
        // SAFETY: SSE2 is part of the x86_64 baseline.
        unsafe {
            let i = _mm_cvttps_epi32(k.into());
            [
                _mm_cvtsi128_si32(i) as usize,
                _mm_cvtsi128_si32(_mm_shuffle_epi32::<1>(i)) as usize,
                _mm_cvtsi128_si32(_mm_shuffle_epi32::<2>(i)) as usize,
            ]
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        [k.x as usize, k.y as usize, k.z as usize]
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
        // Embree's rule: 4 bins and one more per 20 primitives. Most nodes are
        // small, and their bins cost more than their few primitives; n/2 bins
        // (at least 8) built the 1M mesh's binary tree about a third slower, for
        // an SAH cost 0.6% lower.
        let count = (4 + prims.len() / 20).min(BINS);
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
            ..=4 => best_split::<4>(prims, binning),
            5..=8 => best_split::<8>(prims, binning),
            9..=16 => best_split::<16>(prims, binning),
            _ => best_split::<BINS>(prims, binning),
        }?;
        // Relative to the parent's area; the traversal step into this node is paid either way.
        let split_cost = TRAVERSAL_COST + cost / bounds.surface_area();
        if prims.len() <= self.max_leaf && leaf_cost <= split_cost {
            return None;
        }
        let (mid, children) = partition_bounded(prims, |p| binning.below(p, axis, boundary));
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
    if prims.len() <= PARALLEL_REDUCE {
        // Filled in place: a `Bins<32>` is 4.6 kB, too much to move around per node.
        let mut bins = [[Bin::EMPTY; N]; 3];
        bin_into(prims, binning, &mut bins);
        return best_of_axes(&bins, binning);
    }
    let bins = reduce_chunks(prims, |c| fill_bins::<N>(c, binning), merge_bins);
    best_of_axes(&bins, binning)
}

/// The three axes' bins of one index side by side, one SIMD lane per axis (lane
/// 3 unused): the bounds per coordinate and the count (exact in `f32` below 2²⁴).
#[derive(Clone, Copy)]
struct BinLanes {
    lo: [Vec4; 3],
    hi: [Vec4; 3],
    count: Vec4,
}

impl BinLanes {
    const EMPTY: BinLanes = BinLanes {
        lo: [Vec4::INFINITY; 3],
        hi: [Vec4::NEG_INFINITY; 3],
        count: Vec4::ZERO,
    };

    fn gather<const N: usize>(bins: &Bins<N>, k: usize) -> BinLanes {
        let [x, y, z] = [&bins[0][k], &bins[1][k], &bins[2][k]];
        BinLanes {
            lo: [0, 1, 2].map(|c| Vec4::new(x.min[c], y.min[c], z.min[c], 0.0)),
            hi: [0, 1, 2].map(|c| Vec4::new(x.max[c], y.max[c], z.max[c], 0.0)),
            count: Vec4::new(x.count as f32, y.count as f32, z.count as f32, 0.0),
        }
    }

    #[inline(always)]
    fn union(&self, o: &BinLanes) -> BinLanes {
        BinLanes {
            lo: [0, 1, 2].map(|c| self.lo[c].min(o.lo[c])),
            hi: [0, 1, 2].map(|c| self.hi[c].max(o.hi[c])),
            count: self.count + o.count,
        }
    }

    /// `Bin::area_blocks` lane by lane, with the same operations in the same
    /// order (so the same bits) wherever the box is not empty.
    #[inline(always)]
    fn area_blocks(&self) -> Vec4 {
        let d = [0, 1, 2].map(|c| self.hi[c] - self.lo[c]);
        let area = 2.0 * (d[0] * d[1] + d[1] * d[2] + d[2] * d[0]);
        let blocks = ((self.count + 3.0) * 0.25).floor();
        area * blocks
    }
}

/// The cheapest boundary over the three axes as `(cost, axis, boundary)`: the
/// sweeps of [`best_boundary`] on all three axes at once, one per SIMD lane,
/// with the same choice (the first cheapest boundary of each axis, the first
/// cheapest axis).
fn best_of_axes<const N: usize>(bins: &Bins<N>, binning: Binning) -> Option<(f32, usize, usize)> {
    let n = binning.count;
    // right[k]: count and area·blocks of the union of bins k.. (k ≥ 1).
    let mut right = [(Vec4::ZERO, Vec4::ZERO); BINS];
    let mut acc = BinLanes::EMPTY;
    for k in (1..n).rev() {
        acc = acc.union(&BinLanes::gather(bins, k));
        right[k] = (acc.count, acc.area_blocks());
    }
    let mut left = BinLanes::EMPTY;
    let mut best_cost = Vec4::INFINITY;
    let mut best_k = Vec4::ZERO;
    let mut found = BVec4A::FALSE;
    for (k, &(right_count, right_cost)) in right.iter().enumerate().take(n).skip(1) {
        left = left.union(&BinLanes::gather(bins, k - 1));
        let valid = left.count.cmpne(Vec4::ZERO) & right_count.cmpne(Vec4::ZERO);
        let cost = INTERSECTION_COST * (left.area_blocks() + right_cost);
        let take = valid & (!found | cost.cmplt(best_cost));
        best_cost = Vec4::select(take, cost, best_cost);
        best_k = Vec4::select(take, Vec4::splat(k as f32), best_k);
        found |= take;
    }
    let found = found.bitmask();
    let mut best: Option<(f32, usize, usize)> = None;
    for axis in 0..3 {
        if binning.scale[axis] == 0.0 || found & 1 << axis == 0 {
            continue;
        }
        let cost = best_cost[axis];
        if best.is_none_or(|(c, _, _)| cost < c) {
            best = Some((cost, axis, best_k[axis] as usize));
        }
    }
    best
}

/// Bins every primitive on all three axes. The bin indices are computed for the
/// three axes at once with the same operations as [`Binning::bin`] (lane by lane,
/// the same bits), so partitioning sees the same bins.
fn fill_bins<const N: usize>(prims: &[BuildPrim], binning: Binning) -> Bins<N> {
    let mut bins = [[Bin::EMPTY; N]; 3];
    bin_into(prims, binning, &mut bins);
    bins
}

/// [`fill_bins`] into bins the caller cleared.
#[inline(always)]
fn bin_into<const N: usize>(prims: &[BuildPrim], binning: Binning, bins: &mut Bins<N>) {
    let origin = Vec3A::from_array(binning.min);
    let scale = Vec3A::from_array(binning.scale);
    let last = binning.count - 1;
    let add = |bins: &mut Bins<N>, p: &BuildPrim| {
        let (lo, hi) = (Vec3A::from(p.bounds.min), Vec3A::from(p.bounds.max));
        let k = bin_indices(((lo + hi) * 0.5 - origin) * scale, last);
        for (axis, axis_bins) in bins.iter_mut().enumerate() {
            let b = &mut axis_bins[k[axis]];
            b.min = b.min.min(lo);
            b.max = b.max.max(hi);
            b.count += 1;
        }
    };
    if prims.len() < DUAL_BINS {
        prims.iter().for_each(|p| add(bins, p));
        return;
    }
    // Neighbouring primitives often fall in the same bin, so each update would
    // wait for the last one: two sets of bins taking turns halve that chain.
    // Unions are exact, so the merged bins are the same bits.
    let mut other = [[Bin::EMPTY; N]; 3];
    let mut pairs = prims.chunks_exact(2);
    for pair in &mut pairs {
        add(bins, &pair[0]);
        add(&mut other, &pair[1]);
    }
    pairs.remainder().iter().for_each(|p| add(bins, p));
    for (xa, ya) in bins.iter_mut().zip(&other) {
        for (x, y) in xa.iter_mut().zip(ya) {
            *x = x.union(y);
        }
    }
}

/// Nodes with at least this many primitives are binned into two sets of bins.
const DUAL_BINS: usize = 256;

fn merge_bins<const N: usize>(mut a: Bins<N>, b: Bins<N>) -> Bins<N> {
    for (xa, ya) in a.iter_mut().zip(&b) {
        for (x, y) in xa.iter_mut().zip(ya) {
            *x = x.union(y);
        }
    }
    a
}

/// Cheapest boundary `k` (bins `< k` go left) of one axis as
/// `(Σ area·blocks·C_isect, k)`: the scalar reference for [`best_of_axes`].
#[cfg(test)]
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
    use crate::sampling::Rng;
    use glam::Vec3;

    #[test]
    fn parallel_binning_matches_serial_at_any_thread_count() {
        let mut rng = Rng::from_seed(3);
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
        // The partition's side test is the bin's.
        for p in prims.iter().take(2000) {
            for axis in 0..3 {
                for boundary in 1..BINS {
                    let below = binning.bin(p, axis) < boundary;
                    assert_eq!(binning.below(p, axis, boundary), below);
                }
            }
        }
        let odd_binning = Binning {
            min: [0.0; 3],
            scale: [1.0; 3],
            count: 8,
        };
        for x in [
            f32::NAN,
            f32::NEG_INFINITY,
            f32::INFINITY,
            -0.5,
            0.5,
            2.0,
            2.5,
            7.5,
            1e30,
        ] {
            let p = BuildPrim::new(0, Aabb::new(Vec3::splat(x), Vec3::splat(x)));
            for boundary in 1..8 {
                let below = odd_binning.bin(&p, 0) < boundary;
                assert_eq!(odd_binning.below(&p, 0, boundary), below, "{x} {boundary}");
            }
        }
        // The SIMD bin indices are the scalar ones, also on odd input.
        let odd = [
            f32::NAN,
            f32::NEG_INFINITY,
            f32::INFINITY,
            -0.5,
            -0.0,
            0.0,
            0.99,
            7.0,
            7.5,
            8.0,
            1e30,
            -1e30,
            3.0e9,
        ];
        for &x in &odd {
            let k = Vec3A::new(x, 7.999, 3.5);
            assert_eq!(bin_indices(k, 7), [bin_index(x, 7), 7, 3], "{x}");
        }
        // The SIMD sweep over three axes chooses what the scalar one does.
        for (i, chunk) in prims.chunks(37).take(500).enumerate() {
            let mut b = binning;
            b.count = 8 + i % (BINS - 7);
            b.scale[i % 3] = if i % 5 == 0 { 0.0 } else { b.scale[i % 3] };
            let bins = fill_bins::<BINS>(chunk, b);
            let mut expected: Option<(f32, usize, usize)> = None;
            for (axis, axis_bins) in bins.iter().enumerate() {
                if b.scale[axis] == 0.0 {
                    continue;
                }
                if let Some((cost, k)) = best_boundary(&axis_bins[..b.count]) {
                    if expected.is_none_or(|(c, _, _)| cost < c) {
                        expected = Some((cost, axis, k));
                    }
                }
            }
            let got = best_of_axes(&bins, b);
            assert_eq!(
                got.map(|g| (g.0.to_bits(), g.1, g.2)),
                expected.map(|e| (e.0.to_bits(), e.1, e.2))
            );
        }
        for axis_bins in &serial {
            assert_eq!(axis_bins.iter().map(|b| b.count).sum::<u32>(), 50_000);
        }
    }
}
