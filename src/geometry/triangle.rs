//! Watertight ray-triangle intersection (Woop, Benthin and Wald 2013, as in
//! pbrt-v4 `IntersectTriangle`).
//!
//! The ray is sheared so that it points along +z from the origin; the test then
//! works in 2-D on the sheared corners. Every corner is transformed by exactly the
//! same operations whichever triangle it belongs to, so the edge functions of a
//! shared edge are exact negatives of each other and no ray slips between two
//! triangles. Edge functions that round to zero are recomputed in `f64`, where the
//! products are exact, so rays through edges and vertices are decided exactly.
//!
//! The work that depends only on the ray (axis permutation, shear) lives in
//! [`TriangleRay`], built once per ray; corners live transposed in
//! [`PackedTriangle`] so that one SIMD lane handles one corner.

use super::Ray;
use crate::lanes::{F32s, LaneBits, Mask, Simd, Vec3s};
use glam::{Vec3, Vec4, Vec4Swizzles};

/// A triangle hit: parametric distance and barycentrics of corners 1 and 2.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriangleHit {
    pub t: f32,
    pub b1: f32,
    pub b2: f32,
}

/// The per-ray part of the watertight test: permutation `kx, ky, kz` (with `kz`
/// the dominant axis of `d`) and the shear taking `d` to `+z`.
#[derive(Clone, Copy, Debug)]
pub struct TriangleRay {
    kx: usize,
    ky: usize,
    kz: usize,
    /// Origin components on the permuted axes, splatted over the corner lanes.
    ox: Vec4,
    oy: Vec4,
    oz: Vec4,
    sx: Vec4,
    sy: Vec4,
    sz: Vec4,
    /// Lowest accepted `t`: `t_min`, but at least the smallest normal float, so a
    /// hit at `t = 0` (the origin on the surface) never counts, as in Embree.
    pub t_lo: f32,
}

impl TriangleRay {
    pub fn new(ray: &Ray) -> Self {
        let ad = ray.d.abs();
        // pbrt's MaxComponentIndex, so ties pick the same axis as the reference.
        let kz = if ad.x > ad.y {
            if ad.x > ad.z {
                0
            } else {
                2
            }
        } else if ad.y > ad.z {
            1
        } else {
            2
        };
        let kx = if kz == 2 { 0 } else { kz + 1 };
        let ky = if kx == 2 { 0 } else { kx + 1 };
        let (d, o) = (ray.d, ray.o);
        TriangleRay {
            kx,
            ky,
            kz,
            ox: Vec4::splat(o[kx]),
            oy: Vec4::splat(o[ky]),
            oz: Vec4::splat(o[kz]),
            sx: Vec4::splat(-d[kx] / d[kz]),
            sy: Vec4::splat(-d[ky] / d[kz]),
            sz: Vec4::splat(1.0 / d[kz]),
            t_lo: ray.t_min.max(f32::MIN_POSITIVE),
        }
    }
}

/// A triangle stored transposed: `rows[a]` holds axis `a` of corners 0, 1, 2 in
/// lanes 0, 1, 2 (lane 3 is zero). 48 bytes, one aligned load per axis.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(16))]
pub struct PackedTriangle {
    rows: [Vec4; 3],
}

impl PackedTriangle {
    pub fn new(p0: Vec3, p1: Vec3, p2: Vec3) -> Self {
        PackedTriangle {
            rows: [
                Vec4::new(p0.x, p1.x, p2.x, 0.0),
                Vec4::new(p0.y, p1.y, p2.y, 0.0),
                Vec4::new(p0.z, p1.z, p2.z, 0.0),
            ],
        }
    }

    /// Corners in their original order.
    pub fn corners(&self) -> [Vec3; 3] {
        let [x, y, z] = self.rows;
        [
            Vec3::new(x.x, y.x, z.x),
            Vec3::new(x.y, y.y, z.y),
            Vec3::new(x.z, y.z, z.z),
        ]
    }

