//! The traversal layout: each inner node holds the boxes of both its children,
//! so one SIMD slab test decides which children the ray enters and at what
//! distance, and a popped node is never re-tested (its entry distance is on the
//! stack). The builder's 32-byte nodes are converted after the build.

use super::node::BvhNode;
use crate::geometry::ray::gamma;
use crate::geometry::Ray;

/// Slack on the exit distance so rounding in the slab test never culls a box the
/// ray touches (pbrt's `1 + 2γ(3)`).
pub(crate) const EXIT_SLACK: f32 = 1.0 + 2.0 * gamma(3);

/// A reference to a child: an inner node (`count == 0`, `index` into the pair
/// nodes) or a leaf (`count` primitives from slot `index`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct ChildRef {
    pub index: u32,
    pub count: u32,
}

impl ChildRef {
    #[inline(always)]
    pub fn is_leaf(self) -> bool {
        self.count != 0
    }
}

/// One cache line: per axis `[min₀, min₁, max₀, max₁]` of the two child boxes,
/// then the two child references.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C, align(64))]
pub(crate) struct PairNode {
    bounds: [[f32; 4]; 3],
    pub children: [ChildRef; 2],
}

const _: () = assert!(std::mem::size_of::<PairNode>() == 64);

/// Converts the builder's depth-first nodes. The root's own box is dropped:
/// traversal starts at the root's children (box tests only cull, so skipping one
/// changes no result). Returns the pair nodes and the root reference.
pub(crate) fn pair_nodes(nodes: &[BvhNode]) -> (Vec<PairNode>, ChildRef) {
    let Some(root) = nodes.first() else {
        return (Vec::new(), ChildRef::default());
    };
    if root.count() > 0 {
        let leaf = ChildRef {
            index: root.offset,
            count: root.count(),
        };
        return (Vec::new(), leaf);
    }
    let mut out = Vec::with_capacity(nodes.len() / 2);
    convert(nodes, 0, &mut out);
    (out, ChildRef { index: 0, count: 0 })
}

/// Emits inner node `i` and its inner descendants depth first; returns its index.
fn convert(nodes: &[BvhNode], i: usize, out: &mut Vec<PairNode>) -> u32 {
    let me = out.len();
    out.push(PairNode::default());
    let kids = [i + 1, nodes[i].offset as usize];
    let mut node = PairNode::default();
    for (slot, &k) in kids.iter().enumerate() {
        let child = &nodes[k];
        for axis in 0..3 {
            node.bounds[axis][slot] = child.min[axis];
            node.bounds[axis][2 + slot] = child.max[axis];
        }
        node.children[slot] = if child.count() > 0 {
            ChildRef {
                index: child.offset,
                count: child.count(),
            }
        } else {
            ChildRef {
                index: convert(nodes, k, out),
                count: 0,
            }
        };
    }
    out[me] = node;
    me as u32
}

/// Per-ray setup of the slab test: origin and reciprocal direction per axis,
/// and whether the direction is negative (sign bit, so `−0` counts), which picks
/// the near and far bound without `min`/`max` of the two slab distances.
///
/// A direction component of `±0` gives an infinite reciprocal; if the origin lies
/// exactly on that slab's plane the distance is `0·∞ = NaN`. Such a slab does not
/// constrain the ray; both versions of the test ignore NaN distances.
#[derive(Clone, Copy, Debug)]
pub(crate) struct PairRay {
    o: [f32; 3],
    inv: [f32; 3],
    neg: [bool; 3],
    t_min: f32,
    #[cfg(target_arch = "x86_64")]
    simd: SimdPairRay,
}

#[cfg(target_arch = "x86_64")]
#[derive(Clone, Copy, Debug)]
struct SimdPairRay {
    o: [std::arch::x86_64::__m128; 3],
    inv: [std::arch::x86_64::__m128; 3],
    /// All-ones where the axis' direction is negative.
    neg: [std::arch::x86_64::__m128; 3],
    t_min: std::arch::x86_64::__m128,
}

