//! The native BVH against the brute-force oracle on random triangle soups, plus
//! watertightness and self-intersection checks of the primitive tests.

use crate::bvh_common;

use bvh_common::*;
use ember::accel::{Accel, BruteForce, Bvh, BvhBuilder};
use ember::geometry::Ray;
use ember::sampling::{uniform_sphere, Rng};
use ember::scene::Scene;
use glam::Vec3;
use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed};
use std::collections::HashMap;

/// What a random soup is made of (counts shrink when a case fails).
#[derive(Clone, Debug)]
struct SoupSpec {
    seed: u64,
    random: usize,
    slivers: usize,
    degenerate: usize,
    duplicates: usize,
    grid: usize,
    spheres: usize,
}

fn soup_spec() -> impl Strategy<Value = SoupSpec> {
    (
        any::<u64>(),
        0usize..150,
        0usize..40,
        0usize..8,
        0usize..6,
        0usize..7,
        0usize..5,
    )
        .prop_map(
            |(seed, random, slivers, degenerate, duplicates, grid, spheres)| SoupSpec {
                seed,
                random,
                slivers,
                degenerate,
                duplicates,
                grid,
                spheres,
            },
        )
}

struct SoupBuilder {
    rng: Rng,
    positions: Vec<Vec3>,
    tris: Vec<[u32; 3]>,
    spheres: Vec<(Vec3, f32)>,
}

impl SoupBuilder {
    fn u3(&mut self) -> Vec3 {
        Vec3::new(
            self.rng.next_f32(),
            self.rng.next_f32(),
            self.rng.next_f32(),
        )
    }

    fn point(&mut self) -> Vec3 {
        10.0 * self.u3()
    }

    fn push(&mut self, p: [Vec3; 3]) {
        let base = self.positions.len() as u32;
        self.positions.extend(p);
        self.tris.push([base, base + 1, base + 2]);
    }

    fn random_triangle(&mut self) {
        let c = self.point();
        let size = 0.05 * 60f32.powf(self.rng.next_f32());
        let p = [0; 3].map(|_| c + size * uniform_sphere(self.rng.next_2d()));
        self.push(p);
    }

    /// Nearly collinear, or long and needle thin.
    fn sliver(&mut self) {
        let (a, b) = (self.point(), self.point());
        let off = 10f32.powf(-7.0 + 4.0 * self.rng.next_f32()) * (b - a).length();
        let c = a.lerp(b, self.rng.next_f32()) + off * uniform_sphere(self.rng.next_2d());
        self.push([a, b, c]);
    }

    fn degenerate(&mut self) {
        let (a, b) = (self.point(), self.point());
        let p = if self.rng.next_f32() < 0.5 {
            [a, b, b]
        } else {
            [a, a, a]
        };
        self.push(p);
    }

    fn duplicate(&mut self) {
        if let Some(&t) = self.tris.first() {
            self.tris.push(t);
        }
    }

    /// An n×n height field with shared (indexed) vertices.
    fn grid(&mut self, n: usize) {
        let origin = self.point();
        let (u, v) = (
            uniform_sphere(self.rng.next_2d()),
            uniform_sphere(self.rng.next_2d()),
        );
        let w = u.cross(v).normalize_or_zero();
        let base = self.positions.len() as u32;
        for i in 0..=n {
            for j in 0..=n {
                let h = 0.3 * (self.rng.next_f32() - 0.5);
                self.positions
                    .push(origin + i as f32 * u + j as f32 * v + h * w);
            }
        }
        let at = |i: usize, j: usize| base + (i * (n + 1) + j) as u32;
        for i in 0..n {
            for j in 0..n {
                self.tris.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
                self.tris.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
            }
        }
    }

    fn sphere(&mut self) {
        let c = self.point();
        let r = 0.1 + 2.0 * self.rng.next_f32();
        self.spheres.push((c, r));
    }
}

fn make_soup(spec: &SoupSpec) -> Scene {
    let mut b = SoupBuilder {
        rng: Rng::from_seed(spec.seed),
        positions: Vec::new(),
        tris: Vec::new(),
        spheres: Vec::new(),
    };
    (0..spec.random).for_each(|_| b.random_triangle());
    (0..spec.slivers).for_each(|_| b.sliver());
    (0..spec.degenerate).for_each(|_| b.degenerate());
    (0..spec.duplicates).for_each(|_| b.duplicate());
    if spec.grid > 0 {
        b.grid(spec.grid);
    }
    (0..spec.spheres).for_each(|_| b.sphere());
    scene_from(b.positions, b.tris, b.spheres)
}

