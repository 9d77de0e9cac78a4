//! The traversal layout: wide nodes of [`WIDTH`] children whose boxes are stored
//! per axis (structure of arrays), so one SIMD pass tests a ray against every
//! child box and yields the entry distances used to visit them nearest first.
//! The builder's binary tree is collapsed into this layout by [`super::collapse`].
//!
//! Why 16 wide: against 8 wide (trees otherwise built alike, with the quantised
//! child boxes tried then on the 1M mesh and `f32` ones on CBbunny; interleaved
//! in one process on this machine, AMD EPYC, 1 thread), the 998k-triangle mesh traced
//! incoherent rays 1.14× and shadow rays 1.15× faster, with 5.7 instead of 7.6
//! node visits per incoherent ray: its traversal waits on memory, and a level
//! less is a dependent cache miss less. CBbunny (in cache): incoherent 1.08×,
//! shadow 1.11×, camera 0.98×. A 16-wide node is one AVX-512 pass or two AVX2
//! passes. (With the earlier greedy collapse, 8 wide had beaten 4 wide: 4 wide
//! made 1.7× the nodes and rays visited more of them.) The width is this one
//! constant; 4, 8 and 16 keep compiling.
//!
//! Child boxes quantised to a byte per coordinate (Embree's compressed nodes;
//! 192 instead of 448 bytes a node, bounds checked to contain the exact ones)
//! were measured and dropped: at 16 wide, against these `f32` nodes on displaced
//! spheres (interleaved, 1 thread, loaded machine), incoherent rays were
//! 0.79-0.89× as fast from 30k to 500k triangles and 0.99-1.05× from 1M to 4M,
//! shadow rays 0.82-1.20×, camera rays 0.66-0.95× throughout: decoding costs
//! more than the bytes save once a level less has cut the misses. (At 8 wide
//! they had won on the 1M mesh.)

use crate::geometry::ray::gamma;
use crate::geometry::{Aabb, Ray};
use crate::lanes::rays::PacketRays;
use crate::lanes::{F32s, LaneBits, Simd};

/// Children per node.
pub(crate) const WIDTH: usize = 16;

/// Slack on the exit distance so rounding in the slab test never culls a box the
/// ray touches (pbrt's `1 + 2γ(3)`).
pub(crate) const EXIT_SLACK: f32 = 1.0 + 2.0 * gamma(3);

/// A reference to a child in 32 bits: an inner node (`count() == 0`, `index()`
/// into the wide nodes) or a leaf (`count()` primitives in block `index()`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct ChildRef(u32);

impl ChildRef {
    /// Leaves hold at most one block of 4, so the count takes 3 bits.
    const COUNT_BITS: u32 = 3;

    pub fn node(index: u32) -> Self {
        assert!(index < 1 << (32 - Self::COUNT_BITS), "too many nodes");
        ChildRef(index << Self::COUNT_BITS)
    }

    pub fn leaf(block: u32, count: u32) -> Self {
        assert!(block < 1 << (32 - Self::COUNT_BITS), "too many leaf blocks");
        assert!((1..=4).contains(&count));
        ChildRef(block << Self::COUNT_BITS | count)
    }

    #[inline(always)]
    pub fn is_leaf(self) -> bool {
        self.count() != 0
    }

    #[inline(always)]
    pub fn index(self) -> u32 {
        self.0 >> Self::COUNT_BITS
    }

    #[inline(always)]
    pub fn count(self) -> u32 {
        self.0 & ((1 << Self::COUNT_BITS) - 1)
    }

    /// The same reference with its index moved by `shift` (a subtree appended).
    pub fn shifted(self, shift: u32) -> Self {
        ChildRef(self.0 + (shift << Self::COUNT_BITS))
    }
}

/// `lo[a][c]`, `hi[a][c]`: the bounds of child `c` on axis `a`. Unused slots hold
/// the empty box (`+∞`, `−∞`), which every ray misses.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(64))]
pub(crate) struct WideNode {
    lo: [[f32; WIDTH]; 3],
    hi: [[f32; WIDTH]; 3],
    children: [ChildRef; WIDTH],
}

/// A node without children (no ray enters it).
impl Default for WideNode {
    fn default() -> Self {
        WideNode {
            lo: [[f32::INFINITY; WIDTH]; 3],
            hi: [[f32::NEG_INFINITY; WIDTH]; 3],
            children: [ChildRef::default(); WIDTH],
        }
    }
}

