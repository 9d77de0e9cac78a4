//! Scenes generated in code: the ~1M-triangle benchmark mesh and the awkward
//! geometry (degenerate and sliver triangles, shared edges, nested spheres) that the
//! backend cross-checks need and no course scene has.

use crate::color::Color;
use crate::geometry::Aabb;
use crate::materials::Material;
use crate::sampling::Rng;
use crate::scene::{CameraDesc, Scene, Sphere, Triangle, NO_LIGHT};
use glam::Vec3;
use std::f32::consts::PI;

/// A scene of bare geometry with one grey Lambertian material and the default camera.
pub fn geometry_scene(positions: Vec<Vec3>, tris: &[[u32; 3]], spheres: &[(Vec3, f32)]) -> Scene {
    let triangles = tris
        .iter()
        .map(|&v| Triangle {
            v,
            n: None,
            material: 0,
            light: NO_LIGHT,
        })
        .collect();
    let spheres = spheres
        .iter()
        .map(|&(centre, radius)| Sphere {
            centre,
            radius,
            material: 0,
        })
        .collect();
    // Look down a diagonal: the default −Z view sees the grids edge-on.
    let forward = Vec3::new(-0.4, -0.6, -0.7).normalize();
    let up = (Vec3::Y - Vec3::Y.dot(forward) * forward).normalize();
    let mut scene = Scene {
        camera: CameraDesc {
            forward,
            up,
            ..CameraDesc::default()
        },
        positions,
        triangles,
        spheres,
        materials: vec![Material::lambertian(Color::splat(0.5))],
        ..Scene::default()
    };
    scene.bounds =
        (0..scene.num_prims() as u32).fold(Aabb::EMPTY, |b, p| b.union(&scene.prim_bounds(p)));
    scene
}

/// A unit sphere tessellated into about `target_tris` triangles with a smooth radial
/// bump field (±6%), so neighbouring triangles are not coplanar and the BVH is not trivial.
pub fn displaced_sphere(target_tris: usize) -> Scene {
    // Interior rings give 2·lon triangles each; lon = 2·lat keeps quads near-square.
    let lat = ((target_tris as f32 / 4.0).sqrt().ceil() as u32).max(2);
    let lon = 2 * lat;
    let radius = |theta: f32, phi: f32| {
        1.0 + 0.04 * (7.0 * theta).sin() * (5.0 * phi).cos()
            + 0.02 * (23.0 * phi + 3.0 * theta).sin()
    };
    let mut positions = vec![Vec3::new(0.0, radius(0.0, 0.0), 0.0)];
    for i in 1..lat {
        let theta = PI * i as f32 / lat as f32;
        for j in 0..lon {
            let phi = 2.0 * PI * j as f32 / lon as f32;
            let dir = Vec3::new(
                theta.sin() * phi.cos(),
                theta.cos(),
                theta.sin() * phi.sin(),
            );
            positions.push(radius(theta, phi) * dir);
        }
    }
    let south = positions.len() as u32;
    positions.push(Vec3::new(0.0, -radius(PI, 0.0), 0.0));
    let ring = |i: u32, j: u32| 1 + (i - 1) * lon + j % lon;
    let mut tris = Vec::with_capacity(2 * (lat as usize) * lon as usize);
    for j in 0..lon {
        tris.push([0, ring(1, j + 1), ring(1, j)]);
        tris.push([south, ring(lat - 1, j), ring(lat - 1, j + 1)]);
    }
    for i in 1..lat - 1 {
        for j in 0..lon {
            let (a, b, c, d) = (
                ring(i, j),
                ring(i, j + 1),
                ring(i + 1, j),
                ring(i + 1, j + 1),
            );
            tris.push([a, b, d]);
            tris.push([a, d, c]);
        }
    }
    geometry_scene(positions, &tris, &[])
}

