//! Wide nodes with their child boxes quantised to a byte per coordinate: 192
//! bytes for 16 children. The layout of large trees, whose traversal waits on
//! memory (see `Bvh::build`).

#[cfg(doc)]
use super::wide::FloatNode;
use super::wide::{ChildRef, WideNode, WideRay, EXIT_SLACK, WIDTH};
use crate::geometry::Aabb;

/// A wide node with its child boxes quantised to 8 bits per coordinate (Embree's
/// compressed nodes, Ylitie et al.'s CWBVH): on axis `a`, child `c` spans
/// `[dequantize(a, lo[a][c]), dequantize(a, hi[a][c])]`. Large meshes are memory
/// bound, and this is 192 bytes (three cache lines) where a [`FloatNode`] takes 448.
///
/// Quantised boxes are conservative, bit for bit as traversal computes them: the
/// build checks each bound through [`dequantize`] itself and moves it outwards
/// until it contains the exact one. A ray can only enter more boxes, never fewer,
/// so leaves (whose test is exact) find the same hits.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(64))]
pub(crate) struct QuantizedNode {
    /// The grid per axis: its first point and the (power of two) step between points.
    origin: [f32; 3],
    scale: [f32; 3],
    lo: [[u8; WIDTH]; 3],
    hi: [[u8; WIDTH]; 3],
    children: [ChildRef; WIDTH],
    /// Bit `c` set when slot `c` holds a child; the box tests return only these.
    used: u32,
}

const _: () = assert!(WIDTH != 8 || std::mem::size_of::<QuantizedNode>() == 128);
const _: () = assert!(WIDTH != 16 || std::mem::size_of::<QuantizedNode>() == 192);

/// A node without children (no ray enters it): a placeholder while building.
impl Default for QuantizedNode {
    fn default() -> Self {
        QuantizedNode {
            origin: [0.0; 3],
            scale: [0.0; 3],
            lo: [[0; WIDTH]; 3],
            hi: [[0; WIDTH]; 3],
            children: [ChildRef::default(); WIDTH],
            used: 0,
        }
    }
}

/// A quantised coordinate in world space; the one formula the build checks and
/// every box test computes (a multiplication then an addition, never fused).
#[inline(always)]
fn dequantize(origin: f32, scale: f32, q: u8) -> f32 {
    origin + f32::from(q) * scale
}

/// The grid of one axis over the finite interval `[lo, hi]`: it starts at `lo`, and
/// its step is the least power of two whose 255th point is at least `hi` (the
/// products of a power of two are exact, so only the addition rounds). A flat
/// interval gets step 0: every point is `lo`.
fn grid(lo: f32, hi: f32) -> (f32, f32) {
    let extent = f64::from(hi) - f64::from(lo);
    if extent <= 0.0 {
        return (lo, 0.0);
    }
    // ⌈log₂(extent / 255)⌉ from the bits: the exponent, plus one unless a power of two.
    let bits = (extent / 255.0).to_bits();
    let exponent = ((bits >> 52) & 0x7ff) as i32 - 1023 + i32::from(bits & ((1 << 52) - 1) != 0);
    let mut scale = f32::from_bits(((exponent.clamp(-126, 127) + 127) as u32) << 23);
    // The check guards the rounding of the addition. (At 2¹²⁷ the last point is
    // +∞, which contains anything.)
    while dequantize(lo, scale, 255) < hi {
        scale *= 2.0;
    }
    (lo, scale)
}