impl WideNode {
    /// A node over `children` (1 to [`WIDTH`]), each with its exact box.
    pub fn new(children: &[(Aabb, ChildRef)]) -> Self {
        assert!(!children.is_empty() && children.len() <= WIDTH);
        let mut node = WideNode::default();
        for (c, &(b, child)) in children.iter().enumerate() {
            for a in 0..3 {
                node.lo[a][c] = b.min[a];
                node.hi[a][c] = b.max[a];
            }
            node.children[c] = child;
        }
        node
    }

    /// The child in slot `c` (a slot in use).
    #[inline(always)]
    pub fn child(&self, c: usize) -> ChildRef {
        self.children[c]
    }

    /// The slots in use.
    pub fn children_mut(&mut self) -> &mut [ChildRef] {
        let len = self.len();
        &mut self.children[..len]
    }

    pub fn child_bounds(&self, c: usize) -> Aabb {
        Aabb::new(
            glam::Vec3::new(self.lo[0][c], self.lo[1][c], self.lo[2][c]),
            glam::Vec3::new(self.hi[0][c], self.hi[1][c], self.hi[2][c]),
        )
    }

    /// Slots in use (children fill the slots from slot 0, so this counts them):
    /// every slot compared, without an early exit, so the packet traversal's hot
    /// loop gets it as one vector comparison.
    #[inline(always)]
    pub fn len(&self) -> usize {
        let (lo, hi) = (&self.lo[0], &self.hi[0]);
        (0..WIDTH).filter(|&c| lo[c] <= hi[c]).count()
    }

    /// The slab test of child `c` against every lane of a packet, as `hits_avx2`
    /// does it for one ray: the lanes that enter it before their `t_max`, and their
    /// entry distances.
    #[inline(always)]
    pub fn hits_packet<S: Simd>(
        &self,
        s: S,
        rays: &PacketRays<S>,
        c: usize,
        t_max: F32s<S>,
    ) -> (LaneBits, F32s<S>) {
        let o = [rays.o.x, rays.o.y, rays.o.z];
        let mut t0 = F32s::splat(s, 0.0);
        let mut t1 = t_max;
        for (a, ((o, inv), neg)) in o.iter().zip(&rays.inv).zip(&rays.neg).enumerate() {
            let (lo, hi) = (F32s::splat(s, self.lo[a][c]), F32s::splat(s, self.hi[a][c]));
            let near = F32s::select(*neg, hi, lo);
            let far = F32s::select(*neg, lo, hi);
            t0 = ((near - *o) * *inv).max(t0);
            t1 = ((far - *o) * *inv).min(t1);
        }
        (t0.le(t1 * F32s::splat(s, EXIT_SLACK)).bits(), t0)
    }

    /// The portable box test; `f32::max`/`min` return the non-NaN operand.
    #[inline(always)]
    fn hits_scalar(&self, ray: &WideRay, t_max: f32, entry: &mut [f32; WIDTH]) -> u32 {
        let mut mask = 0;
        for (c, entry_c) in entry.iter_mut().enumerate() {
            let mut t0 = ray.t_min;
            let mut t1 = t_max;
            for a in 0..3 {
                let (lo, hi) = (self.lo[a][c], self.hi[a][c]);
                let (near, far) = if ray.neg[a] { (hi, lo) } else { (lo, hi) };
                t0 = t0.max((near - ray.o[a]) * ray.inv[a]);
                t1 = t1.min((far - ray.o[a]) * ray.inv[a]);
            }
            *entry_c = t0;
            if t0 <= t1 * EXIT_SLACK {
                mask |= 1 << c;
            }
        }
        mask
    }