    /// The watertight test for `t ∈ [ray.t_min, t_max]`, `t > 0`. No hit is
    /// rejected for lying within the rounding error of `t` (pbrt-v4's `t ≤ δt`):
    /// that bound grows like 1/det and rejected real hits at grazing angles. Rays
    /// spawned from a triangle skip it instead (`Ray::skip`, applied by the
    /// callers). Degenerate triangles must be filtered out beforehand (see
    /// [`triangle_is_hittable`]).
    #[inline(always)]
    pub fn intersect(&self, ray: &TriangleRay, t_max: f32) -> Option<TriangleHit> {
        let xk = self.rows[ray.kx] - ray.ox;
        let yk = self.rows[ray.ky] - ray.oy;
        let zk = self.rows[ray.kz] - ray.oz;
        let xt = xk + ray.sx * zk;
        let yt = yk + ray.sy * zk;
        // Lane i: e_i = x_{i+1}·y_{i+2} − y_{i+1}·x_{i+2}.
        let mut e = xt.yzxw() * yt.zxyw() - yt.yzxw() * xt.zxyw();
        let neg = e.cmplt(Vec4::ZERO).bitmask() & 7;
        let pos = e.cmpgt(Vec4::ZERO).bitmask() & 7;
        // Rounding is monotonic, so a non-zero f32 edge function already has the
        // exact sign: mixed non-zero signs are a certain miss.
        if neg != 0 && pos != 0 {
            return None;
        }
        if neg | pos != 7 {
            e = exact_edge_functions(xt, yt);
            let neg = e.cmplt(Vec4::ZERO).bitmask() & 7;
            let pos = e.cmpgt(Vec4::ZERO).bitmask() & 7;
            if neg != 0 && pos != 0 {
                return None;
            }
        }
        let det = e.x + e.y + e.z;
        if det == 0.0 {
            return None;
        }
        let zt = ray.sz * zk;
        let t_scaled = e.x * zt.x + e.y * zt.y + e.z * zt.z;
        let inv_det = 1.0 / det;
        let t = t_scaled * inv_det;
        // Written so that NaN (a zero direction) fails.
        if !(t >= ray.t_lo && t <= t_max) {
            return None;
        }
        Some(TriangleHit {
            t,
            b1: e.y * inv_det,
            b2: e.z * inv_det,
        })
    }
}

/// Four triangles stored per corner and axis with one triangle per lane, so the
/// watertight test runs on four triangles in one pass (glam's `Vec4`, SSE on
/// x86-64). Every lane performs the same operations in the same order as
/// [`PackedTriangle::intersect`] (no fused multiply-add, an exact division), so a
/// lane's result is bit for bit the scalar test's; lanes whose edge functions
/// round to zero are handed to the scalar test and its `f64` fallback.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(16))]
pub struct Triangle4 {
    /// `p[corner][axis]`, lane `i` = triangle `i`.
    p: [[Vec4; 3]; 3],
}

/// Per-lane results of [`Triangle4::intersect`]: bit `i` of `mask` set when
/// triangle `i` is hit, at `t[i]` with barycentrics `b1[i]`, `b2[i]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hits4 {
    pub mask: u32,
    pub t: [f32; 4],
    pub b1: [f32; 4],
    pub b2: [f32; 4],
}

impl Triangle4 {
    /// Up to four triangles; missing lanes are zero (callers mask them off).
    pub fn new(tris: &[[Vec3; 3]]) -> Self {
        assert!(tris.len() <= 4);
        let mut p = [[[0.0f32; 4]; 3]; 3];
        for (lane, corners) in tris.iter().enumerate() {
            for (k, c) in corners.iter().enumerate() {
                for axis in 0..3 {
                    p[k][axis][lane] = c[axis];
                }
            }
        }
        Triangle4 {
            p: p.map(|rows| rows.map(Vec4::from_array)),
        }
    }

    /// The corners of triangle `lane`.
    #[inline(always)]
    pub fn corners(&self, lane: usize) -> [Vec3; 3] {
        std::array::from_fn(|k| {
            Vec3::new(self.p[k][0][lane], self.p[k][1][lane], self.p[k][2][lane])
        })
    }

    /// Triangle `lane` in the scalar layout.
    pub fn lane(&self, lane: usize) -> PackedTriangle {
        let c = |k: usize| Vec3::new(self.p[k][0][lane], self.p[k][1][lane], self.p[k][2][lane]);
        PackedTriangle::new(c(0), c(1), c(2))
    }

