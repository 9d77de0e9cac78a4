//! Helpers shared by the BVH tests: scene construction, random rays, and the
//! comparison of an acceleration structure's answer with the brute-force oracle.

#![allow(dead_code)]

use ember::accel::{Accel, BruteForce, Bvh, BvhBuilder};
use ember::geometry::sphere::intersect_sphere;
use ember::geometry::triangle::intersect_triangle;
use ember::geometry::{Aabb, Ray};
use ember::sampling::{uniform_sphere, Sampler};
use ember::scene::{PrimHit, Scene, Sphere, Triangle, NO_LIGHT};
use glam::Vec3;

/// Relative tolerance on `t` when two structures report different primitives.
/// The BVH's box test is conservative against the exact hit point, but a reported
/// `t` carries the triangle test's own rounding (pbrt's δt, a few ulps); two
/// primitives hit within that error of each other (shared edges and vertices,
/// touching or coincident surfaces) may legitimately come out in either order.
/// 1e-5 is about 170 ulps: far above that error, far below any real separation
/// in these scenes.
pub const REL_T: f32 = 1e-5;

pub fn builders() -> [BvhBuilder; 2] {
    [BvhBuilder::Sah, BvhBuilder::Midpoint]
}

/// A scene holding only geometry (materials are irrelevant to intersection).
pub fn scene_from(positions: Vec<Vec3>, tris: Vec<[u32; 3]>, spheres: Vec<(Vec3, f32)>) -> Scene {
    let mut scene = Scene {
        positions,
        triangles: tris
            .into_iter()
            .map(|v| Triangle {
                v,
                n: None,
                material: 0,
                light: NO_LIGHT,
            })
            .collect(),
        spheres: spheres
            .into_iter()
            .map(|(centre, radius)| Sphere {
                centre,
                radius,
                material: 0,
            })
            .collect(),
        ..Scene::default()
    };
    scene.bounds =
        (0..scene.num_prims() as u32).fold(Aabb::EMPTY, |b, i| b.union(&scene.prim_bounds(i)));
    scene
}

/// The primitive tested on its own.
pub fn prim_alone(scene: &Scene, ray: &Ray, prim: u32) -> Option<f32> {
    let i = prim as usize;
    let ntri = scene.triangles.len();
    if i < ntri {
        let [p0, p1, p2] = scene.triangle_positions(i);
        intersect_triangle(ray, p0, p1, p2).map(|h| h.0)
    } else {
        let s = &scene.spheres[i - ntri];
        intersect_sphere(ray, s.centre, s.radius)
    }
}

fn close(a: f32, b: f32) -> bool {
    (a - b).abs() <= REL_T * a.abs().max(b.abs())
}

/// Checks a structure's nearest hit against the oracle's.
pub fn compare_nearest(
    scene: &Scene,
    ray: &Ray,
    got: Option<PrimHit>,
    want: Option<PrimHit>,
) -> Result<(), String> {
    let report = || format!("ray {ray:?}: got {got:?}, want {want:?}");
    match (got, want) {
        (None, None) => Ok(()),
        (Some(g), Some(w)) if g.prim == w.prim => {
            // Same primitive, same ray: the same test must give the same numbers.
            if g == w {
                Ok(())
            } else {
                Err(format!("same prim, different hit: {}", report()))
            }
        }
        (Some(g), Some(w)) => {
            // A tie (see REL_T); the reported primitive must really be hit there.
            if !close(g.t, w.t) {
                return Err(format!("different nearest prim: {}", report()));
            }
            if prim_alone(scene, ray, g.prim) != Some(g.t) {
                return Err(format!("reported hit is not a hit: {}", report()));
            }
            Ok(())
        }
        (Some(h), None) | (None, Some(h)) => {
            // Only a hit within rounding of t_max may be seen by one and not the other.
            if ray.t_max.is_finite() && close(h.t, ray.t_max) {
                Ok(())
            } else {
                Err(format!("hit/miss disagree: {}", report()))
            }
        }
    }
}

