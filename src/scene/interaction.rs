//! Surface points of ray hits, per lane, and the rays that leave them: written once
//! over the lane type; [`super::SurfaceInteraction`] is the one-path form.

use super::{into_triangle, Scene, NO_LIGHT};
use crate::geometry::ray::{gamma, offset_origin};
use crate::geometry::sphere::sphere_spawn_origin;
use crate::lanes::rays::HitPacket;
use crate::lanes::{each_lane, prefetch, LaneBits, LaneMask, Lanes, Real, LANES, V3};
use glam::Vec3;

/// The hits of a set of lanes: where each is, with what error, its normals, and what
/// it hit (primitive, material, area light), as the scene describes it.
#[derive(Clone, Copy)]
pub struct Hits<L: Lanes> {
    pub p: V3<L::F>,
    /// Conservative per-axis bound on the error of `p`.
    pub p_error: V3<L::F>,
    /// Unit geometric normal; it points to the surface's front.
    pub ng: V3<L::F>,
    /// Unit shading normal, on the same side as `ng`.
    pub ns: V3<L::F>,
    /// Texture coordinates where the triangle has them, else its `(b1, b2)`.
    pub uv: (L::F, L::F),
    pub prim: [u32; LANES],
    pub material: [u32; LANES],
    /// The area light whose surface each lane hit (`NO_LIGHT` if none).
    pub light: [u32; LANES],
    /// Lanes on triangles (the others are on spheres), their corners, and the
    /// spheres' centres and radii.
    pub triangles: LaneBits,
    pub corners: [V3<L::F>; 3],
    pub centre: V3<L::F>,
    pub radius: L::F,
}

impl Scene {
    /// The hits `h` of rays `o + t·d` in `lanes`. Points come from barycentrics
    /// (triangles) or are projected onto the sphere, so their error scales with the
    /// scene's magnitudes, not with `t`.
    #[inline(always)]
    pub fn hits<L: Lanes>(
        &self,
        l: L,
        lanes: LaneBits,
        o: V3<L::F>,
        d: V3<L::F>,
        h: &HitPacket,
    ) -> Hits<L> {
        let ntri = self.triangles.len();
        let mut corner = [[[0.0f32; LANES]; 3]; 3];
        let mut normal = [[[0.0f32; LANES]; 3]; 3];
        let mut has_normals: LaneBits = 0;
        let mut triangles: LaneBits = 0;
        let mut centre = [[0.0f32; LANES]; 3];
        let mut radius = [0.0f32; LANES];
        let mut material = [0u32; LANES];
        let mut light = [NO_LIGHT; LANES];
        // First the primitives' records, asking for their corners' and normals'
        // memory as the indices arrive, so the misses of all lanes overlap.
        let mut vertex = [[0u32; LANES]; 3];
        let mut normal_index = [[0u32; LANES]; 3];
        for i in each_lane(lanes) {
            let p = h.prim[i] as usize;
            if p < ntri {
                let tri = &self.triangles[p];
                triangles |= 1 << i;
                for (k, &v) in tri.v.iter().enumerate() {
                    vertex[k][i] = v;
                    prefetch(self.positions.as_ptr().wrapping_add(v as usize));
                }
                if let Some(n) = tri.n {
                    has_normals |= 1 << i;
                    for (k, &v) in n.iter().enumerate() {
                        normal_index[k][i] = v;
                        prefetch(self.normals.as_ptr().wrapping_add(v as usize));
                    }
                }
                light[i] = tri.light;
                material[i] = tri.material;
            } else {
                let sp = &self.spheres[p - ntri];
                (centre[0][i], centre[1][i], centre[2][i]) = sp.centre.into();
                radius[i] = sp.radius;
                material[i] = sp.material;
            }
        }
        for i in each_lane(triangles) {
            for (k, v) in vertex.iter().enumerate() {
                let q = self.positions[v[i] as usize];
                (corner[k][0][i], corner[k][1][i], corner[k][2][i]) = q.into();
            }
        }
        for i in each_lane(has_normals) {
            for (k, v) in normal_index.iter().enumerate() {
                let q = self.normals[v[i] as usize];
                (normal[k][0][i], normal[k][1][i], normal[k][2][i]) = q.into();
            }
        }
        let (b1, b2) = (l.f_from(h.b1), l.f_from(h.b2));
        // Element by element, not `.map`: a closure the compiler leaves out of line
        // loses the instruction set, and each load becomes a call (1.7 % of CBbunny).
        let corners = [
            V3::from_arrays(l, &corner[0]),
            V3::from_arrays(l, &corner[1]),
            V3::from_arrays(l, &corner[2]),
        ];
        let (mut p, mut p_error, mut ng) = triangle_points(l, triangles, corners, b1, b2);
        let mut ns = ng;
        if has_normals != 0 {
            let n = [
                V3::from_arrays(l, &normal[0]),
                V3::from_arrays(l, &normal[1]),
                V3::from_arrays(l, &normal[2]),
            ];
            let (g, s) = shading_normals(l, ng, n, b1, b2);
            let m = l.mask(has_normals);
            ng = V3::select(m, g, ng);
            ns = V3::select(m, s, ns);
        }
        let centre = V3::from_arrays(l, &centre);
        let radius = l.f_from(radius);
        let spheres = lanes & !triangles;
        if spheres != 0 {
            let (sp, sp_error, n) = sphere_points(l, o, d, l.f_from(h.t), centre, radius);
            let m = l.mask(spheres);
            p = V3::select(m, sp, p);
            p_error = V3::select(m, sp_error, p_error);
            ng = V3::select(m, n, ng);
            ns = V3::select(m, n, ns);
        }
        let uv = if self.has_textures() {
            let mut uv = [[0.0f32; LANES]; 2];
            for i in each_lane(triangles) {
                let (b1, b2) = (h.b1[i], h.b2[i]);
                let t = self.texcoord(h.prim[i] as usize, 1.0 - b1 - b2, b1, b2);
                (uv[0][i], uv[1][i]) = (t.x, t.y);
            }
            (l.f_from(uv[0]), l.f_from(uv[1]))
        } else {
            (b1, b2)
        };
        Hits {
            p,
            p_error,
            ng,
            ns,
            uv,
            prim: h.prim,
            material,
            light,
            triangles,
            corners,
            centre,
            radius,
        }
    }
}