    /// The watertight test of the triangles in `lanes` (a bit mask) for
    /// `t ∈ [ray.t_min, t_max]`, with the same results as the scalar test per lane.
    #[inline(always)]
    pub fn intersect(&self, ray: &TriangleRay, t_max: f32, lanes: u32) -> Hits4 {
        let (kx, ky, kz) = (ray.kx, ray.ky, ray.kz);
        let shear = |k: usize| {
            let x = self.p[k][kx] - ray.ox;
            let y = self.p[k][ky] - ray.oy;
            let z = self.p[k][kz] - ray.oz;
            (x + ray.sx * z, y + ray.sy * z, ray.sz * z)
        };
        let (x0, y0, z0) = shear(0);
        let (x1, y1, z1) = shear(1);
        let (x2, y2, z2) = shear(2);
        let e0 = x1 * y2 - y1 * x2;
        let e1 = x2 * y0 - y2 * x0;
        let e2 = x0 * y1 - y0 * x1;
        let zero = Vec4::ZERO;
        let neg = (e0.cmplt(zero) | e1.cmplt(zero) | e2.cmplt(zero)).bitmask();
        let pos = (e0.cmpgt(zero) | e1.cmpgt(zero) | e2.cmpgt(zero)).bitmask();
        let rounded = (e0.cmpeq(zero) | e1.cmpeq(zero) | e2.cmpeq(zero)).bitmask();
        let mixed = neg & pos;
        let exact = lanes & rounded & !mixed;
        let mut out = Hits4 {
            mask: 0,
            t: [0.0; 4],
            b1: [0.0; 4],
            b2: [0.0; 4],
        };
        if lanes & !mixed & !rounded != 0 {
            let det = e0 + e1 + e2;
            let t_scaled = e0 * z0 + e1 * z1 + e2 * z2;
            let inv_det = Vec4::ONE / det;
            let t = t_scaled * inv_det;
            let in_range = t.cmpge(Vec4::splat(ray.t_lo)) & t.cmple(Vec4::splat(t_max));
            let ok = in_range & det.cmpne(zero);
            out.mask = ok.bitmask() & lanes & !mixed & !rounded;
            out.t = t.to_array();
            out.b1 = (e1 * inv_det).to_array();
            out.b2 = (e2 * inv_det).to_array();
        }
        if exact != 0 {
            self.intersect_exact_lanes(ray, t_max, exact, &mut out);
        }
        out
    }

    /// The lanes where an edge function rounded to zero, through the scalar test.
    #[cold]
    #[inline(never)]
    fn intersect_exact_lanes(&self, ray: &TriangleRay, t_max: f32, lanes: u32, out: &mut Hits4) {
        for lane in 0..4 {
            if lanes & 1 << lane == 0 {
                continue;
            }
            if let Some(h) = self.lane(lane).intersect(ray, t_max) {
                out.mask |= 1 << lane;
                out.t[lane] = h.t;
                out.b1[lane] = h.b1;
                out.b2[lane] = h.b2;
            }
        }
    }
}

/// Edge functions in `f64`, where products of two floats are exact: used when an
/// f32 edge function rounded to zero, i.e. the ray passes (nearly) through an edge.
#[cold]
#[inline(never)]
fn exact_edge_functions(xt: Vec4, yt: Vec4) -> Vec4 {
    let x = xt.to_array().map(f64::from);
    let y = yt.to_array().map(f64::from);
    let e = |i: usize, j: usize| (x[i] * y[j] - y[i] * x[j]) as f32;
    Vec4::new(e(1, 2), e(2, 0), e(0, 1), 0.0)
}

/// Whether a triangle can ever be hit: finite corners and a non-zero area, the
/// same criterion as pbrt (zero-area triangles would give meaningless edge tests).
pub fn triangle_is_hittable(p0: Vec3, p1: Vec3, p2: Vec3) -> bool {
    let finite = p0.is_finite() && p1.is_finite() && p2.is_finite();
    finite && (p2 - p0).cross(p1 - p0).length_squared() != 0.0
}

/// Intersects `ray` with triangle `(p0, p1, p2)`; returns `(t, b1, b2)` with
/// `t ∈ [t_min, t_max]` and barycentrics of corners 1 and 2.
pub fn intersect_triangle(ray: &Ray, p0: Vec3, p1: Vec3, p2: Vec3) -> Option<(f32, f32, f32)> {
    if !triangle_is_hittable(p0, p1, p2) {
        return None;
    }
    let tri = PackedTriangle::new(p0, p1, p2);
    tri.intersect(&TriangleRay::new(ray), ray.t_max)
        .map(|h| (h.t, h.b1, h.b2))
}

