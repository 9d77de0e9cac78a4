//! The flat scene ember renders: world-space triangles and spheres, materials,
//! lights and one camera. No scene graph survives loading.

pub mod collada;

use crate::geometry::{offset_ray_origin, ray::gamma, sphere::sphere_spawn_origin, Aabb, Ray};
use crate::lights::{AreaLight, Light};
use crate::materials::Material;
use crate::texture::Texture;
use crate::Color;
use glam::{Vec2, Vec3};
use std::sync::Arc;

/// Marker for "no light" in `Triangle::light`.
pub const NO_LIGHT: u32 = u32::MAX;

/// A triangle of the flat scene: indices into `Scene::positions` (and `Scene::normals`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Triangle {
    pub v: [u32; 3],
    /// Per-corner shading normals, if the mesh had a NORMAL input.
    pub n: Option<[u32; 3]>,
    pub material: u32,
    /// Index into `Scene::lights` when this triangle is the surface of an area light.
    pub light: u32,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sphere {
    pub centre: Vec3,
    pub radius: f32,
    pub material: u32,
}

/// What the file says about the view. The eye comes from the scene bounds (spec §4), or,
/// for files other tools wrote, from the camera node (`placement`, issue 26).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraDesc {
    /// Unit forward direction `F`.
    pub forward: Vec3,
    /// Unit up `U`, orthogonal to `F`.
    pub up: Vec3,
    /// `tan(xfov/2)` as given or derived from the file, if known.
    pub tan_half_x: Option<f32>,
    /// `tan(yfov/2)` as given or derived from the file, if known.
    pub tan_half_y: Option<f32>,
    /// The camera node's world position, when the file has a camera.
    pub position: Option<Vec3>,
    /// Where the eye goes: the course's rule or the file's own position.
    pub placement: Placement,
}

/// Where the camera's eye is put.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Placement {
    /// The course's rule (spec §4): `centre − 1.5·diagonal·F` of the scene bounds,
    /// whatever the file says.
    #[default]
    Course,
    /// The camera node's own position (`CameraDesc::position`), as the file's author
    /// put it; the course's rule where the file has no camera.
    File,
}

impl Default for CameraDesc {
    fn default() -> Self {
        // No camera in the file: look down −Z like COLLADA's default camera, 49.13° wide.
        CameraDesc {
            forward: Vec3::NEG_Z,
            up: Vec3::Y,
            tan_half_x: Some((49.13434f32.to_radians() * 0.5).tan()),
            tan_half_y: None,
            position: None,
            placement: Placement::Course,
        }
    }
}

/// One mesh instance of the file: which triangles it became, under which names.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshInstance {
    /// The scene node's name (or id), else the geometry's.
    pub name: String,
    /// Its triangles are `Scene::triangles[first..first + count]`.
    pub first: u32,
    pub count: u32,
    /// Materials its triangles use (indices into `Scene::materials`).
    pub materials: Vec<u32>,
}

#[derive(Clone, Debug, Default)]
pub struct Scene {
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    pub triangles: Vec<Triangle>,
    pub spheres: Vec<Sphere>,
    pub materials: Vec<Material>,
    pub lights: Vec<Light>,
    pub camera: CameraDesc,
    /// Bounds of triangles and spheres (spec §4 `B`); area-light quads are excluded.
    pub bounds: Aabb,
    /// Non-fatal problems found while loading (e.g. a missing material).
    pub warnings: Vec<String>,
    /// The file's mesh instances, for `ember info` (the renderer never reads them).
    pub meshes: Vec<MeshInstance>,
    /// The file's name of each material (parallel to `materials`; may be shorter for
    /// scenes built in code).
    pub material_names: Vec<String>,
    /// Which camera placement the loader chose and why, for `ember info`.
    pub placement_reason: String,
    /// Texture coordinates, indexed by `triangle_uvs`.
    pub uvs: Vec<Vec2>,
    /// Each triangle's corner texture coordinates (indices into `uvs`), parallel to
    /// `triangles`; shorter when later triangles (area-light quads) have none. Only
    /// triangles of textured materials carry them.
    pub triangle_uvs: Vec<Option<[u32; 3]>>,
    pub textures: Vec<Arc<Texture>>,
    /// The diffuse texture of each material (index into `textures`), parallel to
    /// `materials`; may be shorter (no texture).
    pub material_textures: Vec<Option<u32>>,
    /// Two-sided emission attached to primitives on top of their material, found only by
    /// BSDF sampling: the emitting, reflecting walls of the analytic furnace. Test builds
    /// only (feature `testing`); the loader has no such thing.
    #[cfg(feature = "testing")]
    pub surface_emission: Vec<(PrimId, Color)>,
}