/// Checks `occluded` against the oracle's nearest hit on the same ray.
pub fn compare_occluded(ray: &Ray, got: bool, want: Option<PrimHit>) -> Result<(), String> {
    if got == want.is_some() {
        return Ok(());
    }
    match want {
        Some(h) if ray.t_max.is_finite() && close(h.t, ray.t_max) => Ok(()),
        _ => Err(format!(
            "occluded {got} but oracle says {want:?} for {ray:?}"
        )),
    }
}

/// Directions along the axes, with mixed signed zeros in the other components.
pub fn axis_direction(k: usize) -> Vec3 {
    const DIRS: [[f32; 3]; 8] = [
        [1.0, 0.0, 0.0],
        [-1.0, -0.0, 0.0],
        [0.0, 1.0, -0.0],
        [-0.0, -1.0, 0.0],
        [0.0, 0.0, 1.0],
        [-0.0, -0.0, -1.0],
        [2.5, -0.0, -0.0],
        [0.0, -3.0, 0.0],
    ];
    Vec3::from_array(DIRS[k % DIRS.len()])
}

/// A random ray for `bounds`: origins inside (and on the faces of) the bounds or
/// outside them, directions uniform, axis-aligned, or aimed at a given point;
/// mostly unbounded, sometimes a finite `[t_min, t_max]`.
pub fn random_ray(rng: &mut Sampler, bounds: &Aabb, targets: &[Vec3]) -> Ray {
    let size = bounds.diagonal().max(Vec3::splat(1e-3));
    let lerp = |u: Vec3| bounds.min + u * size;
    let u3 = |rng: &mut Sampler| Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
    let o = match (rng.next_f32() * 4.0) as u32 {
        0 => lerp(u3(rng)),
        // On a face: origin coordinates equal to a box bound.
        1 => {
            let mut p = lerp(u3(rng));
            let axis = (rng.next_f32() * 3.0) as usize % 3;
            p[axis] = if rng.next_f32() < 0.5 {
                bounds.min[axis]
            } else {
                bounds.max[axis]
            };
            p
        }
        2 => lerp(u3(rng) * 1.6 - Vec3::splat(0.3)),
        _ => bounds.centre() + size.length() * 1.5 * uniform_sphere(rng.next_2d()),
    };
    let d = match (rng.next_f32() * 3.0) as u32 {
        0 => uniform_sphere(rng.next_2d()),
        1 => axis_direction((rng.next_f32() * 8.0) as usize),
        _ if !targets.is_empty() => {
            let t =
                targets[((rng.next_f32() * targets.len() as f32) as usize).min(targets.len() - 1)];
            let d = t - o;
            if d == Vec3::ZERO {
                Vec3::X
            } else {
                d
            }
        }
        _ => uniform_sphere(rng.next_2d()),
    };
    let mut ray = Ray::new(o, d);
    if rng.next_f32() < 0.2 {
        ray.t_max = rng.next_f32() * 2.0 * size.length() / d.length();
        if rng.next_f32() < 0.5 {
            ray.t_min = ray.t_max * rng.next_f32() * 0.5;
        }
    }
    ray
}

/// Runs `rays` through BruteForce and both BVH builders; panics on the first
/// disagreement. The oracle's answers are computed in parallel.
pub fn check_against_brute(scene: &Scene, rays: &[Ray]) {
    use rayon::prelude::*;
    let brute = BruteForce::new(scene);
    let want: Vec<Option<PrimHit>> = rays.par_iter().map(|r| brute.intersect(r)).collect();
    for builder in builders() {
        let bvh = Bvh::build(scene, builder);
        let failures: Vec<String> = rays
            .par_iter()
            .zip(&want)
            .filter_map(|(ray, &w)| {
                let nearest = compare_nearest(scene, ray, bvh.intersect(ray), w);
                let occluded = compare_occluded(ray, bvh.occluded(ray), w);
                nearest.and(occluded).err()
            })
            .collect();
        assert!(
            failures.is_empty(),
            "{}: {} of {} rays disagree with brute force; first: {}",
            bvh.name(),
            failures.len(),
            rays.len(),
            failures[0]
        );
    }
}