/// Which children the ray enters (`mask` bit `c` for child `c`) and where.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct PairHits {
    pub mask: u32,
    pub entry: [f32; 2],
}

impl PairRay {
    pub fn new(ray: &Ray) -> Self {
        let inv = ray.d.recip().to_array();
        let o = ray.o.to_array();
        let neg = ray.d.to_array().map(f32::is_sign_negative);
        PairRay {
            o,
            inv,
            neg,
            t_min: ray.t_min,
            #[cfg(target_arch = "x86_64")]
            simd: SimdPairRay::new(o, inv, neg, ray.t_min),
        }
    }

    #[inline(always)]
    pub fn hits(&self, node: &PairNode, t_max: f32) -> PairHits {
        #[cfg(target_arch = "x86_64")]
        {
            self.hits_sse(node, t_max)
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            self.hits_scalar(node, t_max)
        }
    }

    /// Portable version; `f32::max`/`min` return the non-NaN operand.
    #[allow(dead_code)]
    pub fn hits_scalar(&self, node: &PairNode, t_max: f32) -> PairHits {
        let mut out = PairHits {
            mask: 0,
            entry: [0.0; 2],
        };
        for c in 0..2 {
            let mut entry = self.t_min;
            let mut exit = t_max;
            for a in 0..3 {
                let (lo, hi) = (node.bounds[a][c], node.bounds[a][2 + c]);
                let (near, far) = if self.neg[a] { (hi, lo) } else { (lo, hi) };
                entry = entry.max((near - self.o[a]) * self.inv[a]);
                exit = exit.min((far - self.o[a]) * self.inv[a]);
            }
            out.entry[c] = entry;
            if entry <= exit * EXIT_SLACK {
                out.mask |= 1 << c;
            }
        }
        out
    }

    /// SSE2 version: lanes `[near₀, near₁, far₀, far₁]` per axis.
    /// `_mm_max_ps(a, b)` and `_mm_min_ps(a, b)` return `b` when either operand
    /// is NaN, so NaN slab distances (first operand) leave the accumulated
    /// interval as it was.
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    pub fn hits_sse(&self, node: &PairNode, t_max: f32) -> PairHits {
        use std::arch::x86_64::*;
        let SimdPairRay { o, inv, neg, t_min } = self.simd;
        // SAFETY: PairNode is repr(C, align(64)) and starts with three 16-byte
        // rows. SSE2 is part of the x86_64 baseline.
        unsafe {
            let rows = node.bounds.as_ptr() as *const __m128;
            let mut entry = t_min;
            let mut exit = _mm_set1_ps(t_max);
            for a in 0..3 {
                let v = _mm_load_ps(rows.add(a) as *const f32);
                let swapped = _mm_shuffle_ps(v, v, 0x4E);
                let v = _mm_xor_ps(v, _mm_and_ps(_mm_xor_ps(v, swapped), neg[a]));
                let t = _mm_mul_ps(_mm_sub_ps(v, o[a]), inv[a]);
                entry = _mm_max_ps(t, entry);
                exit = _mm_min_ps(t, exit);
            }
            let exit = _mm_movehl_ps(exit, exit);
            let inside = _mm_cmple_ps(entry, _mm_mul_ps(exit, _mm_set1_ps(EXIT_SLACK)));
            let mut e = [0.0f32; 4];
            _mm_storeu_ps(e.as_mut_ptr(), entry);
            PairHits {
                mask: (_mm_movemask_ps(inside) & 3) as u32,
                entry: [e[0], e[1]],
            }
        }
    }
}

