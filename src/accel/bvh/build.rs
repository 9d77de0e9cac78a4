//! The builder skeleton shared by the split rules: top-down recursion over an
//! in-place partitioned primitive array, emitting nodes depth first.
//!
//! Large subtrees are built in parallel with `rayon::join`, then written into
//! one node array in a fixed order, so the tree is the same whatever the
//! thread count. Reductions over large nodes (bounds, SAH bins) run
//! over fixed-size chunks whose partial results are merged in chunk order, so
//! they too give the same bits whatever the thread count.

use super::node::BvhNode;
use crate::geometry::Aabb;
use crate::scene::PrimId;
use glam::Vec3A;
use rayon::prelude::*;

/// Subtrees with more primitives than this are built in parallel.
const PARALLEL_THRESHOLD: usize = 4096;

/// Reductions over more primitives than this run in parallel, in chunks of
/// [`REDUCE_CHUNK`]: otherwise the top levels of a large build are serial.
pub(crate) const PARALLEL_REDUCE: usize = 8192;
pub(crate) const REDUCE_CHUNK: usize = 4096;

/// Past this depth every split is an object median, so the tree is at most
/// `MEDIAN_DEPTH + 32` deep and fits the traversal stack.
const MEDIAN_DEPTH: u32 = 30;

/// Bound on the depth of any tree this module builds.
pub(crate) const MAX_DEPTH: usize = MEDIAN_DEPTH as usize + 33;

/// A primitive record of 32 bytes (two per cache line): bounds and id; the
/// centroid is recomputed from the bounds where needed.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(32))]
pub(crate) struct BuildPrim {
    pub bounds: Aabb,
    pub id: PrimId,
}

const _: () = assert!(std::mem::size_of::<BuildPrim>() == 32);

impl BuildPrim {
    pub fn new(id: PrimId, bounds: Aabb) -> Self {
        BuildPrim { bounds, id }
    }

    /// One coordinate of the centroid, without computing the other two.
    #[inline(always)]
    pub fn centroid_on(&self, axis: usize) -> f32 {
        0.5 * (self.bounds.min[axis] + self.bounds.max[axis])
    }
}

/// The bounds of a node's primitives and of their centroids: what a split rule
/// needs from a node, handed down by the parent's split when it has them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct NodeBounds {
    pub bounds: Aabb,
    pub centroids: Aabb,
}

impl NodeBounds {
    pub fn union(&self, o: &NodeBounds) -> NodeBounds {
        NodeBounds {
            bounds: self.bounds.union(&o.bounds),
            centroids: self.centroids.union(&o.centroids),
        }
    }

    /// Both bounds of `prims` in one pass (chunked in parallel for large inputs).
    pub fn of(prims: &[BuildPrim]) -> NodeBounds {
        let serial = |c: &[BuildPrim]| {
            c.iter()
                .fold(Accumulator::EMPTY, |mut b, p| {
                    b.grow(p);
                    b
                })
                .bounds()
        };
        reduce_chunks(prims, serial, |a, b| a.union(&b))
    }
}

/// [`NodeBounds`] being gathered, in SIMD registers: the same min/max as
/// `NodeBounds::grow` on finite input (all a build sees), and the centroid is
/// `0.5·(min + max)` lane by lane, the same bits as `Aabb::centre` and
/// `BuildPrim::centroid_on`.
#[derive(Clone, Copy)]
struct Accumulator {
    lo: Vec3A,
    hi: Vec3A,
    c_lo: Vec3A,
    c_hi: Vec3A,
}

impl Accumulator {
    const EMPTY: Accumulator = Accumulator {
        lo: Vec3A::INFINITY,
        hi: Vec3A::NEG_INFINITY,
        c_lo: Vec3A::INFINITY,
        c_hi: Vec3A::NEG_INFINITY,
    };

    #[inline(always)]
    fn grow(&mut self, p: &BuildPrim) {
        let (lo, hi) = (Vec3A::from(p.bounds.min), Vec3A::from(p.bounds.max));
        let c = (lo + hi) * 0.5;
        self.lo = self.lo.min(lo);
        self.hi = self.hi.max(hi);
        self.c_lo = self.c_lo.min(c);
        self.c_hi = self.c_hi.max(c);
    }

    fn bounds(&self) -> NodeBounds {
        NodeBounds {
            bounds: Aabb::new(self.lo.into(), self.hi.into()),
            centroids: Aabb::new(self.c_lo.into(), self.c_hi.into()),
        }
    }
}

/// A split decision: the primitives are partitioned so that `[..mid]` goes to
/// the first child, and `axis` is the split axis (for traversal order).
/// `children` are the two sides' bounds when the rule computed them while
/// partitioning (else the skeleton computes them). Unions of boxes are exact,
/// so either way they are the same bits.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Split {
    pub axis: usize,
    pub mid: usize,
    pub children: Option<[NodeBounds; 2]>,
}

