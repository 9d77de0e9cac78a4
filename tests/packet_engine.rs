//! The packet engine against the scalar one: packet traversal finds, lane for
//! lane, what single rays find; packet renders are the scalar renders bit for bit.
//! Every instruction set this CPU has is checked (they must agree with each other
//! too, which the scalar reference makes transitive).

use crate::bvh_common;
use crate::common;

use bvh_common::{builders, random_ray, scene_from};
use common::{load, random_triangle_point};
use ember::accel::{Accel, AccelKind, Bvh, BvhBuilder, HitPacket, RayPacket};
use ember::geometry::Ray;
use ember::integrators::{DirectStrategy, Estimator, Roulette};
use ember::lanes::{instruction_set, limit_instruction_set, InstructionSet, LANES};
use ember::render::{Engine, RenderJob, RenderSettings};
use ember::sampling::{uniform_sphere, Rng};
use ember::scene::Scene;
use glam::Vec3;
use std::sync::Mutex;

/// The instruction-set cap is process-wide: tests that set it take turns.
static CAP: Mutex<()> = Mutex::new(());

/// Runs `f` once per instruction set this CPU has, capped to each in turn.
fn for_each_instruction_set(mut f: impl FnMut(InstructionSet)) {
    let _turn = CAP.lock().unwrap_or_else(|e| e.into_inner());
    let mut seen = Vec::new();
    for isa in [
        InstructionSet::Avx512,
        InstructionSet::Avx2,
        InstructionSet::Portable,
    ] {
        limit_instruction_set(isa);
        let active = instruction_set();
        if !seen.contains(&active) {
            seen.push(active);
            f(active);
        }
    }
    limit_instruction_set(InstructionSet::Avx512);
}

/// Rays that leave a surface point of each kind of primitive (skipping it), shadow
/// segments between two surface points, and the random rays of the BVH tests.
fn rays_for(scene: &Scene, seed: u64, n: usize) -> Vec<Ray> {
    let mut rng = Rng::from_seed(seed);
    let targets: Vec<Vec3> = (0..scene.triangles.len())
        .flat_map(|i| scene.triangle_positions(i))
        .collect();
    let surface_point =
        |rng: &mut Rng| (!scene.triangles.is_empty()).then(|| random_triangle_point(scene, rng));
    (0..n)
        .map(|k| match (k % 3, surface_point(&mut rng)) {
            (0, Some((p, prim))) => Ray {
                skip: prim,
                ..Ray::new(p, uniform_sphere(rng.next_2d()))
            },
            (1, Some((p, prim))) => {
                let (q, _) = surface_point(&mut rng).expect("triangles");
                Ray {
                    skip: prim,
                    ..Ray::segment(p, q - p, 1.0 - 1e-4)
                }
            }
            _ => {
                let mut r = random_ray(&mut rng, &scene.bounds, &targets);
                // Packets start at t = 0.
                r.t_min = 0.0;
                r
            }
        })
        .collect()
}

/// Every lane of every packet against the single-ray answer, for both builders.
fn check_packets(scene: &Scene, rays: &[Ray], seed: u64) {
    let mut rng = Rng::from_seed(seed);
    for builder in builders() {
        let bvh = Bvh::build(scene, builder);
        for chunk in rays.chunks(LANES) {
            let mut packet = RayPacket::default();
            for (i, r) in chunk.iter().enumerate() {
                packet.set(i, r);
            }
            // A random subset of the lanes is active; the others must be left alone.
            let active = (rng.next_f32() * 65536.0) as u32 & ((1 << chunk.len()) - 1) | 1;
            let mut hits = HitPacket::default();
            hits.t[LANES - 1] = 42.0;
            bvh.intersect_packet(&packet, active, &mut hits);
            let occluded = bvh.occluded_packet(&packet, active);
            for (i, r) in chunk.iter().enumerate() {
                let on = active >> i & 1 != 0;
                if !on {
                    assert_eq!(occluded >> i & 1, 0, "inactive lane {i} reported occluded");
                    continue;
                }
                assert_eq!(hits.hit(i), bvh.intersect(r), "{builder:?} lane {i}: {r:?}");
                assert_eq!(
                    occluded >> i & 1 != 0,
                    bvh.occluded(r),
                    "{builder:?} lane {i} occlusion: {r:?}"
                );
            }
            if active >> (LANES - 1) & 1 == 0 {
                assert_eq!(hits.t[LANES - 1], 42.0, "an inactive lane was written");
            }
        }
    }
}