    /// Eight children per register (16-wide nodes take two passes).
    /// `_mm256_max_ps(a, b)` and `_mm256_min_ps(a, b)` return `b` when either
    /// operand is NaN, so NaN slab distances (first operand) leave the
    /// accumulated interval as it was, like the scalar test.
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    ///
    /// # Safety
    /// Only from code compiled with `avx2`, on a CPU that has it.
    unsafe fn hits_avx2(&self, ray: &WideRay, t_max: f32, entry: &mut [f32; WIDTH]) -> u32 {
        use std::arch::x86_64::*;
        const _: () = assert!(WIDTH == 16 || WIDTH == 8 || WIDTH == 4);
        if WIDTH == 4 {
            return hits4(self, ray, t_max, entry);
        }
        let mut mask = 0;
        for half in 0..WIDTH / 8 {
            let lanes = half * 8;
            // The node is 64-byte aligned and each run of eight bounds is 32 bytes.
            let mut t0 = _mm256_set1_ps(ray.t_min);
            let mut t1 = _mm256_set1_ps(t_max);
            for a in 0..3 {
                let (near, far) = if ray.neg[a] {
                    (&self.hi[a], &self.lo[a])
                } else {
                    (&self.lo[a], &self.hi[a])
                };
                let o = _mm256_set1_ps(ray.o[a]);
                let inv = _mm256_set1_ps(ray.inv[a]);
                let bn = _mm256_load_ps(near[lanes..].as_ptr());
                let bf = _mm256_load_ps(far[lanes..].as_ptr());
                t0 = _mm256_max_ps(_mm256_mul_ps(_mm256_sub_ps(bn, o), inv), t0);
                t1 = _mm256_min_ps(_mm256_mul_ps(_mm256_sub_ps(bf, o), inv), t1);
            }
            let slack = _mm256_mul_ps(t1, _mm256_set1_ps(EXIT_SLACK));
            let inside = _mm256_cmp_ps::<_CMP_LE_OQ>(t0, slack);
            _mm256_storeu_ps(entry[lanes..].as_mut_ptr(), t0);
            mask |= (_mm256_movemask_ps(inside) as u32) << lanes;
        }
        mask
    }
}

impl WideNode {
    /// All sixteen children in one 512-bit pass (the same operations as
    /// [`hits_avx2`](Self::hits_avx2), so the same mask and entries).
    ///
    /// # Safety
    /// Only from code compiled with `avx512f`, on a CPU that has it.
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    unsafe fn hits_avx512(&self, ray: &WideRay, t_max: f32, entry: &mut [f32; WIDTH]) -> u32 {
        use std::arch::x86_64::*;
        if WIDTH != 16 {
            return self.hits_avx2(ray, t_max, entry);
        }
        let mut t0 = _mm512_set1_ps(ray.t_min);
        let mut t1 = _mm512_set1_ps(t_max);
        for a in 0..3 {
            let (near, far) = if ray.neg[a] {
                (&self.hi[a], &self.lo[a])
            } else {
                (&self.lo[a], &self.hi[a])
            };
            let o = _mm512_set1_ps(ray.o[a]);
            let inv = _mm512_set1_ps(ray.inv[a]);
            // The node is 64-byte aligned and each row of sixteen bounds is 64 bytes.
            let bn = _mm512_load_ps(near.as_ptr());
            let bf = _mm512_load_ps(far.as_ptr());
            t0 = _mm512_max_ps(_mm512_mul_ps(_mm512_sub_ps(bn, o), inv), t0);
            t1 = _mm512_min_ps(_mm512_mul_ps(_mm512_sub_ps(bf, o), inv), t1);
        }
        let slack = _mm512_mul_ps(t1, _mm512_set1_ps(EXIT_SLACK));
        _mm512_storeu_ps(entry.as_mut_ptr(), t0);
        u32::from(_mm512_cmp_ps_mask::<_CMP_LE_OQ>(t0, slack))
    }
}

/// The SSE version for 4-wide nodes (the same operations on four lanes).
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn hits4(node: &WideNode, ray: &WideRay, t_max: f32, entry: &mut [f32; WIDTH]) -> u32 {
    use std::arch::x86_64::*;
    // SAFETY: SSE is part of x86-64; each row holds WIDTH = 4 floats at a 16-byte
    // aligned offset of the 64-byte aligned node.
    unsafe {
        let mut t0 = _mm_set1_ps(ray.t_min);
        let mut t1 = _mm_set1_ps(t_max);
        for a in 0..3 {
            let (near, far) = if ray.neg[a] {
                (&node.hi[a], &node.lo[a])
            } else {
                (&node.lo[a], &node.hi[a])
            };
            let o = _mm_set1_ps(ray.o[a]);
            let inv = _mm_set1_ps(ray.inv[a]);
            let tn = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(near.as_ptr()), o), inv);
            let tf = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(far.as_ptr()), o), inv);
            t0 = _mm_max_ps(tn, t0);
            t1 = _mm_min_ps(tf, t1);
        }
        let inside = _mm_cmple_ps(t0, _mm_mul_ps(t1, _mm_set1_ps(EXIT_SLACK)));
        _mm_storeu_ps(entry.as_mut_ptr(), t0);
        _mm_movemask_ps(inside) as u32
    }
}

