//! Wide nodes with their child boxes as `f32`: 448 bytes for 16 children. The
//! layout of trees small enough to stay in the caches, where a box test that
//! reads its bounds directly beats the quantised one (see `Bvh::build`).

use super::wide::{ChildRef, WideNode, WideRay, EXIT_SLACK, WIDTH};
use crate::geometry::Aabb;

/// `lo[a][c]`, `hi[a][c]`: the bounds of child `c` on axis `a`. Unused slots hold
/// the empty box (`+∞`, `−∞`), which every ray misses.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(32))]
pub(crate) struct FloatNode {
    lo: [[f32; WIDTH]; 3],
    hi: [[f32; WIDTH]; 3],
    children: [ChildRef; WIDTH],
}

/// A node without children (no ray enters it).
impl Default for FloatNode {
    fn default() -> Self {
        FloatNode {
            lo: [[f32::INFINITY; WIDTH]; 3],
            hi: [[f32::NEG_INFINITY; WIDTH]; 3],
            children: [ChildRef::default(); WIDTH],
        }
    }
}

impl WideNode for FloatNode {
    fn new(children: &[(Aabb, ChildRef)]) -> Self {
        assert!(!children.is_empty() && children.len() <= WIDTH);
        let mut node = FloatNode::default();
        for (c, &(b, child)) in children.iter().enumerate() {
            for a in 0..3 {
                node.lo[a][c] = b.min[a];
                node.hi[a][c] = b.max[a];
            }
            node.children[c] = child;
        }
        node
    }

    #[inline(always)]
    fn child(&self, c: usize) -> ChildRef {
        self.children[c]
    }

    fn children_mut(&mut self) -> &mut [ChildRef] {
        let len = self.len();
        &mut self.children[..len]
    }

    fn child_bounds(&self, c: usize) -> Aabb {
        Aabb::new(
            glam::Vec3::new(self.lo[0][c], self.lo[1][c], self.lo[2][c]),
            glam::Vec3::new(self.hi[0][c], self.hi[1][c], self.hi[2][c]),
        )
    }

    fn len(&self) -> usize {
        (0..WIDTH)
            .take_while(|&c| self.lo[0][c] <= self.hi[0][c])
            .count()
    }

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
    unsafe fn hits_avx2(&self, ray: &WideRay, t_max: f32, entry: &mut [f32; WIDTH]) -> u32 {
        use std::arch::x86_64::*;
        const _: () = assert!(WIDTH == 16 || WIDTH == 8 || WIDTH == 4);
        if WIDTH == 4 {
            return hits4(self, ray, t_max, entry);
        }
        let mut mask = 0;
        for half in 0..WIDTH / 8 {
            let lanes = half * 8;
            // The node is 32-byte aligned and each run of eight bounds is 32 bytes.
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

/// The SSE version for 4-wide nodes (the same operations on four lanes).
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn hits4(node: &FloatNode, ray: &WideRay, t_max: f32, entry: &mut [f32; WIDTH]) -> u32 {
    use std::arch::x86_64::*;
    // SAFETY: SSE is part of x86-64; each row holds WIDTH = 4 floats at a 16-byte
    // aligned offset of the 32-byte aligned node.
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

#[cfg(test)]
mod tests {
    use super::super::wide::tests as common;
    use super::*;

    #[test]
    fn slab_test_orders_and_culls() {
        common::slab_test_orders_and_culls::<FloatNode>();
    }

    #[test]
    fn slab_test_handles_parallel_rays_on_faces() {
        common::slab_test_handles_parallel_rays_on_faces::<FloatNode>();
    }

    #[test]
    fn simd_box_test_matches_scalar_on_random_and_adversarial_rays() {
        common::simd_box_test_matches_scalar_on_random_and_adversarial_rays::<FloatNode>();
    }
}