/// The grid points of each box on one axis: the highest at or below `lo[c]` and
/// the lowest at or above `hi[c]`, all within `[origin, origin + 255·scale]`.
///
/// The position `(x − origin)·scale⁻¹` (the reciprocal of a power of two is
/// exact, so only the subtraction rounds, by far less than one grid step) has a
/// floor or ceiling at most one point off the exact one; one step checked
/// through [`dequantize`] corrects that. In `f32` and without branches, lane by
/// lane, so the compiler makes SIMD of it; every box is then checked, and the
/// rare ones this misses (near the ends of the float range, where the
/// subtraction or `q·scale` overflows) are walked to their point one step at a
/// time.
fn quantize(
    origin: f32,
    scale: f32,
    lo: &[f32; WIDTH],
    hi: &[f32; WIDTH],
) -> ([u8; WIDTH], [u8; WIDTH]) {
    if scale == 0.0 {
        return ([0; WIDTH], [0; WIDTH]);
    }
    let inverse = 1.0 / scale;
    let mut q_lo = [0u8; WIDTH];
    let mut q_hi = [0u8; WIDTH];
    for c in 0..WIDTH {
        // Truncation is the floor of a non-negative position.
        let q = ((lo[c] - origin) * inverse).clamp(0.0, 255.0) as i32;
        let q = q - i32::from(q > 0 && dequantize(origin, scale, q as u8) > lo[c]);
        q_lo[c] = q as u8;
        let p = ((hi[c] - origin) * inverse).clamp(0.0, 255.0);
        let q = p as i32;
        let q = q + i32::from((q as f32) < p);
        let q = q + i32::from(q < 255 && dequantize(origin, scale, q as u8) < hi[c]);
        q_hi[c] = q as u8;
    }
    let contains = |c: usize, q_lo: &[u8; WIDTH], q_hi: &[u8; WIDTH]| {
        dequantize(origin, scale, q_lo[c]) <= lo[c] && dequantize(origin, scale, q_hi[c]) >= hi[c]
    };
    for c in 0..WIDTH {
        // Only near the ends of the float range (where `q·scale` overflows) is one
        // step not enough.
        if !contains(c, &q_lo, &q_hi) {
            while q_lo[c] > 0 && dequantize(origin, scale, q_lo[c]) > lo[c] {
                q_lo[c] -= 1;
            }
            while q_hi[c] < 255 && dequantize(origin, scale, q_hi[c]) < hi[c] {
                q_hi[c] += 1;
            }
            assert!(
                contains(c, &q_lo, &q_hi),
                "a quantised box contains its child's box"
            );
        }
    }
    (q_lo, q_hi)
}

impl WideNode for QuantizedNode {
    fn new(children: &[(Aabb, ChildRef)]) -> Self {
        assert!(!children.is_empty() && children.len() <= WIDTH);
        let mut node = QuantizedNode {
            used: (1 << children.len()) - 1,
            ..QuantizedNode::default()
        };
        for axis in 0..3 {
            // Unused slots repeat the first child, so every lane holds a real box.
            let lo: [f32; WIDTH] =
                std::array::from_fn(|c| children.get(c).unwrap_or(&children[0]).0.min[axis]);
            let hi: [f32; WIDTH] =
                std::array::from_fn(|c| children.get(c).unwrap_or(&children[0]).0.max[axis]);
            let (origin, scale) = grid(
                lo.iter().copied().fold(f32::INFINITY, f32::min),
                hi.iter().copied().fold(f32::NEG_INFINITY, f32::max),
            );
            node.origin[axis] = origin;
            node.scale[axis] = scale;
            (node.lo[axis], node.hi[axis]) = quantize(origin, scale, &lo, &hi);
        }
        for (c, &(_, child)) in children.iter().enumerate() {
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

    fn len(&self) -> usize {
        self.used.count_ones() as usize
    }

    fn child_bounds(&self, c: usize) -> Aabb {
        let at =
            |a: usize, q: &[[u8; WIDTH]; 3]| dequantize(self.origin[a], self.scale[a], q[a][c]);
        Aabb::new(
            glam::Vec3::new(at(0, &self.lo), at(1, &self.lo), at(2, &self.lo)),
            glam::Vec3::new(at(0, &self.hi), at(1, &self.hi), at(2, &self.hi)),
        )
    }

    #[inline(always)]
    fn hits_scalar(&self, ray: &WideRay, t_max: f32, entry: &mut [f32; WIDTH]) -> u32 {
        let mut mask = 0;
        for (c, entry_c) in entry.iter_mut().enumerate() {
            let mut t0 = ray.t_min;
            let mut t1 = t_max;
            for a in 0..3 {
                let (origin, scale) = (self.origin[a], self.scale[a]);
                let lo = dequantize(origin, scale, self.lo[a][c]);
                let hi = dequantize(origin, scale, self.hi[a][c]);
                let (near, far) = if ray.neg[a] { (hi, lo) } else { (lo, hi) };
                t0 = t0.max((near - ray.o[a]) * ray.inv[a]);
                t1 = t1.min((far - ray.o[a]) * ray.inv[a]);
            }
            *entry_c = t0;
            if t0 <= t1 * EXIT_SLACK {
                mask |= 1 << c;
            }
        }
        mask & self.used
    }

    /// Eight children per register (16-wide nodes take two passes), dequantised
    /// in the lanes with the scalar operations; NaN slab distances are ignored
    /// as in `FloatNode`'s test.
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
            // Each run of eight quantised bounds is read by one 8-byte load.
            let mut t0 = _mm256_set1_ps(ray.t_min);
            let mut t1 = _mm256_set1_ps(t_max);
            for a in 0..3 {
                let (near, far) = if ray.neg[a] {
                    (&self.hi[a], &self.lo[a])
                } else {
                    (&self.lo[a], &self.hi[a])
                };
                let origin = _mm256_set1_ps(self.origin[a]);
                let scale = _mm256_set1_ps(self.scale[a]);
                let o = _mm256_set1_ps(ray.o[a]);
                let inv = _mm256_set1_ps(ray.inv[a]);
                // `dequantize` in eight lanes: exact conversion, multiply, add.
                let qn = _mm256_cvtepu8_epi32(_mm_loadl_epi64(near[lanes..].as_ptr().cast()));
                let qf = _mm256_cvtepu8_epi32(_mm_loadl_epi64(far[lanes..].as_ptr().cast()));
                let bn = _mm256_add_ps(origin, _mm256_mul_ps(_mm256_cvtepi32_ps(qn), scale));
                let bf = _mm256_add_ps(origin, _mm256_mul_ps(_mm256_cvtepi32_ps(qf), scale));
                t0 = _mm256_max_ps(_mm256_mul_ps(_mm256_sub_ps(bn, o), inv), t0);
                t1 = _mm256_min_ps(_mm256_mul_ps(_mm256_sub_ps(bf, o), inv), t1);
            }
            let slack = _mm256_mul_ps(t1, _mm256_set1_ps(EXIT_SLACK));
            let inside = _mm256_cmp_ps::<_CMP_LE_OQ>(t0, slack);
            _mm256_storeu_ps(entry[lanes..].as_mut_ptr(), t0);
            mask |= (_mm256_movemask_ps(inside) as u32) << lanes;
        }
        mask & self.used
    }
}