/// The per-ray part of the watertight test for sixteen rays, one per lane: each
/// lane has its own axis permutation, applied by selecting coordinates, so a lane
/// computes exactly what [`TriangleRay`] and [`PackedTriangle::intersect`] do for
/// its ray.
#[derive(Clone, Copy)]
pub struct TriangleRays<S: Simd> {
    /// Lanes whose dominant axis `kz` is x, and y (else z).
    z_is_x: Mask<S>,
    z_is_y: Mask<S>,
    /// The origin on the permuted axes.
    o: Vec3s<S>,
    sx: F32s<S>,
    sy: F32s<S>,
    sz: F32s<S>,
    t_lo: F32s<S>,
}

impl<S: Simd> TriangleRays<S> {
    /// Rays from `o` along `d` with `t_min = 0` (spawned and camera rays).
    #[inline(always)]
    pub fn new(s: S, o: Vec3s<S>, d: Vec3s<S>) -> Self {
        let ad = d.abs();
        // pbrt's MaxComponentIndex, as in `TriangleRay::new`.
        let x_gt_y = ad.x.gt(ad.y);
        let z_is_x = x_gt_y & ad.x.gt(ad.z);
        let z_is_y = !x_gt_y & ad.y.gt(ad.z);
        let (o, d) = (permute(z_is_x, z_is_y, o), permute(z_is_x, z_is_y, d));
        TriangleRays {
            z_is_x,
            z_is_y,
            o,
            sx: -d.x / d.z,
            sy: -d.y / d.z,
            sz: F32s::splat(s, 1.0) / d.z,
            t_lo: F32s::splat(s, f32::MIN_POSITIVE),
        }
    }

    /// The watertight test of one triangle against the lanes in `active` for
    /// `t ∈ [t_lo, t_max]`, in two halves: these edge functions and the lanes that
    /// may hit, then [`finish`](Self::finish): the lanes hit, with `t`, `b1`, `b2`.
    /// A leaf computes the first half for all its triangles before branching on any,
    /// so the tests overlap. Lanes whose edge functions round to zero go through the
    /// scalar test and its `f64` fallback, as in [`Triangle4::intersect`].
    #[inline(always)]
    pub fn edges(&self, s: S, corners: &[Vec3; 3], active: LaneBits) -> Edges<S> {
        let (x0, y0, z0) = self.shear(s, corners[0]);
        let (x1, y1, z1) = self.shear(s, corners[1]);
        let (x2, y2, z2) = self.shear(s, corners[2]);
        let e0 = x1 * y2 - y1 * x2;
        let e1 = x2 * y0 - y2 * x0;
        let e2 = x0 * y1 - y0 * x1;
        let zero = F32s::splat(s, 0.0);
        let neg = (e0.lt(zero) | e1.lt(zero) | e2.lt(zero)).bits();
        let pos = (e0.gt(zero) | e1.gt(zero) | e2.gt(zero)).bits();
        let rounded = (e0.eq(zero) | e1.eq(zero) | e2.eq(zero)).bits();
        let mixed = neg & pos;
        Edges {
            e: [e0, e1, e2],
            z: [z0, z1, z2],
            candidates: active & !mixed & !rounded,
            exact: active & rounded & !mixed,
        }
    }

    /// The second half of the test begun by [`edges`](Self::edges), for its lanes.
    #[inline(always)]
    pub fn finish(
        &self,
        s: S,
        corners: &[Vec3; 3],
        edges: &Edges<S>,
        t_max: F32s<S>,
    ) -> (LaneBits, F32s<S>, F32s<S>, F32s<S>) {
        let zero = F32s::splat(s, 0.0);
        let (candidates, exact) = (edges.candidates, edges.exact);
        if candidates | exact == 0 {
            // Every lane passes outside an edge: the usual answer, known before the division.
            return (0, zero, zero, zero);
        }
        let [e0, e1, e2] = edges.e;
        let [z0, z1, z2] = edges.z;
        let det = e0 + e1 + e2;
        let t_scaled = e0 * z0 + e1 * z1 + e2 * z2;
        let inv_det = F32s::splat(s, 1.0) / det;
        let mut t = t_scaled * inv_det;
        let in_range = t.ge(self.t_lo) & t.le(t_max) & !det.eq(zero);
        let mut hit = in_range.bits() & candidates;
        let mut b1 = e1 * inv_det;
        let mut b2 = e2 * inv_det;
        if exact != 0 {
            (hit, t, b1, b2) = self.exact_lanes(s, corners, t_max, exact, (hit, t, b1, b2));
        }
        (hit, t, b1, b2)
    }

