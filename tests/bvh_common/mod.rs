//! Helpers shared by the BVH tests: scene construction, random rays, and the
//! comparison of an acceleration structure's answer with the brute-force oracle.

#![allow(dead_code)]

use ember::accel::{Accel, BruteForce, Bvh, BvhBuilder};
use ember::geometry::sphere::{intersect_sphere, intersect_sphere_leaving};
use ember::geometry::triangle::intersect_triangle;
use ember::geometry::{Aabb, Ray};
use ember::sampling::{uniform_sphere, Rng};
use ember::scene::{PrimHit, Scene, Sphere, Triangle, NO_LIGHT};
use glam::{DVec3, Vec3};

/// When two structures may report different primitives, or one reports a hit
/// at the very end of the ray's interval that the other does not see.
///
/// The BVH's box test is conservative against the exact hit point, but a
/// reported `t` carries the triangle test's own rounding (pbrt's bound δt), which
/// scales with the coordinates involved (origin, corners), not with `t`: a hit
/// at `t ≈ 1e-4` on a unit-sized triangle is only good to about 1e-4
/// relative. Two primitives hit within that error of each other (shared edges
/// and vertices, touching or coincident surfaces) may come out in either order.
/// `REL_T` = 1e-5 (about 170 ulps) of `t` plus the same fraction of the scene's
/// magnitude lies far above that error and far below any real separation in
/// these scenes.
pub const REL_T: f32 = 1e-5;

#[derive(Clone, Copy, Debug)]
pub struct Tolerance {
    /// `REL_T` times the scene's magnitude (largest coordinate plus diagonal).
    abs: f32,
}

impl Tolerance {
    pub fn for_scene(scene: &Scene) -> Self {
        let b = scene_bounds(scene);
        let magnitude = if b.is_empty() {
            1.0
        } else {
            b.min.abs().max(b.max.abs()).max_element() + b.diagonal().length()
        };
        Tolerance {
            abs: REL_T * magnitude,
        }
    }

    /// Allowed difference between two `t` values near `t` on `ray`.
    pub fn slack(&self, ray: &Ray, t: f32) -> f32 {
        REL_T * t.abs() + self.abs / ray.d.length()
    }

    pub fn close(&self, ray: &Ray, a: f32, b: f32) -> bool {
        (a - b).abs() <= self.slack(ray, a.abs().max(b.abs()))
    }
}

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
    prim_hit(scene, ray, prim).map(|h| h.0)
}

/// `(t, b1, b2)` of the primitive tested on its own, honouring `ray.skip` as the
/// accelerators do: the triangle a ray left is never hit, the sphere it left only
/// at its far side.
pub fn prim_hit(scene: &Scene, ray: &Ray, prim: u32) -> Option<(f32, f32, f32)> {
    let i = prim as usize;
    let ntri = scene.triangles.len();
    let from_here = prim == ray.skip;
    if i < ntri {
        let [p0, p1, p2] = scene.triangle_positions(i);
        (!from_here).then(|| intersect_triangle(ray, p0, p1, p2))?
    } else {
        let s = &scene.spheres[i - ntri];
        let t = if from_here {
            intersect_sphere_leaving(ray, s.centre, s.radius)
        } else {
            intersect_sphere(ray, s.centre, s.radius)
        };
        Some((t?, 0.0, 0.0))
    }
}

/// Checks a structure's nearest hit against the oracle's.
pub fn compare_nearest(
    scene: &Scene,
    tol: &Tolerance,
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
            if !tol.close(ray, g.t, w.t) {
                return Err(format!("different nearest prim: {}", report()));
            }
            if prim_alone(scene, ray, g.prim) != Some(g.t) {
                return Err(format!("reported hit is not a hit: {}", report()));
            }
            Ok(())
        }
        (Some(h), None) | (None, Some(h)) => {
            // Only a hit within rounding of t_max may be seen by one and not the other.
            if ray.t_max.is_finite() && tol.close(ray, h.t, ray.t_max) {
                Ok(())
            } else {
                Err(format!("hit/miss disagree: {}", report()))
            }
        }
    }
}