/// A primitive id: triangles first, then spheres.
pub type PrimId = u32;

/// The minimal answer of an acceleration structure: enough to rebuild the full
/// surface interaction identically whichever backend found it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PrimHit {
    pub t: f32,
    pub prim: PrimId,
    /// Barycentrics of corners 1 and 2 for triangles (Embree's u, v); unused for spheres.
    pub b1: f32,
    pub b2: f32,
}

/// Everything shading needs about a hit point.
#[derive(Clone, Copy, Debug)]
pub struct SurfaceInteraction {
    pub t: f32,
    pub p: Vec3,
    /// Conservative per-axis bound on the error of `p`.
    pub p_error: Vec3,
    /// Unit geometric normal; it points to the surface's front.
    pub ng: Vec3,
    /// Unit shading normal, on the same side as `ng`.
    pub ns: Vec3,
    /// Texture coordinates: interpolated from the triangle's corners where it has
    /// them (`Scene::triangle_uvs`), else the barycentrics `(b1, b2)`.
    pub uv: Vec2,
    pub prim: PrimId,
    pub material: u32,
    pub light: u32,
    /// The sphere `(centre, radius)` the point lies on, if it is a sphere's: rays leave
    /// it from within an ulp of `p` (`sphere_spawn_origin`), not by the error bound.
    pub sphere: Option<(Vec3, f32)>,
}

impl SurfaceInteraction {
    /// A ray leaving this point in direction `w`: its origin moved off the surface
    /// to `w`'s side by the point's error bound, and this primitive named as the
    /// one to skip (see [`Ray::skip`]), so the ray neither starts behind the surface
    /// nor finds it again at `t ≈ 0`.
    pub fn spawn_ray(&self, w: Vec3) -> Ray {
        Ray {
            skip: self.prim,
            ..Ray::new(self.spawn_origin(w), w)
        }
    }

    /// Where a ray leaving this point toward `w` starts: off the surface by the error
    /// bound, or for a sphere just on `w`'s side of it.
    fn spawn_origin(&self, w: Vec3) -> Vec3 {
        self.sphere
            .and_then(|(c, r)| sphere_spawn_origin(self.p, self.ng, w.dot(self.ng) > 0.0, c, r))
            .unwrap_or_else(|| offset_ray_origin(self.p, self.p_error, self.ng, w))
    }

    /// The segment from this point towards `target`, `o + t·(target − o)` for
    /// `t ∈ [0, t_end]` (`t_end` just below 1 leaves out a surface at `target`),
    /// spawned like [`spawn_ray`](Self::spawn_ray).
    pub fn spawn_segment(&self, target: Vec3, t_end: f32) -> Ray {
        let o = self.spawn_origin(target - self.p);
        Ray {
            skip: self.prim,
            ..Ray::segment(o, target - o, t_end)
        }
    }
}

/// `p = a ⊕ b`, a point of the triangle with corners `t` and barycentrics `bary`, kept
/// in it: within half an ulp of an edge, `p` is rounded on each axis to the
/// float on the side of the exact sum toward the triangle's centroid (the
/// round-to-nearest sum when that is already there, else one ulp further in).
/// Rounded to nearest, a floor point within half an ulp of a wall lands on the wall's
/// plane (and one near the diagonal of a quad in the other triangle): a ray leaving it
/// may then meet that neighbour at `t ≈ 0`; at 1e5 (half an ulp is 4 mm) that darkened
/// every edge of a room (stability case 5). Away from the edges `p` stays as rounded:
/// rounding everything inward would move whole walls' shading points by an ulp.
pub(crate) fn into_triangle(p: Vec3, a: Vec3, b: Vec3, t: [Vec3; 3], bary: [f32; 3]) -> Vec3 {
    // Distance to the edge opposite corner k: b_k · 2·area / |edge|; rounding to
    // nearest moves `p` by at most half an ulp per axis (≤ γ₁|p|).
    let area2 = (t[1] - t[0]).cross(t[2] - t[0]).length();
    let edges = [t[2] - t[1], t[2] - t[0], t[1] - t[0]];
    let margin = (gamma(1) * p.abs()).length();
    let near_edge = (0..3).any(|k| bary[k] * area2 <= margin * edges[k].length());
    if !near_edge {
        return p;
    }
    let centroid = (t[0] + t[1] + t[2]) / 3.0;
    let mut p = p;
    for i in 0..3 {
        // TwoSum (Knuth): the exact rounding error of the sum, `a + b = p + e`.
        let bb = p[i] - a[i];
        let e = (a[i] - (p[i] - bb)) + (b[i] - bb);
        let inward = centroid[i] - p[i];
        if e > 0.0 && inward > 0.0 {
            p[i] = crate::geometry::ray::next_float_up(p[i]);
        } else if e < 0.0 && inward < 0.0 {
            p[i] = crate::geometry::ray::next_float_down(p[i]);
        }
    }
    p
}