/// How a builder splits a node.
pub(crate) trait SplitRule: Sync {
    /// Largest leaf the rule may produce; bigger nodes are always split.
    fn max_leaf(&self) -> usize;

    /// Partitions `prims` and returns the split, or `None` for a leaf. A rule may
    /// also return `None` when it finds no split (e.g. all centroids equal); the
    /// skeleton then splits nodes above `max_leaf` in halves.
    fn split(&self, prims: &mut [BuildPrim], node: &NodeBounds) -> Option<Split>;
}

/// Builds the flat node array over `prims`, reordering them into leaf order.
pub(crate) fn build_nodes<R: SplitRule>(rule: &R, prims: &mut [BuildPrim]) -> Vec<BvhNode> {
    if prims.is_empty() {
        return Vec::new();
    }
    let root = NodeBounds::of(prims);
    let part = build_part(rule, prims, &root, 0, 0);
    let mut nodes = vec![BvhNode::default(); part.len];
    write_part(part, 0, &mut nodes);
    nodes
}

/// A built subtree: small ones as their own depth-first node vector (offsets
/// relative to its start), large ones as their root and two parts built in
/// parallel. Each node is copied once, into its final slot, by [`write_part`].
struct Part {
    /// Nodes in the subtree.
    len: usize,
    kind: PartKind,
}

enum PartKind {
    Flat(Vec<BvhNode>),
    /// The root (its second-child offset is set when written) and its children.
    Split(BvhNode, Box<[Part; 2]>),
}

fn build_part<R: SplitRule>(
    rule: &R,
    prims: &mut [BuildPrim],
    node: &NodeBounds,
    first: u32,
    depth: u32,
) -> Part {
    if prims.len() <= PARALLEL_THRESHOLD {
        // About 2/3 of a node per primitive covers leaves of 3 or more.
        let mut nodes = Vec::with_capacity(prims.len() * 2 / 3 + 1);
        build_into(rule, prims, node, first, depth, &mut nodes);
        return Part {
            len: nodes.len(),
            kind: PartKind::Flat(nodes),
        };
    }
    let Some(Split {
        axis,
        mid,
        children,
    }) = choose_split(rule, prims, node, depth)
    else {
        let leaf = BvhNode::leaf(&node.bounds, first, prims.len() as u32);
        return Part {
            len: 1,
            kind: PartKind::Flat(vec![leaf]),
        };
    };
    let (left, right) = prims.split_at_mut(mid);
    let [lb, rb] = children.unwrap_or_else(|| [NodeBounds::of(left), NodeBounds::of(right)]);
    let right_first = first + mid as u32;
    let (l, r) = rayon::join(
        || build_part(rule, left, &lb, first, depth + 1),
        || build_part(rule, right, &rb, right_first, depth + 1),
    );
    Part {
        len: 1 + l.len + r.len,
        kind: PartKind::Split(BvhNode::inner(&node.bounds, 0, axis), Box::new([l, r])),
    }
}

/// Writes `part` into `out` (exactly its slots), whose first slot is `base`.
fn write_part(part: Part, base: u32, out: &mut [BvhNode]) {
    match part.kind {
        PartKind::Flat(nodes) => {
            for (slot, mut node) in out.iter_mut().zip(nodes) {
                if node.count() == 0 {
                    node.offset += base;
                }
                *slot = node;
            }
        }
        PartKind::Split(mut root, children) => {
            let [l, r] = *children;
            root.offset = base + 1 + l.len as u32;
            out[0] = root;
            let (l_out, r_out) = out[1..].split_at_mut(l.len);
            rayon::join(
                || write_part(l, base + 1, l_out),
                || write_part(r, root.offset, r_out),
            );
        }
    }
}

/// The serial builder: the subtree over `prims` (the primitive slots from
/// `first`), appended depth first to `out`.
fn build_into<R: SplitRule>(
    rule: &R,
    prims: &mut [BuildPrim],
    node: &NodeBounds,
    first: u32,
    depth: u32,
    out: &mut Vec<BvhNode>,
) {
    let Some(Split {
        axis,
        mid,
        children,
    }) = choose_split(rule, prims, node, depth)
    else {
        out.push(BvhNode::leaf(&node.bounds, first, prims.len() as u32));
        return;
    };
    let me = out.len();
    out.push(BvhNode::default());
    let (left, right) = prims.split_at_mut(mid);
    let [lb, rb] = children.unwrap_or_else(|| [NodeBounds::of(left), NodeBounds::of(right)]);
    build_into(rule, left, &lb, first, depth + 1, out);
    let second = out.len();
    build_into(rule, right, &rb, first + mid as u32, depth + 1, out);
    out[me] = BvhNode::inner(&node.bounds, second as u32, axis);
}