#[cfg(target_arch = "x86_64")]
impl SimdPairRay {
    fn new(o: [f32; 3], inv: [f32; 3], neg: [bool; 3], t_min: f32) -> Self {
        use std::arch::x86_64::*;
        // SAFETY: SSE2 is part of the x86_64 baseline; these only build registers.
        unsafe {
            let mask = |n: bool| _mm_castsi128_ps(_mm_set1_epi32(if n { -1 } else { 0 }));
            SimdPairRay {
                o: o.map(|v| _mm_set1_ps(v)),
                inv: inv.map(|v| _mm_set1_ps(v)),
                neg: neg.map(mask),
                t_min: _mm_set1_ps(t_min),
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Aabb;
    use glam::Vec3;

    /// A root over a unit box and a box shifted by 2 in x.
    fn two_boxes() -> PairNode {
        let a = Aabb::new(Vec3::ZERO, Vec3::ONE);
        let b = Aabb::new(Vec3::new(2.0, 0.0, 0.0), Vec3::new(3.0, 1.0, 1.0));
        let nodes = [
            BvhNode::inner(&a.union(&b), 2, 0),
            BvhNode::leaf(&a, 0, 1),
            BvhNode::leaf(&b, 1, 2),
        ];
        let (pairs, root) = pair_nodes(&nodes);
        assert_eq!(root, ChildRef { index: 0, count: 0 });
        assert_eq!(pairs.len(), 1);
        pairs[0]
    }

    fn both(r: &PairRay, node: &PairNode, t_max: f32) -> u32 {
        let s = r.hits_scalar(node, t_max);
        #[cfg(target_arch = "x86_64")]
        assert_eq!(s, r.hits_sse(node, t_max));
        s.mask
    }

    #[test]
    fn converts_children() {
        let n = two_boxes();
        assert_eq!(n.children[0], ChildRef { index: 0, count: 1 });
        assert_eq!(n.children[1], ChildRef { index: 1, count: 2 });
    }

    #[test]
    fn slab_test_orders_and_culls() {
        let n = two_boxes();
        let r = PairRay::new(&Ray::new(Vec3::new(-1.0, 0.5, 0.5), Vec3::X));
        let h = r.hits_scalar(&n, f32::INFINITY);
        assert_eq!((h.mask, h.entry), (3, [1.0, 3.0]));
        assert_eq!(both(&r, &n, f32::INFINITY), 3);
        assert_eq!(both(&r, &n, 2.5), 1);
        let back = PairRay::new(&Ray::new(Vec3::new(4.0, 0.5, 0.5), -Vec3::X));
        let h = back.hits_scalar(&n, f32::INFINITY);
        assert_eq!((h.mask, h.entry), (3, [3.0, 1.0]));
        assert_eq!(both(&back, &n, f32::INFINITY), 3);
        let miss = PairRay::new(&Ray::new(Vec3::new(-1.0, 1.5, 0.5), Vec3::X));
        assert_eq!(both(&miss, &n, f32::INFINITY), 0);
    }

    #[test]
    fn slab_test_handles_parallel_rays_on_faces() {
        let n = two_boxes();
        // Origin on the x = 0 face, direction with zero x: box 0 is touched.
        for d in [Vec3::new(0.0, 0.0, 1.0), Vec3::new(-0.0, 0.0, 1.0)] {
            let r = Ray::new(Vec3::new(0.0, 0.5, -1.0), d);
            assert_eq!(both(&PairRay::new(&r), &n, f32::INFINITY), 1);
            let r = Ray::new(Vec3::new(1.0, 1.0, -1.0), d);
            assert_eq!(both(&PairRay::new(&r), &n, f32::INFINITY), 1);
            let r = Ray::new(Vec3::new(-1e-7, 0.5, -1.0), d);
            assert_eq!(both(&PairRay::new(&r), &n, f32::INFINITY), 0);
            let r = Ray::new(Vec3::new(2.0, 0.0, -1.0), d);
            assert_eq!(both(&PairRay::new(&r), &n, f32::INFINITY), 2);
        }
        let r = Ray::new(Vec3::new(0.5, 0.5, -1.0), Vec3::Z);
        assert_eq!(both(&PairRay::new(&r), &n, 0.5), 0);
        assert_eq!(both(&PairRay::new(&r), &n, 1.0), 1);
        let inside = Ray::new(Vec3::splat(0.5), Vec3::new(-1.0, 2.0, 0.5));
        assert_eq!(both(&PairRay::new(&inside), &n, f32::INFINITY), 1);
    }
}