/// Points worth aiming at: corners, edge midpoints, sphere centres and rims.
fn targets(scene: &Scene) -> Vec<Vec3> {
    let mut t = Vec::new();
    for i in 0..scene.triangles.len() {
        let [a, b, c] = scene.triangle_positions(i);
        t.extend([a, b, c, 0.5 * (a + b), 0.5 * (b + c), 0.5 * (c + a)]);
    }
    for s in &scene.spheres {
        t.extend([
            s.centre,
            s.centre + s.radius * Vec3::X,
            s.centre - s.radius * Vec3::Y,
        ]);
    }
    t
}

fn config() -> Config {
    Config {
        cases: 64,
        rng_seed: RngSeed::Fixed(0x00E3_BE12),
        failure_persistence: None,
        ..Config::default()
    }
}

proptest! {
    #![proptest_config(config())]

    #[test]
    fn bvh_agrees_with_brute_force_on_soups(spec in soup_spec()) {
        let scene = make_soup(&spec);
        let mut rng = Rng::from_seed(spec.seed ^ 0x5EED);
        let aims = targets(&scene);
        let rays: Vec<Ray> = (0..400).map(|_| random_ray(&mut rng, &scene.bounds, &aims)).collect();
        check_against_brute(&scene, &rays);
    }
}

#[test]
fn empty_and_fully_degenerate_scenes_never_hit() {
    let empty = Scene::default();
    let degenerate = scene_from(
        vec![Vec3::ONE; 3],
        vec![[0, 1, 2], [0, 0, 0]],
        vec![(Vec3::ZERO, 0.0)],
    );
    let ray = Ray::new(Vec3::ZERO, Vec3::X);
    for scene in [&empty, &degenerate] {
        for builder in builders() {
            let bvh = Bvh::build(scene, builder);
            assert!(bvh.intersect(&ray).is_none() && !bvh.occluded(&ray));
            assert_eq!(bvh.stats().prims, 0);
        }
        assert!(BruteForce::new(scene).intersect(&ray).is_none());
    }
}

/// Many copies of one triangle: all centroids equal, the builders must still
/// split (no giant leaf) and terminate.
#[test]
fn identical_centroids_build_bounded_leaves() {
    let n = 1000;
    let positions = vec![Vec3::ZERO, Vec3::X, Vec3::Y];
    let scene = scene_from(positions, vec![[0, 1, 2]; n], vec![]);
    for builder in builders() {
        let bvh = Bvh::build(&scene, builder);
        let s = bvh.stats();
        assert_eq!(s.prims, n);
        assert!(s.leaves >= n / 8, "{s:?}");
        let hit = bvh
            .intersect(&Ray::new(Vec3::new(0.2, 0.2, 1.0), -Vec3::Z))
            .expect("hit");
        assert_eq!(hit.t, 1.0);
    }
}

/// One triangle spanning ±3e38 (a scene built through the library, which the loader
/// would refuse) overflows the surface areas above it to infinity: the builders still
/// make leaves of at most a block, never a panic, and the small triangles beside it
/// are hit as the brute-force search hits them.
#[test]
fn overflowing_bounds_build_bounded_leaves() {
    let big = 3e38;
    let mut positions = vec![
        Vec3::new(-big, -big, 50.0),
        Vec3::new(big, -big, 50.0),
        Vec3::new(0.0, big, 50.0),
    ];
    let mut tris = vec![[0, 1, 2]];
    for k in 0..64u32 {
        let z = k as f32;
        positions.extend([
            Vec3::new(-1.0, -1.0, z),
            Vec3::new(1.0, -1.0, z),
            Vec3::new(0.0, 1.0, z),
        ]);
        tris.push([3 * k + 3, 3 * k + 4, 3 * k + 5]);
    }
    let scene = scene_from(positions, tris, vec![]);
    let ray = Ray::new(Vec3::new(0.0, 0.0, 10.5), Vec3::Z);
    let brute = BruteForce::new(&scene).intersect(&ray).map(|h| h.t);
    assert_eq!(brute, Some(0.5));
    for builder in builders() {
        let bvh = Bvh::build(&scene, builder);
        assert_eq!(bvh.stats().prims, 65);
        assert_eq!(bvh.intersect(&ray).map(|h| h.t), brute);
        assert!(bvh.occluded(&ray));
    }
}