#[test]
fn packet_traversal_finds_what_single_rays_find_in_the_course_scenes() {
    let scenes = [
        "scenes/cs184/sky/CBspheres_lambertian.dae",
        "scenes/cs184/sky/CBbunny.dae",
        "scenes/cs184/sky/CBgems.dae",
    ];
    for (k, path) in scenes.iter().enumerate() {
        let scene = load(path);
        let rays = rays_for(&scene, k as u64, 3000);
        for_each_instruction_set(|isa| {
            let _ = isa;
            check_packets(&scene, &rays, 7);
        });
    }
}

/// Triangles sharing edges and vertices (a grid), slivers, spheres and exact
/// duplicates, hit by rays aimed at their corners: ties and edge-on hits.
#[test]
fn packet_traversal_matches_single_rays_on_edges_ties_and_spheres() {
    let mut rng = Rng::from_seed(11);
    let mut positions = Vec::new();
    let mut tris = Vec::new();
    let n = 12;
    for i in 0..=n {
        for j in 0..=n {
            positions.push(Vec3::new(i as f32, 0.3 * rng.next_f32(), j as f32));
        }
    }
    let at = |i: usize, j: usize| (i * (n + 1) + j) as u32;
    for i in 0..n {
        for j in 0..n {
            tris.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
            tris.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
        }
    }
    // Exact duplicates: equal t, so the lower id must win in both traversals.
    tris.extend_from_within(..20);
    let spheres = vec![
        (Vec3::new(3.0, 1.0, 3.0), 0.8),
        (Vec3::new(7.5, 0.5, 4.0), 1.5),
        (Vec3::new(7.5, 0.5, 4.0), 1.5),
    ];
    let scene = scene_from(positions, tris, spheres);
    let mut rays = rays_for(&scene, 3, 4000);
    // Straight down onto grid vertices and edge midpoints.
    for i in 0..n {
        for j in 0..n {
            let p = Vec3::new(i as f32, 5.0, j as f32);
            rays.push(Ray::new(p, -Vec3::Y));
            rays.push(Ray::new(p + Vec3::new(0.5, 0.0, 0.0), -Vec3::Y));
            rays.push(Ray::new(
                p + Vec3::new(0.5, 0.0, 0.5),
                Vec3::new(0.0, -1.0, 0.0),
            ));
        }
    }
    for_each_instruction_set(|_| check_packets(&scene, &rays, 13));
}

fn render(job: &RenderJob, s: &RenderSettings) -> Vec<[u32; 3]> {
    let out = job.render(s);
    out.image
        .pixels
        .iter()
        .map(|p| [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()])
        .collect()
}

#[test]
fn packet_renders_are_the_scalar_renders_bit_for_bit() {
    let base = RenderSettings {
        spp: 8,
        max_depth: 5,
        seed: 99,
        ..RenderSettings::default()
    };
    let light_tracing = RenderSettings {
        estimator: Some(Estimator::LightTracing),
        ..base.clone()
    };
    let cases: [(&str, RenderSettings); 10] = [
        ("scenes/cs184/sky/CBspheres_lambertian.dae", base.clone()),
        (
            "scenes/cs184/sky/CBspheres_lambertian.dae",
            RenderSettings {
                strategy: Some(DirectStrategy::Mis),
                light_samples: 3,
                ..base.clone()
            },
        ),
        (
            "scenes/cs184/sky/CBbunny.dae",
            RenderSettings {
                accumulate: false,
                max_depth: 3,
                spp_offset: 5,
                ..base.clone()
            },
        ),
        (
            "scenes/cs184/sky/CBbunny.dae",
            RenderSettings {
                roulette: Roulette::Fixed {
                    start: 1,
                    prob: 0.6,
                },
                strategy: Some(DirectStrategy::Mis),
                ..base.clone()
            },
        ),
        (
            "scenes/cs184/sky/CBbunny.dae",
            RenderSettings {
                roulette: Roulette::Off,
                max_depth: 0,
                ..base.clone()
            },
        ),
        (
            "scenes/cs184/sky/CBgems.dae",
            RenderSettings {
                strategy: None,
                ..base.clone()
            },
        ),
        // Path tracing with light-traced caustics: both parts, mirror and glass.
        (
            "scenes/cs184/sky/CBspheres.dae",
            RenderSettings {
                estimator: Some(Estimator::Caustics),
                ..base.clone()
            },
        ),
        // Light paths from a point light and from an area light (their rays start on
        // its surface), counting every bounce or only the last.
        ("scenes/cs184/sky/CBempty.dae", light_tracing.clone()),
        (
            "scenes/cs184/sky/CBspheres_lambertian.dae",
            light_tracing.clone(),
        ),
        (
            "scenes/cs184/sky/CBbunny.dae",
            RenderSettings {
                accumulate: false,
                max_depth: 3,
                ..light_tracing
            },
        ),
    ];
    for (path, settings) in cases {
        assert_packet_matches_scalar(path, load(path), &settings);
    }
}