/// An `n × n` grid of quads on a gently curved sheet, two triangles per quad with
/// alternating diagonals: every interior edge and vertex is shared, the case where a
/// non-watertight test lets rays slip through.
pub fn shared_edge_grid(n: u32) -> Scene {
    let mut positions = Vec::new();
    for i in 0..=n {
        for j in 0..=n {
            let (x, z) = (
                i as f32 / n as f32 * 2.0 - 1.0,
                j as f32 / n as f32 * 2.0 - 1.0,
            );
            positions.push(Vec3::new(x, 0.15 * (2.0 * x).sin() * (3.0 * z).cos(), z));
        }
    }
    let id = |i: u32, j: u32| i * (n + 1) + j;
    let mut tris = Vec::new();
    for i in 0..n {
        for j in 0..n {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i, j + 1), id(i + 1, j + 1));
            if (i + j) % 2 == 0 {
                tris.extend([[a, b, d], [a, d, c]]);
            } else {
                tris.extend([[a, b, c], [b, d, c]]);
            }
        }
    }
    geometry_scene(positions, &tris, &[])
}

/// Random triangles of which a third are degenerate (repeated or collinear corners)
/// and a third are slivers (height 1e-4 of their length), mixed with ordinary ones.
pub fn degenerate_soup(n: usize, seed: u64) -> Scene {
    let mut rng = Rng::from_seed(seed);
    let mut point = |s: f32| Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * s;
    let mut positions = Vec::new();
    let mut tris = Vec::new();
    for k in 0..n {
        let base = point(4.0) - Vec3::splat(2.0);
        let (e1, e2) = (point(1.0) - Vec3::splat(0.5), point(1.0) - Vec3::splat(0.5));
        let corners = match k % 6 {
            0 => [base, base, base + e1],            // two corners equal
            1 => [base, base + e1, base + 0.5 * e1], // collinear
            2 => [base, base + e1, base + 0.5 * e1 + 1e-4 * e2],
            3 => [base, base + e1, base + 1e-4 * e2],
            _ => [base, base + e1, base + e2],
        };
        let first = positions.len() as u32;
        positions.extend(corners);
        tris.push([first, first + 1, first + 2]);
    }
    geometry_scene(positions, &tris, &[])
}

/// Spheres of mixed sizes, some overlapping and some nested, over a two-triangle
/// floor: exercises the id mapping (triangles first) and rays starting inside spheres.
pub fn sphere_cluster(n: usize, seed: u64) -> Scene {
    let mut rng = Rng::from_seed(seed);
    let mut spheres = Vec::new();
    for k in 0..n {
        let c = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 4.0 - Vec3::splat(2.0);
        let r = 0.05 + 0.5 * rng.next_f32();
        spheres.push((c, r));
        if k % 5 == 0 {
            spheres.push((c, 0.5 * r)); // nested, concentric
        }
    }
    let floor = vec![
        Vec3::new(-3.0, -2.5, -3.0),
        Vec3::new(3.0, -2.5, -3.0),
        Vec3::new(3.0, -2.5, 3.0),
        Vec3::new(-3.0, -2.5, 3.0),
    ];
    geometry_scene(floor, &[[0, 1, 2], [0, 2, 3]], &spheres)
}

/// `n` independent random triangles in the box [−1, 1]³: no shared vertices, heavy
/// overlap, no surface structure, the hard case for a BVH. Corners lie in a cube of
/// side `16/√n` around a uniform centre, so the total area (≈ 0.077·side² per
/// triangle) and with it the mean free path of a ray (about one box side) stay the
/// same at every `n`, and only the fineness of the geometry changes.
pub fn random_soup(n: usize, seed: u64) -> Scene {
    let mut rng = Rng::from_seed(seed);
    let side = 16.0 / (n.max(1) as f32).sqrt();
    let mut unit = || Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
    let mut positions = Vec::with_capacity(3 * n);
    for _ in 0..n {
        let centre = 2.0 * unit() - Vec3::ONE;
        for _ in 0..3 {
            positions.push(centre + side * (unit() - Vec3::splat(0.5)));
        }
    }
    let tris: Vec<[u32; 3]> = (0..n as u32)
        .map(|t| [3 * t, 3 * t + 1, 3 * t + 2])
        .collect();
    geometry_scene(positions, &tris, &[])
}