/// Point, error bound and geometric normal per lane.
type HitPoints<F> = (V3<F>, V3<F>, V3<F>);

/// Point, error bound and geometric normal of triangle hits at barycentrics
/// `(b1, b2)`. Relative to corner 0: `p0 + b1·e1 + b2·e2` lies on the triangle's plane
/// for any barycentrics, so its error is the rounding of the edge terms (small, like
/// the triangle) plus one rounding of the sum (≤ γ₁|p|); the absolute form
/// `b0·p0 + b1·p1 + b2·p2` carries γ₇·|p|, which every spawned ray would be offset by
/// (4e-3 at 1e4; stability case 5). On an axis where the three corners agree (a wall,
/// floor or ceiling) the point is corner 0's own coordinate, exactly: no error there,
/// so rays leave such a plane from on it (else a floor at 1e5 sends them ~2e-2 up,
/// inside a ball resting on it).
#[inline(always)]
fn triangle_points<L: Lanes>(
    l: L,
    lanes: LaneBits,
    [p0, p1, p2]: [V3<L::F>; 3],
    b1: L::F,
    b2: L::F,
) -> HitPoints<L::F> {
    let (e1, e2) = (p1 - p0, p2 - p0);
    let (t1, t2) = (e1 * b1, e2 * b2);
    let local = t1 + t2;
    let p = p0 + local;
    let p_error = p.abs() * l.f(gamma(2)) + (t1.abs() + t2.abs()) * l.f(gamma(4));
    let p = into_triangles(l, lanes, p, p0, local, [p0, p1, p2], b1, b2);
    let p_error = exact_axes_zeroed([p0, p1, p2], p_error, V3::splat(l, Vec3::ZERO));
    (p, p_error, e1.cross(e2).normalize_or_zero())
}

/// The interpolated shading normal, and the geometric normal turned to the side of
/// the corners' normals (the loader oriented them); shading normals are kept on the
/// front side so BSDF sides agree with `ng`.
#[inline(always)]
fn shading_normals<L: Lanes>(
    l: L,
    ng: V3<L::F>,
    [n0, n1, n2]: [V3<L::F>; 3],
    b1: L::F,
    b2: L::F,
) -> (V3<L::F>, V3<L::F>) {
    let zero = l.f(0.0);
    let b0 = l.f(1.0) - b1 - b2;
    let interp = (n0 * b0 + n1 * b1 + n2 * b2).normalize_or_zero();
    let ng = V3::select((n0 + n1 + n2).dot(ng).lt(zero), -ng, ng);
    let ns = V3::select(interp.is_zero(), ng, interp);
    let ns = V3::select(ns.dot(ng).lt(zero), -ns, ns);
    (ng, ns)
}