/// Checks `occluded` against the oracle's nearest hit on the same ray.
pub fn compare_occluded(
    tol: &Tolerance,
    ray: &Ray,
    got: bool,
    want: Option<PrimHit>,
) -> Result<(), String> {
    if got == want.is_some() {
        return Ok(());
    }
    match want {
        Some(h) if ray.t_max.is_finite() && tol.close(ray, h.t, ray.t_max) => Ok(()),
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
pub fn random_ray(rng: &mut Rng, bounds: &Aabb, targets: &[Vec3]) -> Ray {
    let size = bounds.diagonal().max(Vec3::splat(1e-3));
    let lerp = |u: Vec3| bounds.min + u * size;
    let u3 = |rng: &mut Rng| Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
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
    let tol = Tolerance::for_scene(scene);
    let want: Vec<Option<PrimHit>> = rays.par_iter().map(|r| brute.intersect(r)).collect();
    for builder in builders() {
        let bvh = Bvh::build(scene, builder);
        let failures: Vec<String> = rays
            .par_iter()
            .zip(&want)
            .filter_map(|(ray, &w)| {
                let nearest = compare_nearest(scene, &tol, ray, bvh.intersect(ray), w);
                let occluded = compare_occluded(&tol, ray, bvh.occluded(ray), w);
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

/// Bounds of every primitive, lights included (the scene's own bounds leave
/// area lights out).
pub fn scene_bounds(scene: &Scene) -> Aabb {
    (0..scene.num_prims() as u32).fold(Aabb::EMPTY, |b, i| b.union(&scene.prim_bounds(i)))
}

/// Up to 4096 corners, edge midpoints and sphere points to aim rays at.
pub fn sample_targets(scene: &Scene, rng: &mut Rng) -> Vec<Vec3> {
    let ntri = scene.triangles.len();
    let mut t = Vec::new();
    for s in &scene.spheres {
        t.extend([
            s.centre,
            s.centre + s.radius * Vec3::X,
            s.centre - s.radius * Vec3::Z,
        ]);
    }
    for _ in 0..if ntri > 0 { 4096 } else { 0 } {
        let i = ((rng.next_f32() * ntri as f32) as usize).min(ntri - 1);
        let [a, b, c] = scene.triangle_positions(i);
        t.push(match (rng.next_f32() * 3.0) as u32 {
            0 => a,
            1 => 0.5 * (b + c),
            _ => (a + b + c) / 3.0,
        });
    }
    t
}

/// Fan-out of the segment oracle's filter levels.
const GROUP: usize = 16;

/// An exhaustive oracle for large scenes: like brute force it tests every
/// primitive that could be hit, but skips those whose (padded) bounds the ray
/// segment misses. Primitives are put in Morton order of their centroids and
/// grouped by `GROUP`, groups again by `GROUP`, and so on; a group is skipped
/// when the segment misses the union of its members' boxes. The filter is a
/// plain scalar slab test in `f64` on boxes padded by 1e-5 of their size and
/// position, far beyond any rounding, so it never skips a primitive that is hit.
/// It answers "the nearest hit with `t ≤ t_limit`"; callers pass the
/// structures' own `t` (slightly enlarged), so only primitives that could be
/// nearer are tested. It shares no code with the BVH but the primitive tests.
pub struct SegmentOracle<'a> {
    scene: &'a Scene,
    /// Primitive ids in Morton order of their centroids.
    order: Vec<u32>,
    /// `levels[0]` holds the primitives' boxes (in `order`), `levels[k + 1][i]`
    /// the union of `levels[k][GROUP·i ..][..GROUP]`.
    levels: Vec<Vec<PaddedBox>>,
    tol: Tolerance,
}

#[derive(Clone, Copy)]
struct PaddedBox {
    lo: DVec3,
    hi: DVec3,
}

impl PaddedBox {
    fn new(b: &Aabb) -> Self {
        let (lo, hi) = (b.min.as_dvec3(), b.max.as_dvec3());
        let pad = 1e-5 * (lo.abs().max(hi.abs()) + (hi - lo)) + DVec3::splat(1e-30);
        PaddedBox {
            lo: lo - pad,
            hi: hi + pad,
        }
    }

    fn union(&self, o: &PaddedBox) -> PaddedBox {
        PaddedBox {
            lo: self.lo.min(o.lo),
            hi: self.hi.max(o.hi),
        }
    }

    /// Whether the segment `o + t·d`, `t ∈ [t0, t1]`, meets the box.
    fn meets(&self, o: DVec3, d: DVec3, mut t0: f64, mut t1: f64) -> bool {
        for a in 0..3 {
            if d[a] == 0.0 {
                if o[a] < self.lo[a] || o[a] > self.hi[a] {
                    return false;
                }
                continue;
            }
            let (n, f) = ((self.lo[a] - o[a]) / d[a], (self.hi[a] - o[a]) / d[a]);
            t0 = t0.max(n.min(f));
            t1 = t1.min(n.max(f));
        }
        t0 <= t1
    }
}

fn morton_key(p: Vec3, b: &Aabb) -> u64 {
    let u = ((p - b.min) / b.diagonal().max(Vec3::splat(1e-30))).clamp(Vec3::ZERO, Vec3::ONE);
    let spread = |x: f32| {
        let mut v = (x * 1023.0) as u64;
        let mut out = 0;
        for bit in 0..10 {
            out |= (v & 1) << (3 * bit);
            v >>= 1;
        }
        out
    };
    spread(u.x) | spread(u.y) << 1 | spread(u.z) << 2
}

impl<'a> SegmentOracle<'a> {
    pub fn new(scene: &'a Scene) -> Self {
        let bounds = scene_bounds(scene);
        let mut order: Vec<u32> = (0..scene.num_prims() as u32).collect();
        order.sort_by_cached_key(|&i| morton_key(scene.prim_bounds(i).centre(), &bounds));
        let mut levels = vec![order
            .iter()
            .map(|&i| PaddedBox::new(&scene.prim_bounds(i)))
            .collect::<Vec<_>>()];
        while levels.last().is_some_and(|l| l.len() > GROUP) {
            let next = levels
                .last()
                .unwrap()
                .chunks(GROUP)
                .map(|c| c.iter().skip(1).fold(c[0], |b, p| b.union(p)))
                .collect();
            levels.push(next);
        }
        SegmentOracle {
            scene,
            order,
            levels,
            tol: Tolerance::for_scene(scene),
        }
    }

    /// Nearest hit on `ray` with `t ≤ t_limit` (`t_limit ≤ ray.t_max`).
    pub fn nearest(&self, ray: &Ray, t_limit: f32) -> Option<PrimHit> {
        let (o, d) = (ray.o.as_dvec3(), ray.d.as_dvec3());
        // The computed t of a hit may be off by the tie tolerance; widen by it.
        let t0 = f64::from(ray.t_min - self.tol.slack(ray, ray.t_min));
        let t1 = f64::from(t_limit + self.tol.slack(ray, t_limit));
        let mut best: Option<PrimHit> = None;
        let top = self.levels.len() - 1;
        let mut stack: Vec<(usize, usize)> =
            (0..self.levels[top].len()).map(|i| (top, i)).collect();
        while let Some((level, i)) = stack.pop() {
            if !self.levels[level][i].meets(o, d, t0, t1) {
                continue;
            }
            if level > 0 {
                let below = self.levels[level - 1].len();
                stack.extend((i * GROUP..((i + 1) * GROUP).min(below)).map(|j| (level - 1, j)));
                continue;
            }
            let limited = Ray {
                t_max: best.map_or(ray.t_max, |h| h.t),
                ..*ray
            };
            if let Some(h) = self.test(self.order[i] as usize, &limited) {
                best = Some(h);
            }
        }
        best.filter(|h| h.t <= t_limit)
    }

    fn test(&self, i: usize, ray: &Ray) -> Option<PrimHit> {
        let (t, b1, b2) = prim_hit(self.scene, ray, i as u32)?;
        Some(PrimHit {
            t,
            prim: i as u32,
            b1,
            b2,
        })
    }
}

/// Like `check_against_brute`, with the segment oracle: each builder's nearest
/// hit must be a real hit with nothing nearer (beyond the tie tolerance), and
/// `occluded` must agree. The oracle runs once per ray, up to the farther of
/// the builders' answers.
pub fn check_against_oracle(scene: &Scene, rays: &[Ray]) {
    use rayon::prelude::*;
    let oracle = SegmentOracle::new(scene);
    let tol = Tolerance::for_scene(scene);
    let bvhs = builders().map(|b| Bvh::build(scene, b));
    let failures: Vec<String> = rays
        .par_iter()
        .filter_map(|ray| {
            let got = bvhs.each_ref().map(|b| b.intersect(ray));
            let limit = got.iter().fold(0.0f32, |l, g| {
                l.max(g.map_or(ray.t_max, |h| {
                    (h.t + 2.0 * tol.slack(ray, h.t)).min(ray.t_max)
                }))
            });
            let want = oracle.nearest(ray, limit);
            bvhs.iter().zip(got).find_map(|(bvh, g)| {
                let nearest = compare_nearest(scene, &tol, ray, g, want);
                let occluded = compare_occluded(&tol, ray, bvh.occluded(ray), want);
                nearest
                    .and(occluded)
                    .err()
                    .map(|e| format!("{}: {e}", bvh.name()))
            })
        })
        .collect();
    assert!(
        failures.is_empty(),
        "{} of {} rays disagree with the oracle; first: {}",
        failures.len(),
        rays.len(),
        failures[0]
    );
}