#[test]
fn trees_are_the_same_whatever_the_thread_count() {
    let spec = SoupSpec {
        seed: 7,
        random: 12000,
        slivers: 200,
        degenerate: 10,
        duplicates: 5,
        grid: 20,
        spheres: 30,
    };
    let scene = make_soup(&spec);
    for builder in builders() {
        let build_with = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| Bvh::build(&scene, builder))
        };
        let (one, four) = (build_with(1), build_with(4));
        assert!(one == four, "{builder:?} differs between 1 and 4 threads");
        let s = one.stats();
        assert_eq!(
            s.prims,
            spec.random + spec.slivers + spec.duplicates + 2 * 20 * 20 + 30
        );
        assert!(
            s.max_depth <= 64 && s.leaves <= s.nodes * s.width && s.prims <= 4 * s.leaves,
            "{s:?}"
        );
    }
}

#[test]
fn sah_tree_is_cheaper_than_midpoint_tree() {
    let spec = SoupSpec {
        seed: 11,
        random: 3000,
        slivers: 100,
        degenerate: 0,
        duplicates: 0,
        grid: 10,
        spheres: 10,
    };
    let scene = make_soup(&spec);
    let sah = Bvh::build(&scene, BvhBuilder::Sah).stats().sah_cost;
    let mid = Bvh::build(&scene, BvhBuilder::Midpoint).stats().sah_cost;
    assert!(sah > 0.0 && sah < mid, "SAH {sah} vs midpoint {mid}");
}

/// A closed mesh (a cube's faces subdivided, vertices shared, projected onto a
/// bumpy sphere), seen from inside: every ray must hit, including rays aimed
/// exactly at vertices and at edge midpoints.
fn closed_mesh(n: usize, rng: &mut Rng) -> Scene {
    let mut index: HashMap<[i32; 3], u32> = HashMap::new();
    let mut positions = Vec::new();
    let mut vertex = |l: [i32; 3], rng: &mut Rng| -> u32 {
        *index.entry(l).or_insert_with(|| {
            let p = Vec3::new(l[0] as f32, l[1] as f32, l[2] as f32) / n as f32 - Vec3::splat(0.5);
            positions.push(p.normalize() * (1.0 + 0.2 * rng.next_f32()));
            positions.len() as u32 - 1
        })
    };
    let mut tris = Vec::new();
    let n_i = n as i32;
    for axis in 0..3 {
        for side in [0, n_i] {
            for i in 0..n_i {
                for j in 0..n_i {
                    let lattice = |a: i32, b: i32| {
                        let mut l = [0; 3];
                        l[axis] = side;
                        l[(axis + 1) % 3] = a;
                        l[(axis + 2) % 3] = b;
                        l
                    };
                    let q = [(i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)]
                        .map(|(a, b)| vertex(lattice(a, b), rng));
                    tris.push([q[0], q[1], q[2]]);
                    tris.push([q[0], q[2], q[3]]);
                }
            }
        }
    }
    scene_from(positions, tris, vec![])
}

#[test]
fn closed_mesh_is_watertight_from_inside() {
    let mut rng = Rng::from_seed(3);
    let scene = closed_mesh(24, &mut rng);
    let mut aims = targets(&scene);
    aims.extend((0..2000).map(|_| 3.0 * uniform_sphere(rng.next_2d())));
    let origins = [
        Vec3::ZERO,
        Vec3::new(0.1, -0.2, 0.05),
        Vec3::new(-0.3, 0.3, 0.3),
    ];
    let brute = BruteForce::new(&scene);
    let bvhs = builders().map(|b| Bvh::build(&scene, b));
    let mut rays = 0;
    for o in origins {
        for &a in &aims {
            let ray = Ray::new(o, a - o);
            assert!(brute.occluded(&ray), "brute force: leak through {ray:?}");
            for bvh in &bvhs {
                assert!(
                    bvh.intersect(&ray).is_some(),
                    "{}: leak through {ray:?}",
                    bvh.name()
                );
            }
            rays += 1;
        }
    }
    assert!(rays > 20000);
}

/// A flat grid on integer coordinates: axis-aligned rays through vertices and
/// edge midpoints are exact in floating point and pass exactly through them.
#[test]
fn flat_grid_has_no_cracks_at_edges_and_vertices() {
    let n = 16;
    let at = |i: usize, j: usize| (i * (n + 1) + j) as u32;
    let positions: Vec<Vec3> = (0..=n)
        .flat_map(|i| (0..=n).map(move |j| Vec3::new(i as f32, j as f32, 0.0)))
        .collect();
    let mut tris = Vec::new();
    for i in 0..n {
        for j in 0..n {
            tris.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
            tris.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
        }
    }
    let scene = scene_from(positions, tris, vec![]);
    let bvhs = builders().map(|b| Bvh::build(&scene, b));
    let brute = BruteForce::new(&scene);
    let mut checked = 0;
    for i in 1..2 * n {
        for j in 1..2 * n {
            let p = Vec3::new(i as f32 * 0.5, j as f32 * 0.5, 0.0);
            for d in [
                -Vec3::Z,
                Vec3::Z,
                Vec3::new(0.5, 0.25, -1.0),
                Vec3::new(-1.0, 1.0, 1.0),
            ] {
                let ray = Ray::new(p - 3.0 * d, d);
                assert!(brute.intersect(&ray).is_some(), "brute: crack at {p}");
                for bvh in &bvhs {
                    let h = bvh
                        .intersect(&ray)
                        .unwrap_or_else(|| panic!("{}: crack at {p}", bvh.name()));
                    assert!((h.t - 3.0).abs() < 1e-5);
                }
                checked += 1;
            }
        }
    }
    assert_eq!(checked, 4 * (2 * n - 1) * (2 * n - 1));
}