/// Sphere hits of rays `o + t·d` on spheres `(c, r)`, relative to the centre: `o − c`
/// is exact for nearby points however far from the origin, where the absolute
/// `o + t·d` would round to the f32 grid there (4e-3 at 1e5, a normal 1e-2 rad off on
/// a ball of radius 0.4). `p = c ⊕ r·n`: one rounding of the sum (≤ γ₁|p|) plus the
/// error of `r·n` (≤ γ₄·r); rays leave from within an ulp of `p`
/// (`sphere_spawn_origin`), not offset by this bound.
#[inline(always)]
fn sphere_points<L: Lanes>(
    l: L,
    o: V3<L::F>,
    d: V3<L::F>,
    t: L::F,
    c: V3<L::F>,
    r: L::F,
) -> HitPoints<L::F> {
    let n = ((o - c) + d * t).normalize_or_zero();
    let n = V3::select(n.is_zero(), V3::splat(l, Vec3::Y), n);
    let p = c + n * r;
    let err = l.f(gamma(4)) * r;
    (p, p.abs() * l.f(gamma(2)) + V3::new(err, err, err), n)
}

/// `v` with the axes on which the three corners agree replaced by `exact`'s.
#[inline(always)]
fn exact_axes_zeroed<F: Real>([p0, p1, p2]: [V3<F>; 3], v: V3<F>, exact: V3<F>) -> V3<F> {
    V3::new(
        F::select(p0.x.eq(p1.x) & p0.x.eq(p2.x), exact.x, v.x),
        F::select(p0.y.eq(p1.y) & p0.y.eq(p2.y), exact.y, v.y),
        F::select(p0.z.eq(p1.z) & p0.z.eq(p2.z), exact.z, v.z),
    )
}

/// `scene::into_triangle` of `p = a ⊕ b` in the lanes in `lanes`. Its edge test is run
/// here with four times its margin, so that whatever the lanes' rounding, every lane
/// it would move is handed to it (they are rare: within half an ulp of an edge); it
/// decides and rounds each.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn into_triangles<L: Lanes>(
    l: L,
    lanes: LaneBits,
    p: V3<L::F>,
    a: V3<L::F>,
    b: V3<L::F>,
    [p0, p1, p2]: [V3<L::F>; 3],
    b1: L::F,
    b2: L::F,
) -> V3<L::F> {
    let area2 = (p1 - p0).cross(p2 - p0).length();
    let margin = (p.abs() * l.f(4.0 * gamma(1))).length();
    let b0 = l.f(1.0) - b1 - b2;
    let near = near_edge(b0, p2 - p1, area2, margin)
        | near_edge(b1, p2 - p0, area2, margin)
        | near_edge(b2, p1 - p0, area2, margin);
    let moved = near.bits() & lanes;
    if moved == 0 {
        return p;
    }
    let mut out = p.to_arrays();
    let (b1, b2) = (b1.to_array(), b2.to_array());
    let [p0, p1, p2, a, b] = [p0, p1, p2, a, b].map(V3::to_arrays);
    let at = |v: &[[f32; LANES]; 3], i: usize| glam::Vec3::new(v[0][i], v[1][i], v[2][i]);
    for i in each_lane(moved) {
        let bary = [1.0 - b1[i] - b2[i], b1[i], b2[i]];
        let corners = [at(&p0, i), at(&p1, i), at(&p2, i)];
        let q = into_triangle(at(&out, i), at(&a, i), at(&b, i), corners, bary);
        (out[0][i], out[1][i], out[2][i]) = q.into();
    }
    V3::from_arrays(l, &out)
}

/// Whether the point at barycentric `bk` is within `margin` of the edge `edge`
/// opposite corner k (`area2`: twice the triangle's area).
#[inline(always)]
fn near_edge<F: Real>(bk: F, edge: V3<F>, area2: F, margin: F) -> F::M {
    (bk * area2).le(margin * edge.length())
}