    /// Corner `p` relative to each lane's origin, permuted and sheared.
    #[inline(always)]
    fn shear(&self, s: S, p: Vec3) -> (F32s<S>, F32s<S>, F32s<S>) {
        let v = permute(self.z_is_x, self.z_is_y, Vec3s::splat(s, p)) - self.o;
        (v.x + self.sx * v.z, v.y + self.sy * v.z, self.sz * v.z)
    }

    /// Lanes with an edge function that rounded to zero, one by one through the
    /// scalar test.
    #[cold]
    #[inline(never)]
    fn exact_lanes(
        &self,
        s: S,
        corners: &[Vec3; 3],
        t_max: F32s<S>,
        lanes: LaneBits,
        (mut hit, t, b1, b2): (LaneBits, F32s<S>, F32s<S>, F32s<S>),
    ) -> (LaneBits, F32s<S>, F32s<S>, F32s<S>) {
        let (mut t, mut b1, mut b2) = (t.to_array(), b1.to_array(), b2.to_array());
        let tri = PackedTriangle::new(corners[0], corners[1], corners[2]);
        let (t_max, ox, oy, oz) = (
            t_max.to_array(),
            self.o.x.to_array(),
            self.o.y.to_array(),
            self.o.z.to_array(),
        );
        let (sx, sy, sz) = (self.sx.to_array(), self.sy.to_array(), self.sz.to_array());
        let (zx, zy) = (self.z_is_x.bits(), self.z_is_y.bits());
        let mut rest = lanes;
        while rest != 0 {
            let i = rest.trailing_zeros() as usize;
            rest &= rest - 1;
            let kz = if zx >> i & 1 != 0 {
                0
            } else if zy >> i & 1 != 0 {
                1
            } else {
                2
            };
            let kx = if kz == 2 { 0 } else { kz + 1 };
            let ray = TriangleRay {
                kx,
                ky: if kx == 2 { 0 } else { kx + 1 },
                kz,
                ox: Vec4::splat(ox[i]),
                oy: Vec4::splat(oy[i]),
                oz: Vec4::splat(oz[i]),
                sx: Vec4::splat(sx[i]),
                sy: Vec4::splat(sy[i]),
                sz: Vec4::splat(sz[i]),
                t_lo: f32::MIN_POSITIVE,
            };
            if let Some(h) = tri.intersect(&ray, t_max[i]) {
                hit |= 1 << i;
                (t[i], b1[i], b2[i]) = (h.t, h.b1, h.b2);
            }
        }
        (
            hit,
            F32s::from_array(s, t),
            F32s::from_array(s, b1),
            F32s::from_array(s, b2),
        )
    }
}

/// One triangle's edge functions against sixteen rays ([`TriangleRays::edges`]).
#[derive(Clone, Copy)]
pub struct Edges<S: Simd> {
    e: [F32s<S>; 3],
    z: [F32s<S>; 3],
    /// Lanes inside all three edges, and lanes with an edge function of zero.
    candidates: LaneBits,
    exact: LaneBits,
}

impl<S: Simd> Edges<S> {
    /// No lane may hit.
    #[inline(always)]
    pub fn none(s: S) -> Self {
        let zero = F32s::splat(s, 0.0);
        Edges {
            e: [zero; 3],
            z: [zero; 3],
            candidates: 0,
            exact: 0,
        }
    }

    /// Only the lanes of `lanes` may hit.
    #[inline(always)]
    pub fn restrict(&mut self, lanes: LaneBits) {
        self.candidates &= lanes;
        self.exact &= lanes;
    }
}