/// Rays spawned from hit points (`SurfaceInteraction::spawn_ray`: offset origin,
/// the primitive as `skip`) never find their own triangle again; from a sphere
/// they leave it (outward) or cross it to the far side (inward), never re-hitting
/// at t ≈ 0. Checked at several scales and far
/// from the origin, where the rounding errors grow with the coordinates.
#[test]
fn spawned_rays_do_not_self_intersect() {
    let spec = SoupSpec {
        seed: 5,
        random: 150,
        slivers: 20,
        degenerate: 0,
        duplicates: 0,
        grid: 6,
        spheres: 6,
    };
    let base = make_soup(&spec);
    for (scale, shift) in [(1e-3, 0.0), (1.0, 0.0), (1e3, 0.0), (1.0, 1e4)] {
        let mut scene = base.clone();
        scene
            .positions
            .iter_mut()
            .for_each(|p| *p = *p * scale + Vec3::splat(shift));
        for s in &mut scene.spheres {
            s.centre = s.centre * scale + Vec3::splat(shift);
            s.radius *= scale;
        }
        scene.bounds = scene_from(scene.positions.clone(), vec![], vec![]).bounds;
        let bvh = Bvh::build(&scene, BvhBuilder::Sah);
        let mut rng = Rng::from_seed(17);
        let (mut spawned, mut failures, mut all) = (0, Vec::new(), Vec::new());
        let aims = targets(&scene);
        let bounds = bvh_bounds(&scene);
        for _ in 0..3000 {
            let ray = random_ray(&mut rng, &bounds, &aims);
            let Some(hit) = bvh.intersect(&ray) else {
                continue;
            };
            let si = scene.interaction(&ray, &hit);
            for _ in 0..4 {
                let next = si.spawn_ray(uniform_sphere(rng.next_2d()));
                all.push(next);
                spawned += 1;
                if let Err(e) = check_spawned(&scene, &bvh, &next, &si, hit.prim) {
                    failures.push(e);
                }
            }
        }
        assert!(spawned > 2000, "scale {scale}: only {spawned} spawned rays");
        // Both builders' SIMD leaves skip what the scalar brute force skips.
        check_against_brute(&scene, &all);
        assert!(
            failures.is_empty(),
            "scale {scale} shift {shift}: {} failures, first {}",
            failures.len(),
            failures[0]
        );
    }
}

fn bvh_bounds(scene: &Scene) -> ember::geometry::Aabb {
    (0..scene.num_prims() as u32).fold(ember::geometry::Aabb::EMPTY, |b, i| {
        b.union(&scene.prim_bounds(i))
    })
}

fn check_spawned(
    scene: &Scene,
    bvh: &Bvh,
    ray: &Ray,
    si: &ember::scene::SurfaceInteraction,
    from: u32,
) -> Result<(), String> {
    let next = bvh.intersect(ray);
    let ntri = scene.triangles.len() as u32;
    if from < ntri {
        return match next {
            Some(h) if h.prim == from => {
                Err(format!("triangle {from} re-hit at t={} by {ray:?}", h.t))
            }
            _ => Ok(()),
        };
    }
    let sphere = scene.spheres[(from - ntri) as usize];
    let cos = ray.d.dot(si.ng);
    match next {
        Some(h) if h.prim == from && cos > 0.0 => {
            Err(format!("sphere re-hit outward at t={} by {ray:?}", h.t))
        }
        Some(h) if h.prim == from => {
            // Inward: the far side lies a chord 2r|cos θ| away.
            let chord = 2.0 * sphere.radius * cos.abs();
            if h.t * ray.d.length() < 0.5 * chord {
                Err(format!(
                    "sphere re-hit inward at t={} (chord {chord}) by {ray:?}",
                    h.t
                ))
            } else {
                Ok(())
            }
        }
        None if cos < 0.0 => Err(format!("ray escaped from inside a sphere: {ray:?}")),
        _ => Ok(()),
    }
}