/// The SSE version for 4-wide nodes (the same operations on four lanes).
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn hits4(node: &QuantizedNode, ray: &WideRay, t_max: f32, entry: &mut [f32; WIDTH]) -> u32 {
    use std::arch::x86_64::*;
    // SAFETY: SSE4.1 comes with the AVX2 this runs under; each row of quantised
    // bounds is WIDTH = 4 bytes, read by one 4-byte load.
    unsafe {
        let mut t0 = _mm_set1_ps(ray.t_min);
        let mut t1 = _mm_set1_ps(t_max);
        for a in 0..3 {
            let (near, far) = if ray.neg[a] {
                (&node.hi[a], &node.lo[a])
            } else {
                (&node.lo[a], &node.hi[a])
            };
            let origin = _mm_set1_ps(node.origin[a]);
            let scale = _mm_set1_ps(node.scale[a]);
            let bound = |row: &[u8; WIDTH]| {
                let bytes = i32::from_le_bytes([row[0], row[1], row[2], row[3]]);
                let q = _mm_cvtepu8_epi32(_mm_cvtsi32_si128(bytes));
                _mm_add_ps(origin, _mm_mul_ps(_mm_cvtepi32_ps(q), scale))
            };
            let o = _mm_set1_ps(ray.o[a]);
            let inv = _mm_set1_ps(ray.inv[a]);
            let tn = _mm_mul_ps(_mm_sub_ps(bound(near), o), inv);
            let tf = _mm_mul_ps(_mm_sub_ps(bound(far), o), inv);
            t0 = _mm_max_ps(tn, t0);
            t1 = _mm_min_ps(tf, t1);
        }
        let inside = _mm_cmple_ps(t0, _mm_mul_ps(t1, _mm_set1_ps(EXIT_SLACK)));
        _mm_storeu_ps(entry.as_mut_ptr(), t0);
        _mm_movemask_ps(inside) as u32 & node.used
    }
}