/// Far from the origin points near edges are rounded into their triangle and rays
/// leave spheres from within an ulp (`into_triangle`, `sphere_spawn_origin`): the
/// lanes must take the same branches (at 1e5 an ulp is 8 mm, a room is 2 m).
#[cfg(feature = "bench")]
#[test]
fn packet_renders_are_the_scalar_renders_far_from_the_origin() {
    use ember::bench::stability::scenes::transformed;
    let path = "scenes/cs184/sky/CBspheres_lambertian.dae";
    for (offset, strategy) in [(1e4, DirectStrategy::Light), (1e5, DirectStrategy::Mis)] {
        let scene = transformed(&load(path), 1.0, Vec3::splat(offset));
        let settings = RenderSettings {
            spp: 8,
            max_depth: 5,
            seed: 7,
            strategy: Some(strategy),
            ..RenderSettings::default()
        };
        assert_packet_matches_scalar(&format!("{path} + {offset}"), scene, &settings);
    }
}

/// Renders `scene` at 64×48 with both engines (the packet one on every instruction
/// set) and asserts identical pixels; every radiance render runs in packets.
fn assert_packet_matches_scalar(path: &str, scene: Scene, settings: &RenderSettings) {
    let job = RenderJob::new(scene, AccelKind::Native(BvhBuilder::Sah), 64, 48).unwrap();
    assert!(
        settings.uses_packets(),
        "{path}: {:?}",
        settings.packet_blocker()
    );
    let scalar = render(
        &job,
        &RenderSettings {
            engine: Engine::Scalar,
            ..settings.clone()
        },
    );
    for_each_instruction_set(|isa| {
        let packet = render(
            &job,
            &RenderSettings {
                engine: Engine::Packet,
                ..settings.clone()
            },
        );
        let differ = scalar.iter().zip(&packet).filter(|(a, b)| a != b).count();
        assert_eq!(
            differ, 0,
            "{path} {isa}: {differ} pixels differ; {settings:?}"
        );
    });
}

#[test]
fn packet_renders_do_not_depend_on_threads_or_bands() {
    let scene = load("scenes/cs184/sky/CBbunny.dae");
    let job = RenderJob::new(scene, AccelKind::Native(BvhBuilder::Sah), 48, 40).unwrap();
    let s = RenderSettings {
        spp: 6,
        max_depth: 4,
        seed: 5,
        engine: Engine::Packet,
        ..RenderSettings::default()
    };
    let full = render(&job, &s);
    let one_thread = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap()
        .install(|| render(&job, &s));
    assert!(full == one_thread, "threads change the image");
    // A band starting off the tile grid regroups every packet.
    let rect = ember::render::PixelRect {
        x0: 3,
        y0: 7,
        x1: 45,
        y1: 29,
    };
    let band = job.render_rect(&s, rect, &|_| {});
    for y in rect.y0..rect.y1 {
        for x in rect.x0..rect.x1 {
            let p = band.image.pixels[((y - rect.y0) * rect.width() + (x - rect.x0)) as usize];
            let want = full[(y * 48 + x) as usize];
            assert_eq!(
                [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()],
                want,
                "({x}, {y})"
            );
        }
    }
}