impl Scene {
    /// Adds `light` and, after every triangle so far, the two triangles of its surface
    /// (no bounds change: spec §4 leaves light quads out). Returns the light's index.
    pub fn add_area_light(&mut self, light: AreaLight) -> u32 {
        let index = self.lights.len() as u32;
        let material = self.black_material();
        self.lights.push(Light::Area(light));
        for tri in light.quad() {
            let base = self.positions.len() as u32;
            self.positions.extend(tri);
            self.triangles.push(Triangle {
                v: [base, base + 1, base + 2],
                n: None,
                material,
                light: index,
            });
        }
        index
    }

    /// Replaces area light `index` (moved, resized or re-coloured), its surface with it.
    pub fn set_area_light(&mut self, index: u32, light: AreaLight) {
        assert!(
            matches!(self.lights[index as usize], Light::Area(_)),
            "light {index} is not an area light"
        );
        self.lights[index as usize] = Light::Area(light);
        let quad = light.quad();
        let tris = self.triangles.iter().filter(|t| t.light == index);
        for (t, corners) in tris.zip(quad) {
            for (&v, p) in t.v.iter().zip(corners) {
                self.positions[v as usize] = p;
            }
        }
    }

    /// Lights the scene with `env` (`-e`): it replaces the file's hemisphere (ambient)
    /// lights, which would otherwise add to it. Area lights keep their surfaces, whose
    /// light indices are renumbered past the removed lights.
    pub fn set_environment(&mut self, env: std::sync::Arc<crate::lights::EnvironmentMap>) {
        let mut renumber = Vec::with_capacity(self.lights.len());
        let mut kept = Vec::with_capacity(self.lights.len() + 1);
        for light in self.lights.drain(..) {
            if matches!(light, Light::Ambient { .. }) {
                renumber.push(NO_LIGHT);
            } else {
                renumber.push(kept.len() as u32);
                kept.push(light);
            }
        }
        kept.push(Light::Environment(env));
        self.lights = kept;
        for t in &mut self.triangles {
            if t.light != NO_LIGHT {
                t.light = renumber[t.light as usize];
            }
        }
    }

    /// The index of the material of light surfaces, added on first use.
    fn black_material(&mut self) -> u32 {
        match self.materials.iter().position(|m| *m == Material::Black) {
            Some(i) => i as u32,
            None => {
                // Keep the names aligned when the loader keeps them.
                if self.material_names.len() == self.materials.len() {
                    self.material_names.push("(area light surface)".into());
                }
                self.materials.push(Material::Black);
                (self.materials.len() - 1) as u32
            }
        }
    }

    /// Radiance leaving the surface of `si` toward world direction `wo`: from the
    /// light when the surface is an area light's, else from the material.
    pub fn emission(&self, si: &SurfaceInteraction, wo: Vec3) -> Color {
        let cos_out = wo.dot(si.ng);
        let le = match self.lights.get(si.light as usize) {
            Some(Light::Area(a)) => a.emitted(cos_out),
            _ => self.materials[si.material as usize].emitted(Vec3::new(0.0, 0.0, cos_out)),
        };
        #[cfg(feature = "testing")]
        if !self.surface_emission.is_empty() {
            return le + self.attached_emission(si.prim);
        }
        le
    }

    /// The test-only emission attached to `prim`.
    #[cfg(feature = "testing")]
    fn attached_emission(&self, prim: PrimId) -> Color {
        self.surface_emission
            .iter()
            .filter(|(p, _)| *p == prim)
            .map(|(_, c)| *c)
            .sum()
    }

