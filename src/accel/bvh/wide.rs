//! The traversal layout: wide nodes of [`WIDTH`] children whose boxes are stored
//! per axis (structure of arrays), so one SIMD pass tests a ray against every
//! child box and yields the entry distances used to visit them nearest first.
//! The builder's binary tree is collapsed into this layout by [`super::collapse`].
//! Two node layouts share it ([`WideNode`]): boxes as `f32` ([`FloatNode`]) or
//! quantised to a byte per coordinate ([`QuantizedNode`]), see `Bvh::build` for
//! which a tree gets.
//!
//! Why 16 wide: against 8 wide (trees otherwise built alike, interleaved in one
//! process on this machine, AMD EPYC, 1 thread), the 998k-triangle mesh traced
//! incoherent rays 1.14× and shadow rays 1.15× faster, with 5.7 instead of 7.6
//! node visits per incoherent ray: its traversal waits on memory, and a level
//! less is a dependent cache miss less. CBbunny (in cache): incoherent 1.08×,
//! shadow 1.11×, camera 0.98×. A 16-wide node is two AVX2 passes. (Before the
//! quantised nodes and the SAH-optimal collapse, 8 wide had beaten 4 wide: 1.7×
//! the nodes and rays visiting more of them.) The width is this one constant;
//! 4, 8 and 16 keep compiling.

use crate::geometry::ray::gamma;
use crate::geometry::{Aabb, Ray};

pub(crate) use super::float_node::FloatNode;
pub(crate) use super::quantized_node::QuantizedNode;

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

/// A wide node layout: up to [`WIDTH`] children, slots in use from slot 0, and
/// the test of one ray against all their boxes. Both versions of the test give
/// the same bits; the AVX2 one may only run where [`simd_available`].
pub(crate) trait WideNode:
    Copy + Default + PartialEq + std::fmt::Debug + Send + Sync
{
    /// A node over `children` (1 to [`WIDTH`]), each with its exact box.
    fn new(children: &[(Aabb, ChildRef)]) -> Self;

    /// The child in slot `c` (a slot in use).
    fn child(&self, c: usize) -> ChildRef;

    /// The slots in use.
    fn children_mut(&mut self) -> &mut [ChildRef];

    /// The box traversal tests for child `c` (contains the exact one).
    fn child_bounds(&self, c: usize) -> Aabb;

    /// Slots in use.
    fn len(&self) -> usize;

    /// The mask of entered children (slots in use only), with their entry
    /// distances written to `entry`. `f32::max`/`min` return the non-NaN operand.
    fn hits_scalar(&self, ray: &WideRay, t_max: f32, entry: &mut [f32; WIDTH]) -> u32;

    /// [`WideNode::hits_scalar`] in AVX2, the same bits.
    ///
    /// # Safety
    /// Only from code compiled with `avx2`, on a CPU that has it.
    #[cfg(target_arch = "x86_64")]
    unsafe fn hits_avx2(&self, ray: &WideRay, t_max: f32, entry: &mut [f32; WIDTH]) -> u32;
}

/// One ray against all child boxes of a node: returns the mask of entered
/// children and writes their entry distances.
pub(crate) trait BoxTest {
    fn hits<N: WideNode>(ray: &WideRay, node: &N, t_max: f32, entry: &mut [f32; WIDTH]) -> u32;
}

/// The portable box test.
pub(crate) struct ScalarBoxes;

impl BoxTest for ScalarBoxes {
    #[inline(always)]
    fn hits<N: WideNode>(ray: &WideRay, node: &N, t_max: f32, entry: &mut [f32; WIDTH]) -> u32 {
        node.hits_scalar(ray, t_max, entry)
    }
}

/// The AVX2 box test, all children in one pass.
#[cfg(target_arch = "x86_64")]
pub(crate) struct Avx2Boxes;

#[cfg(target_arch = "x86_64")]
impl BoxTest for Avx2Boxes {
    #[inline(always)]
    fn hits<N: WideNode>(ray: &WideRay, node: &N, t_max: f32, entry: &mut [f32; WIDTH]) -> u32 {
        // SAFETY: only reached from functions compiled with `avx2` after runtime
        // detection (see `simd_available`).
        unsafe { node.hits_avx2(ray, t_max, entry) }
    }
}

/// Whether the SIMD box test (and the SIMD leaf test) can run on this CPU;
/// detected once (the standard library caches the CPUID result).
#[inline(always)]
pub(crate) fn simd_available() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::is_x86_feature_detected!("avx2")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

#[cfg(test)]
pub(crate) mod tests {
    //! Tests every node layout must pass; each layout's file runs them.
    use super::*;
    use crate::sampling::Sampler;
    use glam::Vec3;

    pub fn node_with<N: WideNode>(boxes: &[Aabb]) -> N {
        let children: Vec<(Aabb, ChildRef)> = boxes
            .iter()
            .enumerate()
            .map(|(c, &b)| (b, ChildRef::leaf(c as u32, 1)))
            .collect();
        N::new(&children)
    }

    /// Scalar and SIMD agree bit for bit; returns the mask.
    pub fn both<N: WideNode>(r: &Ray, node: &N, t_max: f32) -> u32 {
        let wr = WideRay::new(r);
        let mut e = [0.0; WIDTH];
        let m = ScalarBoxes::hits(&wr, node, t_max, &mut e);
        #[cfg(target_arch = "x86_64")]
        if simd_available() {
            let mut e2 = [0.0; WIDTH];
            // SAFETY: AVX2 was detected.
            let m2 = unsafe { avx2_hits(&wr, node, t_max, &mut e2) };
            assert_eq!(m, m2, "{r:?}");
            for c in 0..WIDTH {
                if m & 1 << c != 0 {
                    assert_eq!(e[c].to_bits(), e2[c].to_bits(), "{r:?}");
                }
            }
        }
        m
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn avx2_hits<N: WideNode>(
        wr: &WideRay,
        node: &N,
        t_max: f32,
        entry: &mut [f32; WIDTH],
    ) -> u32 {
        Avx2Boxes::hits(wr, node, t_max, entry)
    }

    fn two_boxes<N: WideNode>() -> N {
        node_with(&[
            Aabb::new(Vec3::ZERO, Vec3::ONE),
            Aabb::new(Vec3::new(2.0, 0.0, 0.0), Vec3::new(3.0, 1.0, 1.0)),
        ])
    }

    pub fn slab_test_orders_and_culls<N: WideNode>() {
        let n: N = two_boxes();
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

    pub fn slab_test_handles_parallel_rays_on_faces<N: WideNode>() {
        let n: N = two_boxes();
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

    /// Random boxes against random, axis-aligned, face-grazing and corner rays:
    /// SIMD and scalar agree, and every ray that enters a child's exact box (by
    /// the float slab test of an exact node) enters the node's box for it.
    pub fn simd_box_test_matches_scalar_on_random_and_adversarial_rays<N: WideNode>() {
        let mut rng = Sampler::from_seed(5);
        let mut v = || Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 4.0 - 2.0;
        for _ in 0..2000 {
            let boxes: Vec<Aabb> = (0..WIDTH)
                .map(|_| {
                    let (a, b) = (v(), v());
                    Aabb::new(a.min(b), a.max(b))
                })
                .collect();
            let boxes = &boxes[..1 + (v().x.abs() * 3.5) as usize % WIDTH];
            let n: N = node_with(boxes);
            let exact: FloatNode = node_with(boxes);
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
                    let m = both(&r, &n, t_max);
                    let m_exact = both(&r, &exact, t_max);
                    assert_eq!(m & m_exact, m_exact, "{r:?} {boxes:?}");
                }
            }
        }
    }
}
