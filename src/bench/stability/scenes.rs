//! The stability scenes: the hand-written files of `scenes/stability/` (embedded, so
//! the report runs from any directory) and the programmatic ones the format cannot
//! express: rescaled and translated copies, a glass slab in front of a light at
//! normal incidence, a fine grid seen at grazing angles, degenerate triangles.

use crate::geometry::Aabb;
use crate::lights::{AreaLight, Light};
use crate::materials::Material;
use crate::scene::{collada, CameraDesc, Scene, Sphere, Triangle, NO_LIGHT};
use crate::{Color, Vec3};
use anyhow::{Context, Result};

/// A file of `scenes/stability/` (or `scenes/`), by name.
pub fn embedded(name: &str) -> Result<Scene> {
    let text = match name {
        "point_light.dae" => include_str!("../../../scenes/stability/point_light.dae"),
        "small_light.dae" => include_str!("../../../scenes/stability/small_light.dae"),
        "glossy_large_light.dae" => {
            include_str!("../../../scenes/stability/glossy_large_light.dae")
        }
        "rough_small_light.dae" => include_str!("../../../scenes/stability/rough_small_light.dae"),
        "caustic.dae" => include_str!("../../../scenes/stability/caustic.dae"),
        "cornell.dae" => include_str!("../../../scenes/cornell.dae"),
        _ => anyhow::bail!("{name}: no such stability scene"),
    };
    collada::parse(text, name).with_context(|| format!("stability scene {name}"))
}

/// `p ↦ scale·p + offset` applied to every position, sphere, light and the bounds.
/// Radiance is unchanged, so the image must not change: the camera is derived from the
/// bounds and moves along.
pub fn transformed(scene: &Scene, scale: f32, offset: Vec3) -> Scene {
    let map = |p: Vec3| scale * p + offset;
    let mut s = scene.clone();
    s.positions.iter_mut().for_each(|p| *p = map(*p));
    for sp in &mut s.spheres {
        sp.centre = map(sp.centre);
        sp.radius *= scale;
    }
    for l in &mut s.lights {
        match l {
            Light::Area(a) => {
                a.centre = map(a.centre);
                a.ex *= scale;
                a.ey *= scale;
            }
            Light::Point { position, .. } => *position = map(*position),
            Light::Spot(spot) => spot.position = map(spot.position),
            Light::Directional { .. } | Light::Ambient { .. } | Light::Environment(_) => {}
        }
    }
    let mut b = Aabb::from_point(map(scene.bounds.min));
    b.grow(map(scene.bounds.max));
    s.bounds = b;
    s
}

/// A scene under construction from quads, spheres and lights.
#[derive(Default)]
pub struct SceneBuilder {
    scene: Scene,
}

impl SceneBuilder {
    pub fn material(&mut self, m: Material) -> u32 {
        self.scene.materials.push(m);
        self.scene.materials.len() as u32 - 1
    }

    pub fn triangle(&mut self, p: [Vec3; 3], material: u32, light: u32) {
        let base = self.scene.positions.len() as u32;
        self.scene.positions.extend_from_slice(&p);
        self.scene.triangles.push(Triangle {
            v: [base, base + 1, base + 2],
            n: None,
            material,
            light,
        });
    }

    /// Parallelogram `origin + s·ex + t·ey`, `s, t ∈ [0, 1]`; its front is `ex × ey`.
    pub fn quad(&mut self, origin: Vec3, ex: Vec3, ey: Vec3, material: u32) {
        self.triangle([origin, origin + ex, origin + ex + ey], material, NO_LIGHT);
        self.triangle([origin, origin + ex + ey, origin + ey], material, NO_LIGHT);
    }

    /// Axis-aligned box whose faces' fronts point outward.
    pub fn cuboid(&mut self, min: Vec3, max: Vec3, material: u32) {
        let d = max - min;
        let (x, y, z) = (
            Vec3::new(d.x, 0.0, 0.0),
            Vec3::new(0.0, d.y, 0.0),
            Vec3::new(0.0, 0.0, d.z),
        );
        self.quad(min, y, x, material); // −z
        self.quad(min + z, x, y, material); // +z
        self.quad(min, x, z, material); // −y
        self.quad(min + y, z, x, material); // +y
        self.quad(min, z, y, material); // −x
        self.quad(min + x, y, z, material); // +x
    }

    pub fn sphere(&mut self, centre: Vec3, radius: f32, material: u32) {
        self.scene.spheres.push(Sphere {
            centre,
            radius,
            material,
        });
    }

    /// A one-sided rectangular area light `centre ± ex/2 ± ey/2` emitting toward `ex × ey`.
    pub fn area_light(&mut self, centre: Vec3, ex: Vec3, ey: Vec3, radiance: Color) {
        self.scene.add_area_light(AreaLight {
            centre,
            ex,
            ey,
            normal: ex.cross(ey).normalize_or_zero(),
            radiance,
        });
    }

    pub fn light(&mut self, light: Light) {
        self.scene.lights.push(light);
    }

    /// The scene, with bounds over the non-light primitives (spec §4) and the given view.
    pub fn finish(mut self, camera: CameraDesc) -> Scene {
        let mut b = Aabb::EMPTY;
        for (i, t) in self.scene.triangles.iter().enumerate() {
            if t.light == NO_LIGHT {
                b = b.union(&self.scene.prim_bounds(i as u32));
            }
        }
        for (i, _) in self.scene.spheres.iter().enumerate() {
            b = b.union(
                &self
                    .scene
                    .prim_bounds((self.scene.triangles.len() + i) as u32),
            );
        }
        self.scene.bounds = b;
        self.scene.camera = camera;
        self.scene
    }
}

/// Index of refraction of the slab and caustic glass.
pub const GLASS_IOR: f32 = 1.5;