/// Per-ray setup of the slab test: origin and reciprocal direction per axis,
/// and whether the direction is negative (sign bit, so `−0` counts), which picks
/// the near and far bound without `min`/`max` of the two slab distances.
///
/// A direction component of `±0` gives an infinite reciprocal; if the origin lies
/// exactly on that slab's plane the distance is `0·∞ = NaN`. Such a slab does not
/// constrain the ray; every version of the test ignores NaN distances.
#[derive(Clone, Copy, Debug)]
pub(crate) struct WideRay {
    pub o: [f32; 3],
    pub inv: [f32; 3],
    pub neg: [bool; 3],
    pub t_min: f32,
}

impl WideRay {
    pub fn new(ray: &Ray) -> Self {
        WideRay {
            o: ray.o.to_array(),
            inv: ray.d.recip().to_array(),
            neg: ray.d.to_array().map(f32::is_sign_negative),
            t_min: ray.t_min,
        }
    }
}

/// One ray against all child boxes of a node: returns the mask of entered
/// children and writes their entry distances.
pub(crate) trait BoxTest {
    fn hits(ray: &WideRay, node: &WideNode, t_max: f32, entry: &mut [f32; WIDTH]) -> u32;
}

/// The portable box test.
pub(crate) struct ScalarBoxes;

impl BoxTest for ScalarBoxes {
    #[inline(always)]
    fn hits(ray: &WideRay, node: &WideNode, t_max: f32, entry: &mut [f32; WIDTH]) -> u32 {
        node.hits_scalar(ray, t_max, entry)
    }
}

/// The AVX2 box test (a 16-wide node in two passes).
#[cfg(target_arch = "x86_64")]
pub(crate) struct Avx2Boxes;

#[cfg(target_arch = "x86_64")]
impl BoxTest for Avx2Boxes {
    #[inline(always)]
    fn hits(ray: &WideRay, node: &WideNode, t_max: f32, entry: &mut [f32; WIDTH]) -> u32 {
        // SAFETY: only reached from functions compiled with `avx2` after runtime
        // detection (see `simd_available`).
        unsafe { node.hits_avx2(ray, t_max, entry) }
    }
}

/// The AVX-512 box test: sixteen children in one pass.
#[cfg(target_arch = "x86_64")]
pub(crate) struct Avx512Boxes;

#[cfg(target_arch = "x86_64")]
impl BoxTest for Avx512Boxes {
    #[inline(always)]
    fn hits(ray: &WideRay, node: &WideNode, t_max: f32, entry: &mut [f32; WIDTH]) -> u32 {
        // SAFETY: only reached from functions compiled with `avx512f` after runtime
        // detection (see `avx512_available`).
        unsafe { node.hits_avx512(ray, t_max, entry) }
    }
}

/// Whether the AVX-512 box test may run: the instruction set `dispatch` would use
/// outside the unit tests (this CPU's, within the `--simd` cap) includes AVX-512.
/// Asked per ray; the detection behind it is kept after its first answer.
#[inline(always)]
pub(crate) fn avx512_available() -> bool {
    crate::lanes::capped_instruction_set() >= crate::lanes::InstructionSet::Avx512
}