    /// Emitters that no `Light` represents (emission materials outside area lights, and
    /// in tests attached surface emission): only BSDF sampling can find them.
    pub fn has_unsampled_emitters(&self) -> bool {
        #[cfg(feature = "testing")]
        if !self.surface_emission.is_empty() {
            return true;
        }
        self.triangles
            .iter()
            .any(|t| t.light == NO_LIGHT && self.materials[t.material as usize].flags().emissive)
            || self
                .spheres
                .iter()
                .any(|s| self.materials[s.material as usize].flags().emissive)
    }

    /// The texture coordinates at barycentrics `(b0, b1, b2)` of triangle `i`, or, for a
    /// triangle without them, `(b1, b2)`.
    #[inline]
    fn texcoord(&self, i: usize, b0: f32, b1: f32, b2: f32) -> Vec2 {
        match self.triangle_uvs.get(i).copied().flatten() {
            Some([a, b, c]) => {
                let uv = |k: u32| self.uvs[k as usize];
                b0 * uv(a) + b1 * uv(b) + b2 * uv(c)
            }
            None => Vec2::new(b1, b2),
        }
    }

    /// The diffuse albedo of `material` at texture coordinates `uv`: its albedo,
    /// times its texture's colour there when it has one. The one place shading
    /// reads textures (a scalar function, called per lane by vector code).
    #[inline]
    pub fn albedo(&self, material: u32, uv: Vec2) -> Color {
        let base = match self.materials[material as usize] {
            Material::Lambertian { albedo } => albedo,
            _ => Color::ZERO,
        };
        match self
            .material_textures
            .get(material as usize)
            .copied()
            .flatten()
        {
            Some(t) => base * self.textures[t as usize].eval(uv),
            None => base,
        }
    }

    /// The material at a hit, its texture applied: a Lambertian material with a
    /// texture becomes the Lambertian of its albedo at `si.uv`.
    #[inline]
    pub fn material_at(&self, si: &SurfaceInteraction) -> Material {
        let m = self.materials[si.material as usize];
        match m {
            Material::Lambertian { .. }
                if self
                    .material_textures
                    .get(si.material as usize)
                    .is_some_and(Option::is_some) =>
            {
                Material::Lambertian {
                    albedo: self.albedo(si.material, si.uv),
                }
            }
            _ => m,
        }
    }

    /// Whether any material has a texture.
    pub fn has_textures(&self) -> bool {
        self.material_textures.iter().any(Option::is_some)
    }

    pub fn num_prims(&self) -> usize {
        self.triangles.len() + self.spheres.len()
    }

    /// Bounds of one primitive (triangles first, then spheres).
    pub fn prim_bounds(&self, prim: PrimId) -> Aabb {
        let i = prim as usize;
        if i < self.triangles.len() {
            let t = &self.triangles[i];
            let mut b = Aabb::from_point(self.positions[t.v[0] as usize]);
            b.grow(self.positions[t.v[1] as usize]);
            b.grow(self.positions[t.v[2] as usize]);
            b
        } else {
            let s = &self.spheres[i - self.triangles.len()];
            Aabb::new(
                s.centre - Vec3::splat(s.radius),
                s.centre + Vec3::splat(s.radius),
            )
        }
    }

    /// Corner positions of triangle `i`.
    #[inline]
    pub fn triangle_positions(&self, i: usize) -> [Vec3; 3] {
        let t = &self.triangles[i];
        [
            self.positions[t.v[0] as usize],
            self.positions[t.v[1] as usize],
            self.positions[t.v[2] as usize],
        ]
    }

    /// Full surface interaction of a primitive hit along `ray`. Points come from
    /// barycentrics (triangles) or are projected onto the sphere, so their error
    /// scales with the scene's magnitudes, not with `t`.
    pub fn interaction(&self, ray: &Ray, h: &PrimHit) -> SurfaceInteraction {
        let i = h.prim as usize;
        if i < self.triangles.len() {
            self.triangle_interaction(i, h)
        } else {
            self.sphere_interaction(ray, i - self.triangles.len(), h)
        }
    }

    /// The axes on which triangle `i`'s three corners have the same coordinate.
    fn exact_axes(&self, i: usize) -> glam::BVec3 {
        let [p0, p1, p2] = self.triangle_positions(i);
        p0.cmpeq(p1) & p0.cmpeq(p2)
    }

