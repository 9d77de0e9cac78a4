//! The 32-byte BVH node and the ray-box slab test.

use crate::geometry::ray::gamma;
use crate::geometry::{Aabb, Ray};
use glam::Vec3;

/// A node of the flat, depth-first node array. The first child of an inner node
/// is the next node; `offset` names the second. `min` and `max` are each followed
/// by a `u32` so one aligned 16-byte load fetches a bound (the fourth lane is
/// ignored by the slab test).
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

    #[inline(always)]
    pub fn axis(&self) -> usize {
        (self.count_axis & 3) as usize
    }

    pub fn bounds(&self) -> Aabb {
        Aabb::new(Vec3::from_array(self.min), Vec3::from_array(self.max))
    }
}

/// Slack on the exit distance so rounding in the slab test never culls a box the
/// ray touches (pbrt's `1 + 2γ(3)`).
const EXIT_SLACK: f32 = 1.0 + 2.0 * gamma(3);

/// Per-ray setup of the slab test: origin, reciprocal direction and, per axis,
/// whether the direction is negative (sign bit, so `−0` counts), which picks the
/// near and far bound without `min`/`max` of the two slab distances.
///
/// A direction component of `±0` gives an infinite reciprocal; if the origin lies
/// exactly on that slab's plane the distance is `0·∞ = NaN`. Such a slab does not
/// constrain the ray, and both versions of the test below ignore NaN distances.
#[derive(Clone, Copy, Debug)]
pub(crate) struct RayBox {
    o: [f32; 4],
    inv: [f32; 4],
    /// All-ones lanes where the direction is negative.
    neg: [u32; 4],
    t_min: f32,
    /// The same in registers (building them per node would cost loads that debug
    /// builds also bounds-check).
    #[cfg(target_arch = "x86_64")]
    simd: SimdRay,
}

#[cfg(target_arch = "x86_64")]
#[derive(Clone, Copy, Debug)]
struct SimdRay {
    o: std::arch::x86_64::__m128,
    inv: std::arch::x86_64::__m128,
    neg: std::arch::x86_64::__m128,
    t_min: std::arch::x86_64::__m128,
    xyz: std::arch::x86_64::__m128,
}

#[cfg(target_arch = "x86_64")]
impl SimdRay {
    fn new(o: [f32; 4], inv: [f32; 4], neg: [u32; 4], t_min: f32) -> Self {
        use std::arch::x86_64::*;
        let bits = |v: u32| v as i32;
        // SAFETY: SSE2 is part of the x86_64 baseline; these only build registers.
        unsafe {
            SimdRay {
                o: _mm_set_ps(o[3], o[2], o[1], o[0]),
                inv: _mm_set_ps(inv[3], inv[2], inv[1], inv[0]),
                neg: _mm_castsi128_ps(_mm_set_epi32(
                    bits(neg[3]),
                    bits(neg[2]),
                    bits(neg[1]),
                    bits(neg[0]),
                )),
                t_min: _mm_set1_ps(t_min),
                xyz: _mm_castsi128_ps(_mm_set_epi32(0, -1, -1, -1)),
            }
        }
    }
}

impl RayBox {
    pub fn new(ray: &Ray) -> Self {
        let inv = ray.d.recip();
        let neg = |v: f32| if v.is_sign_negative() { u32::MAX } else { 0 };
        let o = [ray.o.x, ray.o.y, ray.o.z, 0.0];
        let inv = [inv.x, inv.y, inv.z, 0.0];
        let neg = [neg(ray.d.x), neg(ray.d.y), neg(ray.d.z), 0];
        RayBox {
            o,
            inv,
            neg,
            t_min: ray.t_min,
            #[cfg(target_arch = "x86_64")]
            simd: SimdRay::new(o, inv, neg, ray.t_min),
        }
    }

    /// Whether the direction is negative along `axis` (the far child comes first).
    #[inline(always)]
    pub fn dir_negative(&self, axis: usize) -> bool {
        self.neg[axis] != 0
    }