/// Whether the AVX2 box test (and the SIMD leaf test) may run: as
/// [`avx512_available`], for AVX2.
#[inline(always)]
pub(crate) fn simd_available() -> bool {
    crate::lanes::capped_instruction_set() >= crate::lanes::InstructionSet::Avx2
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;
    use glam::Vec3;

    fn node_with(boxes: &[Aabb]) -> WideNode {
        let children: Vec<(Aabb, ChildRef)> = boxes
            .iter()
            .enumerate()
            .map(|(c, &b)| (b, ChildRef::leaf(c as u32, 1)))
            .collect();
        WideNode::new(&children)
    }

    /// Scalar and SIMD agree bit for bit; returns the mask.
    fn both(r: &Ray, node: &WideNode, t_max: f32) -> u32 {
        let wr = WideRay::new(r);
        let mut e = [0.0; WIDTH];
        let m = ScalarBoxes::hits(&wr, node, t_max, &mut e);
        #[cfg(target_arch = "x86_64")]
        {
            use crate::lanes::{widest_instruction_set, InstructionSet};
            let widest = widest_instruction_set();
            type Test = unsafe fn(&WideRay, &WideNode, f32, &mut [f32; WIDTH]) -> u32;
            let tests: [(InstructionSet, Test); 2] = [
                (InstructionSet::Avx2, avx2_hits),
                (InstructionSet::Avx512, avx512_hits),
            ];
            for (set, test) in tests {
                if widest < set {
                    continue;
                }
                let mut e2 = [0.0; WIDTH];
                // SAFETY: this CPU has the instruction set.
                let m2 = unsafe { test(&wr, node, t_max, &mut e2) };
                assert_eq!(m, m2, "{set:?} {r:?}");
                for c in 0..WIDTH {
                    if m & 1 << c != 0 {
                        assert_eq!(e[c].to_bits(), e2[c].to_bits(), "{set:?} {r:?}");
                    }
                }
            }
        }
        m
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f,avx2")]
    unsafe fn avx512_hits(
        wr: &WideRay,
        node: &WideNode,
        t_max: f32,
        entry: &mut [f32; WIDTH],
    ) -> u32 {
        Avx512Boxes::hits(wr, node, t_max, entry)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn avx2_hits(
        wr: &WideRay,
        node: &WideNode,
        t_max: f32,
        entry: &mut [f32; WIDTH],
    ) -> u32 {
        Avx2Boxes::hits(wr, node, t_max, entry)
    }

    fn two_boxes() -> WideNode {
        node_with(&[
            Aabb::new(Vec3::ZERO, Vec3::ONE),
            Aabb::new(Vec3::new(2.0, 0.0, 0.0), Vec3::new(3.0, 1.0, 1.0)),
        ])
    }

    #[test]
    fn slab_test_orders_and_culls() {
        let n = two_boxes();
        let r = Ray::new(Vec3::new(-1.0, 0.5, 0.5), Vec3::X);
        let mut e = [0.0; WIDTH];
        let m = ScalarBoxes::hits(&WideRay::new(&r), &n, f32::INFINITY, &mut e);
        assert_eq!((m, e[0], e[1]), (3, 1.0, 3.0));
        assert_eq!(both(&r, &n, f32::INFINITY), 3);
        assert_eq!(both(&r, &n, 2.5), 1);
        let back = Ray::new(Vec3::new(4.0, 0.5, 0.5), -Vec3::X);
        assert_eq!(both(&back, &n, f32::INFINITY), 3);
        let miss = Ray::new(Vec3::new(-1.0, 1.5, 0.5), Vec3::X);
        assert_eq!(both(&miss, &n, f32::INFINITY), 0);
    }

    #[test]
    fn slab_test_handles_parallel_rays_on_faces() {
        let n = two_boxes();
        for d in [Vec3::new(0.0, 0.0, 1.0), Vec3::new(-0.0, 0.0, 1.0)] {
            let r = Ray::new(Vec3::new(0.0, 0.5, -1.0), d);
            assert_eq!(both(&r, &n, f32::INFINITY), 1);
            let r = Ray::new(Vec3::new(1.0, 1.0, -1.0), d);
            assert_eq!(both(&r, &n, f32::INFINITY), 1);
            let r = Ray::new(Vec3::new(-1e-7, 0.5, -1.0), d);
            assert_eq!(both(&r, &n, f32::INFINITY), 0);
            let r = Ray::new(Vec3::new(2.0, 0.0, -1.0), d);
            assert_eq!(both(&r, &n, f32::INFINITY), 2);
        }
        let r = Ray::new(Vec3::new(0.5, 0.5, -1.0), Vec3::Z);
        assert_eq!(both(&r, &n, 0.5), 0);
        assert_eq!(both(&r, &n, 1.0), 1);
        let inside = Ray::new(Vec3::splat(0.5), Vec3::new(-1.0, 2.0, 0.5));
        assert_eq!(both(&inside, &n, f32::INFINITY), 1);
    }

    /// Random boxes against random, axis-aligned, face-grazing and corner rays.
    #[test]
    fn simd_box_test_matches_scalar_on_random_and_adversarial_rays() {
        let mut rng = Rng::from_seed(5);
        let mut v = || Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 4.0 - 2.0;
        for _ in 0..2000 {
            let boxes: Vec<Aabb> = (0..WIDTH)
                .map(|_| {
                    let (a, b) = (v(), v());
                    Aabb::new(a.min(b), a.max(b))
                })
                .collect();
            let boxes = &boxes[..1 + (v().x.abs() * 3.5) as usize % WIDTH];
            let n = node_with(boxes);
            let corner = boxes[0].max;
            let rays = [
                Ray::new(v(), v()),
                Ray::new(v(), Vec3::X),
                Ray::new(v(), -Vec3::Y),
                Ray::new(Vec3::new(corner.x, corner.y, -3.0), Vec3::Z),
                Ray::new(
                    Vec3::new(boxes[0].min.x, 0.0, 0.0),
                    Vec3::new(0.0, v().y, v().z),
                ),
                Ray::new(corner, v()),
            ];
            for r in rays {
                for t_max in [f32::INFINITY, 1.0] {
                    both(&r, &n, t_max);
                }
            }
        }
    }
}