#[cfg(test)]
mod tests {
    use super::super::wide::tests as common;
    use super::*;
    use crate::geometry::Ray;
    use crate::sampling::Sampler;
    use glam::Vec3;

    #[test]
    fn slab_test_orders_and_culls() {
        common::slab_test_orders_and_culls::<QuantizedNode>();
    }

    #[test]
    fn slab_test_handles_parallel_rays_on_faces() {
        common::slab_test_handles_parallel_rays_on_faces::<QuantizedNode>();
    }

    #[test]
    fn simd_box_test_matches_scalar_on_random_and_adversarial_rays() {
        common::simd_box_test_matches_scalar_on_random_and_adversarial_rays::<QuantizedNode>();
    }

    /// The dequantised box of every child contains its exact box, whatever the
    /// scale and position of the boxes: tiny, huge, flat, far from the origin,
    /// negative, touching, and at the ends of the float range.
    #[test]
    fn quantised_boxes_contain_the_exact_ones() {
        let mut rng = Sampler::from_seed(11);
        let check = |boxes: &[Aabb]| {
            let children: Vec<(Aabb, ChildRef)> =
                boxes.iter().map(|&b| (b, ChildRef::leaf(0, 1))).collect();
            let node = QuantizedNode::new(&children);
            assert_eq!(node.len(), boxes.len());
            for (c, b) in boxes.iter().enumerate() {
                let q = node.child_bounds(c);
                assert!(
                    q.min.cmple(b.min).all() && q.max.cmpge(b.max).all(),
                    "{b:?} in {q:?}"
                );
            }
        };
        for _ in 0..5000 {
            let centre = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) - 0.5;
            let offset = centre * 10f32.powi((rng.next_f32() * 60.0) as i32 - 30);
            let size = 10f32.powi((rng.next_f32() * 40.0) as i32 - 20);
            let n = 1 + (rng.next_f32() * WIDTH as f32) as usize % WIDTH;
            let boxes: Vec<Aabb> = (0..n)
                .map(|_| {
                    let a = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
                    let b = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
                    let flat = if rng.next_f32() < 0.2 {
                        Vec3::X
                    } else {
                        Vec3::ONE
                    };
                    let (a, b) = (offset + a * size, offset + (a + (b - a) * flat) * size);
                    Aabb::new(a.min(b), a.max(b))
                })
                .collect();
            check(&boxes);
        }
        let max = f32::MAX;
        check(&[Aabb::new(Vec3::splat(-max), Vec3::splat(max))]);
        check(&[
            Aabb::new(Vec3::splat(-max), Vec3::splat(-max / 2.0)),
            Aabb::new(Vec3::splat(max / 3.0), Vec3::splat(max)),
        ]);
        check(&[
            Aabb::new(Vec3::splat(1e-45), Vec3::splat(3e-45)),
            Aabb::new(Vec3::ZERO, Vec3::splat(1e-45)),
        ]);
        check(&[Aabb::new(Vec3::splat(1e7), Vec3::splat(1e7 + 1.0))]);
        check(&[
            Aabb::new(Vec3::splat(-1.0), Vec3::splat(-1.0)),
            Aabb::new(Vec3::splat(-1.0), Vec3::splat(-1.0)),
        ]);
    }

    /// A ray through a face shared by two touching children (the way leaves of
    /// a closed mesh touch) enters both: quantisation never opens a gap.
    #[test]
    fn touching_children_stay_touching() {
        let mut rng = Sampler::from_seed(12);
        for _ in 0..2000 {
            let split = rng.next_f32() * 3.0 - 1.0;
            let lo = Vec3::new(-1.0, rng.next_f32() - 1.0, -1.0);
            let hi = Vec3::new(2.0, rng.next_f32() + 1.0, 1.0);
            let left = Aabb::new(lo, Vec3::new(split, hi.y, hi.z));
            let right = Aabb::new(Vec3::new(split, lo.y, lo.z), hi);
            let node: QuantizedNode = common::node_with(&[left, right]);
            let y = rng.next_f32() * 0.5;
            let ray = Ray::new(Vec3::new(split, y, -3.0), Vec3::new(0.0, 0.0, 1.0));
            assert_eq!(common::both(&ray, &node, f32::INFINITY), 3, "{split}");
        }
    }
}