/// `v` on the axes `(kx, ky, kz)` of each lane: `(y, z, x)` where `kz` is x,
/// `(z, x, y)` where it is y, else `(x, y, z)`.
#[inline(always)]
fn permute<S: Simd>(z_is_x: Mask<S>, z_is_y: Mask<S>, v: Vec3s<S>) -> Vec3s<S> {
    Vec3s::new(
        F32s::select(z_is_x, v.y, F32s::select(z_is_y, v.z, v.x)),
        F32s::select(z_is_x, v.z, F32s::select(z_is_y, v.x, v.y)),
        F32s::select(z_is_x, v.x, F32s::select(z_is_y, v.y, v.z)),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tri() -> [Vec3; 3] {
        [
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        ]
    }

    #[test]
    fn hits_interior_with_barycentrics() {
        let [a, b, c] = tri();
        let ray = Ray::new(Vec3::new(0.25, 0.5, 2.0), Vec3::new(0.0, 0.0, -1.0));
        let (t, b1, b2) = intersect_triangle(&ray, a, b, c).expect("hit");
        assert_eq!(t, 2.0);
        assert!((b1 - 0.25).abs() < 1e-6 && (b2 - 0.5).abs() < 1e-6);
    }

    #[test]
    fn respects_interval_and_backside() {
        let [a, b, c] = tri();
        let mut ray = Ray::new(Vec3::new(0.25, 0.25, 2.0), Vec3::new(0.0, 0.0, -1.0));
        ray.t_max = 1.5;
        assert!(intersect_triangle(&ray, a, b, c).is_none());
        ray.t_max = f32::INFINITY;
        ray.t_min = 2.5;
        assert!(intersect_triangle(&ray, a, b, c).is_none());
        let behind = Ray::new(Vec3::new(0.25, 0.25, 2.0), Vec3::new(0.0, 0.0, 1.0));
        assert!(intersect_triangle(&behind, a, b, c).is_none());
        let from_below = Ray::new(Vec3::new(0.25, 0.25, -2.0), Vec3::new(0.0, 0.0, 1.0));
        assert!(intersect_triangle(&from_below, a, b, c).is_some());
    }

    #[test]
    fn misses_outside_and_degenerate() {
        let [a, b, c] = tri();
        let ray = Ray::new(Vec3::new(0.75, 0.75, 2.0), Vec3::new(0.0, 0.0, -1.0));
        assert!(intersect_triangle(&ray, a, b, c).is_none());
        let through = Ray::new(Vec3::new(0.5, 0.0, 2.0), Vec3::new(0.0, 0.0, -1.0));
        assert!(intersect_triangle(&through, a, b, a + 2.0 * (b - a)).is_none());
        let zero_dir = Ray::new(Vec3::new(0.25, 0.25, 2.0), Vec3::ZERO);
        assert!(intersect_triangle(&zero_dir, a, b, c).is_none());
    }

    /// Rays from far away at 1e-5..1e-3 rad to the plane, through corners, edge
    /// midpoints and the interior: each one hits (pbrt's `t ≤ δt` rejection, once
    /// applied here, dropped such hits because δt grows like 1/det).
    #[test]
    fn grazing_rays_from_afar_hit() {
        let [a, b, c] = tri();
        let targets = [a, b, c, 0.5 * (a + b), 0.5 * (b + c), (a + b + c) / 3.0];
        for p in targets {
            for elevation in [1e-5f32, 1e-4, 1e-3] {
                for horiz in [Vec3::X, -Vec3::Y, Vec3::new(1.0, 1.0, 0.0).normalize()] {
                    let d = (horiz * elevation.cos() - Vec3::Z * elevation.sin()).normalize();
                    let o = p - 30.0 * d;
                    let ray = Ray::new(o, d);
                    // Targets on the boundary may round to either side; interior ones must hit.
                    let hit = intersect_triangle(&ray, a, b, c);
                    if p == (a + b + c) / 3.0 {
                        let (t, ..) = hit.unwrap_or_else(|| panic!("{ray:?} missed"));
                        assert!((t - 30.0).abs() < 1e-3, "{t}");
                    }
                }
            }
        }
        // Through every corner and edge midpoint the two triangles of a square
        // sharing the diagonal leave no gap.
        let d2 = Vec3::new(1.0, 1.0, 0.0);
        let quad = [[a, b, d2], [a, d2, c]];
        for p in [0.5 * d2, 0.25 * d2, 0.75 * d2] {
            for elevation in [1e-5f32, 1e-4] {
                let d = (Vec3::new(1.0, -1.0, 0.0).normalize() * elevation.cos()
                    - Vec3::Z * elevation.sin())
                .normalize();
                let ray = Ray::new(p - 30.0 * d, d);
                assert!(
                    quad.iter()
                        .any(|[x, y, z]| intersect_triangle(&ray, *x, *y, *z).is_some()),
                    "{ray:?} slipped through the diagonal"
                );
            }
        }
    }

    #[test]
    fn edge_and_vertex_rays_hit() {
        let [a, b, c] = tri();
        for p in [a, b, c, 0.5 * (a + b), 0.5 * (b + c), 0.5 * (a + c)] {
            let ray = Ray::new(p + Vec3::new(0.0, 0.0, 3.0), Vec3::new(0.0, 0.0, -1.0));
            assert!(intersect_triangle(&ray, a, b, c).is_some(), "{p}");
        }
    }
}

#[cfg(test)]
mod simd_tests {
    use super::*;
    use crate::sampling::Rng;

    /// Every lane of the four-wide test equals the scalar test, bit for bit.
    fn check(tris: &[[Vec3; 3]; 4], ray: &Ray) {
        let t4 = Triangle4::new(tris);
        let tr = TriangleRay::new(ray);
        for t_max in [ray.t_max, 1.0] {
            let h = t4.intersect(&tr, t_max, 0b1111);
            for (lane, c) in tris.iter().enumerate() {
                let s = PackedTriangle::new(c[0], c[1], c[2]).intersect(&tr, t_max);
                let v = (h.mask & 1 << lane != 0).then(|| TriangleHit {
                    t: h.t[lane],
                    b1: h.b1[lane],
                    b2: h.b2[lane],
                });
                assert_eq!(s, v, "lane {lane} {ray:?} {c:?}");
            }
        }
    }

    #[test]
    fn four_wide_test_matches_scalar_on_random_and_adversarial_rays() {
        let mut rng = Rng::from_seed(9);
        let mut f = move || rng.next_f32();
        let mut hits = 0;
        for _ in 0..5000 {
            let mut v = || Vec3::new(f(), f(), f()) * 2.0 - 1.0;
            let tris: [[Vec3; 3]; 4] = std::array::from_fn(|_| [v(), v(), v()]);
            let [a, b, c] = tris[0];
            let o = v() * 3.0;
            let targets = [a, b, 0.5 * (a + b), 0.5 * (b + c), (a + b + c) / 3.0, v()];
            for p in targets {
                check(&tris, &Ray::new(o, p - o));
                // Axis-aligned through the target.
                for axis in [Vec3::X, Vec3::Y, Vec3::Z] {
                    check(&tris, &Ray::new(p - 2.0 * axis, axis));
                }
            }
            // Along an edge, and grazing the plane.
            check(&tris, &Ray::new(a - (b - a), b - a));
            let n = (b - a).cross(c - a).normalize();
            check(&tris, &Ray::new(a + 1e-6 * n - (c - a), c - a));
            let h =
                Triangle4::new(&tris).intersect(&TriangleRay::new(&Ray::new(o, a - o)), 1e30, 15);
            hits += h.mask.count_ones();
        }
        assert!(
            hits > 1000,
            "the rays must hit often enough to test something"
        );
    }

    #[test]
    fn shared_edge_rays_hit_one_of_two_lanes() {
        let (a, b) = (Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 1.0, 0.0));
        let tris = [
            [a, Vec3::new(1.0, 0.0, 0.0), b],
            [a, b, Vec3::new(0.0, 1.0, 0.0)],
            [a, b, Vec3::new(0.0, 1.0, 0.0)],
            [a, Vec3::new(1.0, 0.0, 0.0), b],
        ];
        // Interior points of the edge (at its ends the rounded crossing may leave the square).
        for i in 1..64 {
            let p = a + (b - a) * (i as f32 / 64.0);
            let ray = Ray::new(p + Vec3::new(0.1, 0.3, 1.0), Vec3::new(-0.1, -0.3, -1.0));
            check(&tris, &ray);
            let h = Triangle4::new(&tris).intersect(&TriangleRay::new(&ray), f32::INFINITY, 3);
            assert_ne!(
                h.mask, 0,
                "ray through the shared edge at {p} slipped through"
            );
        }
    }
}