    /// Whether the ray overlaps the node's box within `[t_min, t_max]`.
    #[inline(always)]
    pub fn hits(&self, node: &BvhNode, t_max: f32) -> bool {
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
    pub fn hits_scalar(&self, node: &BvhNode, t_max: f32) -> bool {
        let mut entry = self.t_min;
        let mut exit = t_max;
        for a in 0..3 {
            let (near, far) = if self.neg[a] != 0 {
                (node.max[a], node.min[a])
            } else {
                (node.min[a], node.max[a])
            };
            entry = entry.max((near - self.o[a]) * self.inv[a]);
            exit = exit.min((far - self.o[a]) * self.inv[a]);
        }
        entry <= exit * EXIT_SLACK
    }

    /// SSE2 version. `_mm_max_ps(a, b)` and `_mm_min_ps(a, b)` return `b` when
    /// either operand is NaN, so NaN slab distances (first operand) fall back to
    /// the ray's interval.
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    pub fn hits_sse(&self, node: &BvhNode, t_max: f32) -> bool {
        use std::arch::x86_64::*;
        let SimdRay {
            o,
            inv,
            neg,
            t_min,
            xyz,
        } = self.simd;
        // SAFETY: BvhNode is repr(C, align(32)) with `min`+`offset` and
        // `max`+`count_axis` as two aligned 16-byte halves. SSE2 is part of the
        // x86_64 baseline.
        unsafe {
            let p = node as *const BvhNode as *const __m128;
            // The fourth lanes hold small integers, i.e. denormals as floats, which
            // cost a microcode assist per multiply on some CPUs: clear them.
            let lo = _mm_and_ps(*p, xyz);
            let hi = _mm_and_ps(*p.add(1), xyz);
            let swap = _mm_and_ps(_mm_xor_ps(lo, hi), neg);
            let near = _mm_xor_ps(lo, swap);
            let far = _mm_xor_ps(hi, swap);
            let tn = _mm_mul_ps(_mm_sub_ps(near, o), inv);
            let tf = _mm_mul_ps(_mm_sub_ps(far, o), inv);
            let tn = _mm_max_ps(tn, t_min);
            let tf = _mm_min_ps(tf, _mm_set1_ps(t_max));
            let entry = _mm_max_ps(
                _mm_max_ps(tn, _mm_shuffle_ps(tn, tn, 0x55)),
                _mm_shuffle_ps(tn, tn, 0xAA),
            );
            let exit = _mm_min_ps(
                _mm_min_ps(tf, _mm_shuffle_ps(tf, tf, 0x55)),
                _mm_shuffle_ps(tf, tf, 0xAA),
            );
            _mm_cvtss_f32(entry) <= _mm_cvtss_f32(exit) * EXIT_SLACK
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit_node() -> BvhNode {
        BvhNode::leaf(&Aabb::new(Vec3::ZERO, Vec3::ONE), 7, 3)
    }

    fn both(rb: &RayBox, node: &BvhNode, t_max: f32) -> bool {
        let s = rb.hits_scalar(node, t_max);
        #[cfg(target_arch = "x86_64")]
        assert_eq!(s, rb.hits_sse(node, t_max));
        s
    }

    #[test]
    fn encodes_leaf_and_inner() {
        let n = unit_node();
        assert_eq!((n.count(), n.offset), (3, 7));
        let i = BvhNode::inner(&n.bounds(), 42, 2);
        assert_eq!((i.count(), i.offset, i.axis()), (0, 42, 2));
    }

    #[test]
    fn slab_test_handles_parallel_rays_on_faces() {
        let n = unit_node();
        // Origin on the x = 0 face, direction with zero x: the box is touched.
        for d in [Vec3::new(0.0, 0.0, 1.0), Vec3::new(-0.0, 0.0, 1.0)] {
            let r = Ray::new(Vec3::new(0.0, 0.5, -1.0), d);
            assert!(both(&RayBox::new(&r), &n, f32::INFINITY));
            let r = Ray::new(Vec3::new(1.0, 1.0, -1.0), d);
            assert!(both(&RayBox::new(&r), &n, f32::INFINITY));
            let r = Ray::new(Vec3::new(-1e-7, 0.5, -1.0), d);
            assert!(!both(&RayBox::new(&r), &n, f32::INFINITY));
        }
        let r = Ray::new(Vec3::new(0.5, 0.5, -1.0), Vec3::Z);
        assert!(!both(&RayBox::new(&r), &n, 0.5));
        assert!(both(&RayBox::new(&r), &n, 1.0));
        let behind = Ray::new(Vec3::new(0.5, 0.5, 2.0), Vec3::Z);
        assert!(!both(&RayBox::new(&behind), &n, f32::INFINITY));
        let inside = Ray::new(Vec3::splat(0.5), Vec3::new(-1.0, 2.0, 0.5));
        assert!(both(&RayBox::new(&inside), &n, f32::INFINITY));
    }
}
