//! The traversal layout: wide nodes of [`WIDTH`] children whose boxes are stored
//! per axis (structure of arrays), so one SIMD pass tests a ray against every
//! child box and yields the entry distances used to visit them nearest first.
//! The builder's binary tree is collapsed into this layout by [`super::collapse`].
//!
//! Why 8 wide: against 4 wide (SSE box test, `WIDTH = 4`; both builds otherwise
//! equal), interleaved runs on this machine (AMD EPYC, CPU time, 1 thread, native
//! over Embree robust) gave on the 998k-triangle mesh incoherent 0.71-0.73 vs
//! 0.66-0.69, shadow 0.71-0.74 vs 0.62-0.68, camera 1.13-1.15 vs 0.98-1.00, and on
//! CBbunny incoherent 1.05-1.20 vs 0.91-0.93, shadow 1.00-1.24 vs 0.79-0.93. With
//! 4 wide the tree has 1.7× the nodes (131k vs 79k) and a higher SAH cost (24.0 vs
//! 16.9), so rays visit more nodes; 8 wide wastes lanes (4.3 children per node on
//! average) but one AVX2 pass costs about what an SSE pass does. The width is this
//! one constant plus the SIMD test (both widths are kept compiling).

use crate::geometry::ray::gamma;
use crate::geometry::{Aabb, Ray};

/// Children per node.
pub(crate) const WIDTH: usize = 8;

/// Slack on the exit distance so rounding in the slab test never culls a box the
/// ray touches (pbrt's `1 + 2γ(3)`).
pub(crate) const EXIT_SLACK: f32 = 1.0 + 2.0 * gamma(3);

/// A reference to a child: an inner node (`count == 0`, `index` into the wide
/// nodes) or a leaf (`count` primitives in block `index`).
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

/// `lo[a][c]`, `hi[a][c]`: the bounds of child `c` on axis `a`. Unused slots hold
/// the empty box (`+∞`, `−∞`), which every ray misses.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(32))]
pub(crate) struct WideNode {
    pub lo: [[f32; WIDTH]; 3],
    pub hi: [[f32; WIDTH]; 3],
    pub children: [ChildRef; WIDTH],
}

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
    pub fn child_bounds(&self, c: usize) -> Aabb {
        Aabb::new(
            glam::Vec3::new(self.lo[0][c], self.lo[1][c], self.lo[2][c]),
            glam::Vec3::new(self.hi[0][c], self.hi[1][c], self.hi[2][c]),
        )
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

/// Portable version; `f32::max`/`min` return the non-NaN operand.
pub(crate) struct ScalarBoxes;

impl BoxTest for ScalarBoxes {
    #[inline(always)]
    fn hits(ray: &WideRay, node: &WideNode, t_max: f32, entry: &mut [f32; WIDTH]) -> u32 {
        let mut mask = 0;
        for (c, entry_c) in entry.iter_mut().enumerate() {
            let mut t0 = ray.t_min;
            let mut t1 = t_max;
            for a in 0..3 {
                let (lo, hi) = (node.lo[a][c], node.hi[a][c]);
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
}

/// AVX2 version, eight children per register. `_mm256_max_ps(a, b)` and
/// `_mm256_min_ps(a, b)` return `b` when either operand is NaN, so NaN slab
/// distances (first operand) leave the accumulated interval as it was, exactly
/// like the scalar version.
#[cfg(target_arch = "x86_64")]
pub(crate) struct Avx2Boxes;

#[cfg(target_arch = "x86_64")]
impl BoxTest for Avx2Boxes {
    #[inline(always)]
    fn hits(ray: &WideRay, node: &WideNode, t_max: f32, entry: &mut [f32; WIDTH]) -> u32 {
        use std::arch::x86_64::*;
        const _: () = assert!(WIDTH == 8 || WIDTH == 4);
        if WIDTH == 4 {
            return hits4(ray, node, t_max, entry);
        }
        // SAFETY: only reached from functions compiled with `avx2` after runtime
        // detection (see `simd_available`); WideNode is 32-byte aligned and each
        // row is 32 bytes, so the aligned loads are in bounds.
        unsafe {
            let mut t0 = _mm256_set1_ps(ray.t_min);
            let mut t1 = _mm256_set1_ps(t_max);
            for a in 0..3 {
                let (near, far) = if ray.neg[a] {
                    (&node.hi[a], &node.lo[a])
                } else {
                    (&node.lo[a], &node.hi[a])
                };
                let o = _mm256_set1_ps(ray.o[a]);
                let inv = _mm256_set1_ps(ray.inv[a]);
                let tn = _mm256_mul_ps(_mm256_sub_ps(_mm256_load_ps(near.as_ptr()), o), inv);
                let tf = _mm256_mul_ps(_mm256_sub_ps(_mm256_load_ps(far.as_ptr()), o), inv);
                t0 = _mm256_max_ps(tn, t0);
                t1 = _mm256_min_ps(tf, t1);
            }
            let inside =
                _mm256_cmp_ps::<_CMP_LE_OQ>(t0, _mm256_mul_ps(t1, _mm256_set1_ps(EXIT_SLACK)));
            _mm256_storeu_ps(entry.as_mut_ptr(), t0);
            _mm256_movemask_ps(inside) as u32
        }
    }
}

/// The SSE version for 4-wide nodes (the same operations on four lanes).
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn hits4(ray: &WideRay, node: &WideNode, t_max: f32, entry: &mut [f32; WIDTH]) -> u32 {
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
mod tests {
    use super::*;
    use crate::sampling::Sampler;
    use glam::Vec3;

    fn node_with(boxes: &[Aabb]) -> WideNode {
        let mut n = WideNode::default();
        for (c, b) in boxes.iter().enumerate() {
            for a in 0..3 {
                n.lo[a][c] = b.min[a];
                n.hi[a][c] = b.max[a];
            }
        }
        n
    }

    /// Scalar and SIMD agree bit for bit; returns the mask.
    fn both(r: &Ray, node: &WideNode, t_max: f32) -> u32 {
        let wr = WideRay::new(r);
        let mut e = [0.0; WIDTH];
        let m = ScalarBoxes::hits(&wr, node, t_max, &mut e);
        #[cfg(target_arch = "x86_64")]
        if simd_available() {
            let mut e2 = [0.0; WIDTH];
            let m2 = Avx2Boxes::hits(&wr, node, t_max, &mut e2);
            assert_eq!(m, m2, "{r:?}");
            for c in 0..WIDTH {
                if m & 1 << c != 0 {
                    assert_eq!(e[c].to_bits(), e2[c].to_bits(), "{r:?}");
                }
            }
        }
        m
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
        let mut rng = Sampler::from_seed(5);
        let mut v = || Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 4.0 - 2.0;
        for _ in 0..2000 {
            let boxes: Vec<Aabb> = (0..WIDTH)
                .map(|_| {
                    let (a, b) = (v(), v());
                    Aabb::new(a.min(b), a.max(b))
                })
                .collect();
            let n = node_with(&boxes[..1 + (v().x.abs() * 3.5) as usize % WIDTH]);
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
                both(&r, &n, f32::INFINITY);
                both(&r, &n, 1.0);
            }
        }
    }
}
