//! The flat scene ember renders: world-space triangles and spheres, materials,
//! lights and one camera. No scene graph survives loading.

pub mod collada;
mod interaction;

pub use crate::geometry::{PrimHit, PrimId};
pub use interaction::Hits;

use crate::geometry::{ray::gamma, Aabb, Ray};
use crate::lanes::rays::HitPacket;
use crate::lanes::{One, V3};
use crate::lights::{AreaLight, Light};
use crate::materials::{Bsdf, Material};
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
    /// The triangle's corners (unused for spheres).
    pub corners: [Vec3; 3],
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

    /// Where a ray leaving this point toward `w` starts (`Hits::spawn_origins`).
    fn spawn_origin(&self, w: Vec3) -> Vec3 {
        self.hits().spawn_origins(One, 1, w.into()).vec3()
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

    /// This point as the one lane of a [`Hits`].
    fn hits(&self) -> Hits<One> {
        let lane = |v: u32| {
            let mut a = [0; crate::lanes::LANES];
            a[0] = v;
            a
        };
        let (centre, radius) = self.sphere.unwrap_or((Vec3::ZERO, 0.0));
        Hits {
            p: self.p.into(),
            p_error: self.p_error.into(),
            ng: self.ng.into(),
            ns: self.ns.into(),
            uv: (self.uv.x, self.uv.y),
            prim: lane(self.prim),
            material: lane(self.material),
            light: lane(self.light),
            triangles: self.sphere.is_none() as u32,
            corners: self.corners.map(V3::from),
            centre: centre.into(),
            radius,
        }
    }

    /// The one lane of `h`, hit at `t`.
    fn from_hits(h: &Hits<One>, t: f32) -> Self {
        SurfaceInteraction {
            t,
            p: h.p.vec3(),
            p_error: h.p_error.vec3(),
            ng: h.ng.vec3(),
            ns: h.ns.vec3(),
            uv: Vec2::new(h.uv.0, h.uv.1),
            prim: h.prim[0],
            material: h.material[0],
            light: h.light[0],
            sphere: (h.triangles & 1 == 0).then(|| (h.centre.vec3(), h.radius)),
            corners: h.corners.map(V3::vec3),
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
        let material = self.light_surface_material();
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
    fn light_surface_material(&mut self) -> u32 {
        match self
            .materials
            .iter()
            .position(|m| *m == Material::light_surface())
        {
            Some(i) => i as u32,
            None => {
                // Keep the names aligned when the loader keeps them.
                if self.material_names.len() == self.materials.len() {
                    self.material_names.push("(area light surface)".into());
                }
                self.materials.push(Material::light_surface());
                (self.materials.len() - 1) as u32
            }
        }
    }

    /// Radiance leaving the surface of `si` toward world direction `wo`: from the
    /// light when the surface is an area light's, else from the material.
    pub fn emission(&self, si: &SurfaceInteraction, wo: Vec3) -> Color {
        let cos_out = wo.dot(si.ng);
        match self.lights.get(si.light as usize) {
            Some(Light::Area(a)) => a.emitted(cos_out),
            _ => self.materials[si.material as usize].emitted(Vec3::new(0.0, 0.0, cos_out)),
        }
    }

    /// Whether some surface emits light that can leave it: an emissive sphere, or an
    /// emissive triangle of non-zero area.
    pub fn has_emitting_surface(&self) -> bool {
        let emits = |m: u32| self.materials[m as usize].emits();
        self.spheres.iter().any(|s| emits(s.material))
            || (0..self.triangles.len()).any(|i| {
                let [a, b, c] = self.triangle_positions(i);
                emits(self.triangles[i].material) && (b - a).cross(c - a) != Vec3::ZERO
            })
    }

    /// Emitters that no `Light` represents (emissive materials outside area lights):
    /// only BSDF sampling can find them.
    pub fn has_unsampled_emitters(&self) -> bool {
        let emits = |m: u32| self.materials[m as usize].emits();
        self.triangles
            .iter()
            .any(|t| t.light == NO_LIGHT && emits(t.material))
            || self.spheres.iter().any(|s| emits(s.material))
    }

    /// The texture coordinates at barycentrics `(b0, b1, b2)` of triangle `i`, or, for a
    /// triangle without them, `(b1, b2)`.
    #[inline]
    pub(crate) fn texcoord(&self, i: usize, b0: f32, b1: f32, b2: f32) -> Vec2 {
        match self.triangle_uvs.get(i).copied().flatten() {
            Some([a, b, c]) => {
                let uv = |k: u32| self.uvs[k as usize];
                b0 * uv(a) + b1 * uv(b) + b2 * uv(c)
            }
            None => Vec2::new(b1, b2),
        }
    }

    /// The BSDF of `material` at texture coordinates `uv`: a Lambertian material with
    /// a diffuse texture has its albedo times the texture's colour there. The one
    /// place shading reads textures (per lane, by the transport).
    #[inline]
    pub fn bsdf_at(&self, material: u32, uv: Vec2) -> Bsdf {
        let bsdf = self.materials[material as usize].bsdf;
        let texture = self
            .material_textures
            .get(material as usize)
            .copied()
            .flatten();
        match (bsdf, texture) {
            (Bsdf::Lambertian(mut b), Some(t)) => {
                b.albedo = (b.albedo.vec3() * self.textures[t as usize].eval(uv)).into();
                Bsdf::Lambertian(b)
            }
            _ => bsdf,
        }
    }

    /// The material at a hit, its texture applied.
    pub fn material_at(&self, si: &SurfaceInteraction) -> Material {
        Material {
            bsdf: self.bsdf_at(si.material, si.uv),
            ..self.materials[si.material as usize]
        }
    }

    /// Whether any material has a texture.
    pub fn has_textures(&self) -> bool {
        !self.textures.is_empty() && self.material_textures.iter().any(Option::is_some)
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

    /// Full surface interaction of a primitive hit along `ray` ([`Scene::hits`] for
    /// one path).
    pub fn interaction(&self, ray: &Ray, h: &PrimHit) -> SurfaceInteraction {
        let mut hp = HitPacket::default();
        hp.set(0, Some(*h));
        let hits = self.hits(One, 1, ray.o.into(), ray.d.into(), &hp);
        SurfaceInteraction::from_hits(&hits, h.t)
    }

    /// `si` (found by a ray spawned from surface point `from` in unit direction `w`)
    /// moved onto the line `from + s·w` itself ([`Hits::on_line`] for one path).
    pub fn on_line(&self, si: &SurfaceInteraction, from: Vec3, w: Vec3) -> SurfaceInteraction {
        let hits = si.hits().on_line(One, 1, from.into(), w.into());
        SurfaceInteraction {
            uv: si.uv,
            ..SurfaceInteraction::from_hits(&hits, si.t)
        }
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
            materials: vec![Material::light_surface()],
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
        let ray = Ray::new(Vec3::new(1e5, 1e5 + 1.0, 1e5), Vec3::NEG_Y);
        let near = s.interaction(&ray, &hit(0.4995, 0.5));
        assert!(near.p.x < 1e5 + 1.0, "{}", near.p);
        assert_eq!(near.p.y, 1e5);
        assert!(1e5 + 1.0 - near.p.x <= 2.0 * 7.8125e-3, "{}", near.p);
        // Away from the edges the point is rounded to nearest, as it was.
        let [p0, p1, p2] = s.triangle_positions(0);
        let mid = s.interaction(&ray, &hit(0.3, 0.3));
        assert_eq!(mid.p, p0 + (0.3 * (p1 - p0) + 0.3 * (p2 - p0)));
    }
}