    fn triangle_interaction(&self, i: usize, h: &PrimHit) -> SurfaceInteraction {
        let tri = &self.triangles[i];
        let [p0, p1, p2] = self.triangle_positions(i);
        let b0 = 1.0 - h.b1 - h.b2;
        // Relative to corner 0: `p0 + b1·e1 + b2·e2` lies on the triangle's plane for any
        // barycentrics, so its error is the rounding of the edge terms (small, like the
        // triangle) plus one rounding of the sum (≤ γ₁|p|). The absolute form
        // `b0·p0 + b1·p1 + b2·p2` carries γ₇·|p|: 7 ulps of the coordinates, which every
        // spawned ray is offset by (4e-3 at 1e4; stability case 5).
        let (e1, e2) = (p1 - p0, p2 - p0);
        let local = h.b1 * e1 + h.b2 * e2;
        let p = p0 + local;
        let p_error = gamma(2) * p.abs() + gamma(4) * ((h.b1 * e1).abs() + (h.b2 * e2).abs());
        let p = into_triangle(p, p0, local, [p0, p1, p2], [b0, h.b1, h.b2]);
        // On an axis where the three corners agree (a wall, floor or ceiling), both edge
        // terms are exact zeros and `p` is corner 0's own coordinate: no error there, so
        // rays leave such a plane from on it, as they do from a plane through 0. Else a
        // floor at 1e5 sends them ~2e-2 up, inside a ball resting on it (case 5).
        let p_error = Vec3::select(self.exact_axes(i), Vec3::ZERO, p_error);
        let mut ng = (p1 - p0).cross(p2 - p0).normalize_or_zero();
        let mut ns = ng;
        if let Some(n) = tri.n {
            let [n0, n1, n2] = n.map(|k| self.normals[k as usize]);
            // The loader already oriented ng toward the corner-normal sum; interpolate.
            let interp = (b0 * n0 + h.b1 * n1 + h.b2 * n2).normalize_or_zero();
            if (n0 + n1 + n2).dot(ng) < 0.0 {
                ng = -ng;
            }
            if interp != Vec3::ZERO {
                ns = interp;
            }
        }
        if ns.dot(ng) < 0.0 {
            // Shading normals are kept on the front side so BSDF sides agree with ng.
            ns = -ns;
        }
        SurfaceInteraction {
            t: h.t,
            p,
            p_error,
            ng,
            ns,
            uv: self.texcoord(i, b0, h.b1, h.b2),
            prim: h.prim,
            material: tri.material,
            light: tri.light,
            sphere: None,
        }
    }

    fn sphere_interaction(&self, ray: &Ray, si: usize, h: &PrimHit) -> SurfaceInteraction {
        let s = &self.spheres[si];
        // Relative to the centre: `o − centre` is exact for nearby points however far
        // from the origin, where the absolute `o + t·d` would round to the f32 grid there
        // (4e-3 at 1e5, a normal 1e-2 rad off on a ball of radius 0.4).
        let raw = (ray.o - s.centre) + h.t * ray.d;
        let n = raw.normalize_or_zero();
        let n = if n == Vec3::ZERO { Vec3::Y } else { n };
        let p = s.centre + s.radius * n;
        // `p = centre ⊕ r·n`: one rounding of the sum (≤ γ₁|p|) plus the error of `r·n`
        // (normalisation and product, ≤ γ₄·r); the centre itself is exact. Rays leave
        // from within an ulp of `p` (`sphere_spawn_origin`), not offset by this bound,
        // which is 2–3 cm at 1e5: more than a resting ball's gap to the floor over ~10 cm.
        let p_error = gamma(2) * p.abs() + Vec3::splat(gamma(4) * s.radius);
        SurfaceInteraction {
            t: h.t,
            p,
            p_error,
            ng: n,
            ns: n,
            uv: Vec2::ZERO,
            prim: h.prim,
            material: s.material,
            light: NO_LIGHT,
            sphere: Some((s.centre, s.radius)),
        }
    }

    /// Barycentrics `b1, b2` of `q`, a point in triangle `i`'s plane (dual basis), if it
    /// lies in the triangle.
    fn barycentrics(&self, i: usize, q: Vec3) -> Option<[f32; 2]> {
        let [p0, p1, p2] = self.triangle_positions(i);
        let (e1, e2, d) = (p1 - p0, p2 - p0, q - p0);
        let m = e1.cross(e2);
        let m2 = m.length_squared();
        let (b1, b2) = (d.cross(e2).dot(m) / m2, e1.cross(d).dot(m) / m2);
        (b1 >= 0.0 && b2 >= 0.0 && b1 + b2 <= 1.0).then_some([b1, b2])
    }