fn choose_split<R: SplitRule>(
    rule: &R,
    prims: &mut [BuildPrim],
    node: &NodeBounds,
    depth: u32,
) -> Option<Split> {
    let n = prims.len();
    if n <= 1 {
        return None;
    }
    if depth >= MEDIAN_DEPTH && n > rule.max_leaf() {
        return Some(median_split(prims, &node.centroids));
    }
    match rule.split(prims, node) {
        Some(s) if s.mid > 0 && s.mid < n => Some(s),
        _ if n > rule.max_leaf() => Some(median_split(prims, &node.centroids)),
        _ => None,
    }
}

/// Object median along the longest axis of `centroids` (the centroid bounds of
/// `prims`): always halves the node (also when all centroids coincide), which
/// bounds the depth.
pub(crate) fn median_split(prims: &mut [BuildPrim], centroids: &Aabb) -> Split {
    let axis = centroids.max_axis();
    let mid = prims.len() / 2;
    prims.select_nth_unstable_by(mid, |a, b| {
        a.centroid_on(axis).total_cmp(&b.centroid_on(axis))
    });
    Split {
        axis,
        mid,
        children: None,
    }
}

/// `serial(prims)` for small inputs; for large ones `serial` of each chunk in
/// parallel, then the partial results merged left to right. The result depends only
/// on the input, not on how rayon schedules the chunks.
pub(crate) fn reduce_chunks<T: Send>(
    prims: &[BuildPrim],
    serial: impl Fn(&[BuildPrim]) -> T + Sync,
    merge: impl Fn(T, T) -> T,
) -> T {
    if prims.len() <= PARALLEL_REDUCE {
        return serial(prims);
    }
    let parts: Vec<T> = prims.par_chunks(REDUCE_CHUNK).map(&serial).collect();
    let mut parts = parts.into_iter();
    let first = parts.next().expect("a large input has a chunk");
    parts.fold(first, merge)
}

/// Moves the primitives satisfying `left` to the front (deterministic, not
/// stable); returns how many there are and the bounds of both sides, gathered on
/// the way.
pub(crate) fn partition_bounded(
    prims: &mut [BuildPrim],
    left: impl Fn(&BuildPrim) -> bool,
) -> (usize, [NodeBounds; 2]) {
    if prims.len() <= SCRATCH {
        return SCRATCH_PRIMS.with_borrow_mut(|scratch| partition_through(prims, scratch, left));
    }
    let mut sides = [Accumulator::EMPTY; 2];
    let mut i = 0;
    let mut j = prims.len();
    while i < j {
        if left(&prims[i]) {
            sides[0].grow(&prims[i]);
            i += 1;
        } else {
            j -= 1;
            sides[1].grow(&prims[i]);
            prims.swap(i, j);
        }
    }
    (i, sides.map(|a| a.bounds()))
}

/// Nodes of at most this many primitives are partitioned through a scratch buffer
/// of this size per thread (128 kB).
const SCRATCH: usize = PARALLEL_THRESHOLD;

thread_local! {
    static SCRATCH_PRIMS: std::cell::RefCell<Vec<BuildPrim>> =
        std::cell::RefCell::new(Vec::with_capacity(SCRATCH));
}

/// [`partition_bounded`] without a branch on the side: each primitive is written
/// to the next free slot at the front or the back of `scratch` (the side picks
/// the slot, not the path), then copied back side by side while the sides'
/// bounds are gathered. The side of a primitive is close to random, and the
/// in-place swap loop mispredicted its branch about every other primitive.
fn partition_through(
    prims: &mut [BuildPrim],
    scratch: &mut Vec<BuildPrim>,
    left: impl Fn(&BuildPrim) -> bool,
) -> (usize, [NodeBounds; 2]) {
    let n = prims.len();
    scratch.clear();
    let slots = &mut scratch.spare_capacity_mut()[..n];
    let (mut front, mut back) = (0, n);
    for p in prims.iter() {
        let goes_left = left(p);
        back -= usize::from(!goes_left);
        slots[if goes_left { front } else { back }].write(*p);
        front += usize::from(goes_left);
    }
    // Every slot was written once: the front ones up to `front`, the back ones
    // from `back == front` on.
    debug_assert_eq!(front, back);
    let gather = |dst: &mut [BuildPrim], src: &[std::mem::MaybeUninit<BuildPrim>]| {
        let mut side = Accumulator::EMPTY;
        for (d, s) in dst.iter_mut().zip(src) {
            // SAFETY: written by the loop above.
            let s = unsafe { s.assume_init() };
            side.grow(&s);
            *d = s;
        }
        side.bounds()
    };
    let (l, r) = prims.split_at_mut(front);
    let sides = [gather(l, &slots[..front]), gather(r, &slots[front..])];
    (front, sides)
}