/// A 4 × 4 light of radiance `radiance` facing −z at z = 2 behind a glass slab
/// (z ∈ [1, 1.2], 3 × 3): a camera at the origin looking along +z sees the light only
/// through the slab, at near-normal incidence.
pub fn slab_in_front_of_light(radiance: f32) -> Scene {
    let mut b = SceneBuilder::default();
    let glass = b.material(Material::glass(GLASS_IOR, Color::ONE, Color::ONE));
    b.cuboid(Vec3::new(-1.5, -1.5, 1.0), Vec3::new(1.5, 1.5, 1.2), glass);
    b.area_light(
        Vec3::new(0.0, 0.0, 2.0),
        Vec3::new(0.0, 4.0, 0.0),
        Vec3::new(4.0, 0.0, 0.0),
        Color::splat(radiance),
    );
    b.finish(CameraDesc {
        forward: Vec3::Z,
        up: Vec3::Y,
        tan_half_x: Some(0.05),
        tan_half_y: None,
        ..CameraDesc::default()
    })
}

/// Number of grid cells per side of `grid_plane`.
pub const GRID_CELLS: u32 = 64;
/// Half the side of `grid_plane`.
pub const GRID_HALF: f32 = 4.0;

/// A `GRID_CELLS²` grid of quads (two triangles each, sharing edges and vertices) on
/// y = 0, `|x|, |z| ≤ GRID_HALF`, under an ambient sky of radiance 1.
pub fn grid_plane() -> Scene {
    let mut b = SceneBuilder::default();
    let m = b.material(Material::lambertian(Color::splat(0.5)));
    let n = GRID_CELLS;
    let step = 2.0 * GRID_HALF / n as f32;
    let corner = |i: u32, j: u32| {
        Vec3::new(
            -GRID_HALF + i as f32 * step,
            0.0,
            -GRID_HALF + j as f32 * step,
        )
    };
    let base = b.scene.positions.len() as u32;
    for j in 0..=n {
        for i in 0..=n {
            b.scene.positions.push(corner(i, j));
        }
    }
    let id = |i: u32, j: u32| base + j * (n + 1) + i;
    for j in 0..n {
        for i in 0..n {
            // Winding for +y fronts: (p1−p0)×(p2−p0) with p1 along z, p2 along x.
            let t = |v: [u32; 3]| Triangle {
                v,
                n: None,
                material: m,
                light: NO_LIGHT,
            };
            b.scene
                .triangles
                .push(t([id(i, j), id(i, j + 1), id(i + 1, j + 1)]));
            b.scene
                .triangles
                .push(t([id(i, j), id(i + 1, j + 1), id(i + 1, j)]));
        }
    }
    b.light(Light::Ambient {
        radiance: Color::ONE,
    });
    // Looking along +z and slightly down; the eye position is set by the caller.
    b.finish(CameraDesc {
        forward: Vec3::Z,
        up: Vec3::Y,
        tan_half_x: Some(0.4),
        tan_half_y: None,
        ..CameraDesc::default()
    })
}

/// A closed grey room (2 × 2 × 2, fronts inward) lit by a ceiling light, holding
/// degenerate triangles: zero area (repeated corner), collinear corners, needles
/// 1e-7 wide, a triangle with a corner at 1e-30 from another, and a zero-area light.
pub fn degenerate_room() -> Scene {
    let mut b = SceneBuilder::default();
    let grey = b.material(Material::lambertian(Color::splat(0.6)));
    let mirror = b.material(Material::mirror(Color::splat(0.9)));
    let glass = b.material(Material::glass(GLASS_IOR, Color::ONE, Color::ONE));
    let (lo, hi) = (Vec3::splat(-1.0), Vec3::splat(1.0));
    let d = hi - lo;
    let (x, y, z) = (
        Vec3::new(d.x, 0.0, 0.0),
        Vec3::new(0.0, d.y, 0.0),
        Vec3::new(0.0, 0.0, d.z),
    );
    // Inward fronts: the cuboid's windings reversed.
    b.quad(lo, x, y, grey);
    b.quad(lo + z, y, x, grey);
    b.quad(lo, z, x, grey);
    b.quad(lo + y, x, z, grey);
    b.quad(lo, y, z, grey);
    b.quad(lo + x, z, y, grey);
    b.area_light(
        Vec3::new(0.0, 0.99, 0.0),
        Vec3::new(0.0, 0.0, 0.5),
        Vec3::new(0.5, 0.0, 0.0),
        Color::splat(8.0),
    );
    b.area_light(
        Vec3::new(0.5, 0.99, 0.5),
        Vec3::new(0.0, 0.0, 0.5),
        Vec3::ZERO,
        Color::splat(8.0),
    );
    let p = Vec3::new(0.1, -0.3, 0.2);
    for m in [grey, mirror, glass] {
        let q = p + Vec3::new(0.2 * m as f32, 0.0, 0.0);
        b.triangle([q, q, q], m, NO_LIGHT);
        b.triangle([q, q + Vec3::X * 0.3, q + Vec3::X * 0.6], m, NO_LIGHT);
        b.triangle(
            [
                q,
                q + Vec3::new(0.5, 0.4, 0.0),
                q + Vec3::new(0.5, 0.4, 1e-7),
            ],
            m,
            NO_LIGHT,
        );
        b.triangle(
            [q, q + Vec3::splat(1e-30), q + Vec3::new(0.0, 0.4, 0.3)],
            m,
            NO_LIGHT,
        );
    }
    b.finish(CameraDesc {
        forward: Vec3::Z,
        up: Vec3::Y,
        tan_half_x: Some(0.5),
        tan_half_y: None,
        ..CameraDesc::default()
    })
}