    /// `si` (found by a ray spawned from surface point `from` in unit direction `w`) moved
    /// onto the line `from + s·w` itself, on the same primitive.
    ///
    /// A spawned ray starts off its surface by the point's rounding error, on a parallel
    /// line (`offset_ray_origin`): what it finds is seen from that displaced origin, a
    /// little closer than from `from` (~2 ulps of the coordinates: 2e-2 at 1e5). At
    /// every bounce that biases toward nearer, brighter light: a mirror's reflection, a
    /// caustic, a light's inverse square (stability case 5). The traced ray decides
    /// which primitive is hit, robustly; where on it is solved here, relative to `from`:
    /// the line meets the plane of the hit (a sphere's tangent plane, O(δ²/r) off the
    /// sphere), and a sphere's normal is taken again there. Grazing hits (|cos| < 0.05)
    /// and points outside the hit triangle (the two lines straddle an edge) are left as
    /// found.
    pub fn on_line(&self, si: &SurfaceInteraction, from: Vec3, w: Vec3) -> SurfaceInteraction {
        let cos = w.dot(si.ng);
        if cos.abs() < 0.05 {
            return *si;
        }
        let s = (si.p - from).dot(si.ng) / cos;
        if !(s > 0.0 && s.is_finite()) {
            return *si;
        }
        let p = from + s * w;
        let i = si.prim as usize;
        let mut out = *si;
        // The found point's error (the plane's), plus the rounding of `from + s·w`.
        let mut p_error = si.p_error + gamma(1) * p.abs() + gamma(5) * (s * w).abs();
        let mut p = p;
        if i < self.triangles.len() {
            let Some([b1, b2]) = self.barycentrics(i, p) else {
                return *si;
            };
            let corners = self.triangle_positions(i);
            p = into_triangle(p, from, s * w, corners, [1.0 - b1 - b2, b1, b2]);
            // On an axis where the corners agree the plane's coordinate is exact: keep it.
            let exact = self.exact_axes(i);
            p = Vec3::select(exact, si.p, p);
            p_error = Vec3::select(exact, Vec3::ZERO, p_error);
        } else {
            // Relative to the centre, as in `sphere_interaction`.
            let sp = &self.spheres[i - self.triangles.len()];
            let n = ((from - sp.centre) + s * w).normalize_or_zero();
            if n.dot(si.ng) <= 0.0 {
                return *si;
            }
            (out.ng, out.ns) = (n, n);
        }
        out.p_error = p_error;
        out.p = p;
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A floor triangle at 1e5 (an ulp is 7.8e-3) whose edge `x = 1e5 + 1` a wall would
    /// stand on.
    fn floor_at_1e5() -> Scene {
        let o = 1e5;
        let mut s = Scene {
            positions: vec![
                Vec3::new(o - 1.0, o, o - 1.0),
                Vec3::new(o + 1.0, o, o - 1.0),
                Vec3::new(o + 1.0, o, o + 1.0),
            ],
            materials: vec![Material::Black],
            ..Default::default()
        };
        s.triangles.push(Triangle {
            v: [0, 1, 2],
            n: None,
            material: 0,
            light: NO_LIGHT,
        });
        s
    }

    #[test]
    fn points_within_half_an_ulp_of_an_edge_stay_in_their_triangle() {
        let s = floor_at_1e5();
        let hit = |b1: f32, b2: f32| PrimHit {
            t: 1.0,
            prim: 0,
            b1,
            b2,
        };
        // x = 1e5 + 1 − 1e-3 exactly: to nearest that is the edge itself, on the wall.
        let near = s.triangle_interaction(0, &hit(0.4995, 0.5));
        assert!(near.p.x < 1e5 + 1.0, "{}", near.p);
        assert_eq!(near.p.y, 1e5);
        assert!(1e5 + 1.0 - near.p.x <= 2.0 * 7.8125e-3, "{}", near.p);
        // Away from the edges the point is rounded to nearest, as it was.
        let [p0, p1, p2] = s.triangle_positions(0);
        let mid = s.triangle_interaction(0, &hit(0.3, 0.3));
        assert_eq!(mid.p, p0 + (0.3 * (p1 - p0) + 0.3 * (p2 - p0)));
    }
}