impl<L: Lanes> Hits<L> {
    /// The hits in `lanes` (found by rays spawned from surface points `from` in unit
    /// directions `w`) moved onto the lines `from + s·w` themselves, on the same
    /// primitives.
    ///
    /// A spawned ray starts off its surface by the point's rounding error, on a
    /// parallel line (`offset_ray_origin`): what it finds is seen from that displaced
    /// origin, a little closer than from `from` (~2 ulps of the coordinates: 2e-2 at
    /// 1e5). At every bounce that biases toward nearer, brighter light: a mirror's
    /// reflection, a caustic, a light's inverse square (stability case 5). The traced
    /// ray decides which primitive is hit, robustly; where on it is solved here,
    /// relative to `from`: the line meets the plane of the hit (a sphere's tangent
    /// plane, O(δ²/r) off the sphere), and a sphere's normal is taken again there.
    /// Grazing hits (|cos| < 0.05) and points outside the hit triangle (the two lines
    /// straddle an edge) are left as found.
    #[inline(always)]
    pub fn on_line(&self, l: L, lanes: LaneBits, from: V3<L::F>, w: V3<L::F>) -> Self {
        let zero = l.f(0.0);
        let cos = w.dot(self.ng);
        let steep = cos.abs().ge(l.f(0.05));
        let dist = (self.p - from).dot(self.ng) / cos;
        let ahead = dist.gt(zero) & dist.is_finite();
        let p = from + w * dist;
        // The found point's error (the plane's), plus the rounding of `from + s·w`.
        let p_error = self.p_error + p.abs() * l.f(gamma(1)) + (w * dist).abs() * l.f(gamma(5));
        // Triangles: the point must lie in the hit triangle; exact axes stay.
        let [p0, p1, p2] = self.corners;
        let (inside, b1, b2) = barycentrics(l, self.corners, p);
        let tri = l.mask(self.triangles);
        let on_tri = (tri & steep & ahead & inside).bits() & lanes;
        let p_tri = into_triangles(l, on_tri, p, from, w * dist, self.corners, b1, b2);
        let tri_p = exact_axes_zeroed([p0, p1, p2], p_tri, self.p);
        let tri_err = exact_axes_zeroed([p0, p1, p2], p_error, V3::splat(l, Vec3::ZERO));
        // Spheres: the normal again at the moved point, relative to the centre.
        let n = ((from - self.centre) + w * dist).normalize_or_zero();
        let facing = n.dot(self.ng).gt(zero);
        let lands = (tri & inside) | (!tri & facing);
        let moved = l.mask(lanes) & steep & ahead & lands;
        let (is_tri, is_sph) = (moved & tri, moved & !tri);
        Hits {
            p: V3::select(is_tri, tri_p, V3::select(is_sph, p, self.p)),
            p_error: V3::select(is_tri, tri_err, V3::select(is_sph, p_error, self.p_error)),
            ng: V3::select(is_sph, n, self.ng),
            ns: V3::select(is_sph, n, self.ns),
            ..*self
        }
    }

    /// Where rays leaving the hits in `lanes` toward `w` start: off the surface by
    /// the error bound, or (a sphere's, lane by lane) just on `w`'s side of it.
    #[inline(always)]
    pub fn spawn_origins(&self, l: L, lanes: LaneBits, w: V3<L::F>) -> V3<L::F> {
        let offset = offset_origin(self.p, self.p_error, self.ng, w);
        let spheres = lanes & !self.triangles;
        if spheres == 0 {
            return offset;
        }
        let mut out = offset.to_arrays();
        let (p, ng, w) = (self.p.to_arrays(), self.ng.to_arrays(), w.to_arrays());
        let (c, r) = (self.centre.to_arrays(), self.radius.to_array());
        let at = |v: &[[f32; LANES]; 3], i: usize| glam::Vec3::new(v[0][i], v[1][i], v[2][i]);
        for i in each_lane(spheres) {
            let (p, ng) = (at(&p, i), at(&ng, i));
            let outward = at(&w, i).dot(ng) > 0.0;
            if let Some(o) = sphere_spawn_origin(p, ng, outward, at(&c, i), r[i]) {
                (out[0][i], out[1][i], out[2][i]) = o.into();
            }
        }
        V3::from_arrays(l, &out)
    }
}

/// Whether `q`, in the plane of the triangle, lies in it, and its `b1, b2` (dual basis).
#[inline(always)]
fn barycentrics<L: Lanes>(l: L, [p0, p1, p2]: [V3<L::F>; 3], q: V3<L::F>) -> (L::M, L::F, L::F) {
    let (e1, e2, d) = (p1 - p0, p2 - p0, q - p0);
    let m = e1.cross(e2);
    let m2 = m.length_squared();
    let b1 = d.cross(e2).dot(m) / m2;
    let b2 = e1.cross(d).dot(m) / m2;
    let zero = l.f(0.0);
    (b1.ge(zero) & b2.ge(zero) & (b1 + b2).le(l.f(1.0)), b1, b2)
}
