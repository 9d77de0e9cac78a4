//! The default Embree path keeps every robustness contract of the native BVH: stability
//! case 6 (rays through vertices, along shared edges and at grazing angles down to
//! 1e-5 rad find the grid; degenerate triangles give no NaN), and the skip contract
//! (`Ray::skip`): a ray spawned from a surface never finds the triangle it leaves, and
//! finds the sphere it leaves only at its far side, near the origin and far from it,
//! at grazing angles too. The variants that give something up say how much.

use crate::common;

use common::load;
use ember::accel::bvh::Bvh;
use ember::accel::embree::EmbreeAccel;
use ember::accel::{
    Accel, AccelBuilder, AccelKind, BvhBuilder, EmbreeMode, EmbreeQuality, EmbreeSelfHits,
    EmbreeSpheres,
};
use ember::bench::meshes;
use ember::bench::stability::robust;
use ember::bench::stability::scenes::transformed;
use ember::bench::stability::Budget;
use ember::geometry::{Ray, NO_PRIM};
use ember::sampling::{uniform_sphere, Rng};
use ember::scene::Scene;
use glam::Vec3;
use rayon::prelude::*;

const DEFAULT: EmbreeMode = EmbreeMode::robust(EmbreeQuality::Medium);

#[test]
fn case6_holds_for_the_default_embree_path() {
    let b = Budget {
        width: 160,
        height: 120,
        spp: 4,
        seed: 20240611,
    };
    let c = robust::grid_with(&b, AccelKind::Embree(DEFAULT)).unwrap();
    eprintln!(
        "case 6 through Embree: {} of {} rays missed at 3e-4..0.1 rad, {} of {} at 1e-5..1e-4 rad; \
         {} of {} grazing pixels with a hole",
        c.holes, c.rays, c.extreme_holes, c.extreme_rays, c.hole_pixels, c.covered_pixels
    );
    assert!(c.rays > 10_000 && c.extreme_rays > 2000 && c.covered_pixels > 500);
    assert_eq!(c.holes, 0, "rays through vertices/edges slipped through");
    assert_eq!(c.extreme_holes, 0, "rays at 1e-5..1e-4 rad missed the grid");
    assert_eq!(c.hole_pixels, 0, "grazing pixels show a hole");
    assert!(
        c.max_abs_y < 1e-5 && c.max_rel_t < 1e-5,
        "hits off the plane"
    );
    assert_eq!(c.degenerate_nonfinite, 0);
    assert!(c.degenerate_all_finite && c.degenerate_mean > 0.0);
}

/// Case 6's ray queries through each robust variant: none may miss. (The variant
/// without the ROBUST flag is measured, not required: BENCHMARKS.md shows its misses.)
#[test]
fn every_robust_variant_finds_every_grazing_hit() {
    for (self_hits, spheres) in [
        (EmbreeSelfHits::Filter, EmbreeSpheres::Embree),
        (EmbreeSelfHits::Offset, EmbreeSpheres::Embree),
        (EmbreeSelfHits::Offset, EmbreeSpheres::Ember),
    ] {
        let mode = EmbreeMode {
            self_hits,
            spheres,
            ..DEFAULT
        };
        let c = robust::grid_queries_with(AccelKind::Embree(mode), 1).unwrap();
        assert_eq!((c.holes, c.extreme_holes), (0, 0), "{mode}");
    }
    let fast = robust::grid_queries_with(
        AccelKind::Embree(EmbreeMode::fast(EmbreeQuality::Medium)),
        1,
    )
    .unwrap();
    eprintln!(
        "without the ROBUST flag: {} of {} and {} of {} grazing rays missed",
        fast.holes, fast.rays, fast.extreme_holes, fast.extreme_rays
    );
}

/// What a spawned ray found, against the native BVH (which keeps the contract).
#[derive(Default, Debug, Clone, Copy)]
struct Tally {
    rays: u64,
    grazing: u64,
    /// Bounce rays whose nearest hit is the primitive left where the native BVH's is
    /// not (a triangle left, or a sphere's near side), and shadow rays occluded by the
    /// primitive left where the native BVH finds them clear.
    own: u64,
    /// Shadow rays occluded where the native BVH finds them clear (own or not).
    extra_occluded: u64,
}

impl Tally {
    fn add(self, o: Tally) -> Tally {
        Tally {
            rays: self.rays + o.rays,
            grazing: self.grazing + o.grazing,
            own: self.own + o.own,
            extra_occluded: self.extra_occluded + o.extra_occluded,
        }
    }
}

/// Ray `i`: from where a random ray inside the scene's bounds first hits, a bounce ray
/// (a third of them within 1e-5 to 1e-2 rad of the surface's plane, on either side)
/// and a shadow segment to a random point stopping a relative 1e-4 short of it (a
/// point in the bounds may lie on a wall), spawned as the integrators spawn them.
fn spawned(scene: &Scene, native: &Bvh, i: usize) -> Option<(Ray, Ray, bool)> {
    let mut rng = Rng::new(77, i as u64, 0);
    let inside = |rng: &mut Rng| {
        let u = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
        scene.bounds.min + u * scene.bounds.diagonal()
    };
    let first = Ray::new(inside(&mut rng), uniform_sphere(rng.next_2d()));
    let hit = native.intersect(&first)?;
    let si = scene.interaction(&first, &hit);
    let n = si.ng;
    let grazing = rng.next_f32() < 1.0 / 3.0;
    let w = if grazing {
        let t = uniform_sphere(rng.next_2d());
        let t = (t - t.dot(n) * n).normalize_or_zero();
        let elevation = 10f32.powf(-5.0 + 3.0 * rng.next_f32());
        let side = if rng.next_f32() < 0.5 { 1.0 } else { -1.0 };
        (t + side * elevation * n).normalize()
    } else {
        uniform_sphere(rng.next_2d())
    };
    Some((
        si.spawn_ray(w),
        si.spawn_segment(inside(&mut rng), 1.0 - 1e-4),
        grazing,
    ))
}

fn tally(scene: &Scene, embree: &EmbreeAccel, rays: usize) -> Tally {
    let native = Bvh::build(scene, BvhBuilder::Sah);
    (0..rays)
        .into_par_iter()
        .filter_map(|i| spawned(scene, &native, i))
        .map(|(bounce, shadow, grazing)| {
            let prim = |h: Option<ember::scene::PrimHit>| h.map_or(NO_PRIM, |h| h.prim);
            let (e, n) = (
                prim(embree.intersect(&bounce)),
                prim(native.intersect(&bounce)),
            );
            let own = e == bounce.skip && n != bounce.skip;
            // Occluded where the native BVH is not: by the primitive left (a broken
            // contract), or by another one (an edge or silhouette the two decide
            // differently; the native BVH rounds a sphere's bounds to nearest, so far
            // from the origin it can miss a ray that clips the sphere's extreme).
            let extra = embree.occluded(&shadow) && !native.occluded(&shadow);
            let by_own = extra && prim(embree.intersect(&shadow)) == shadow.skip;
            Tally {
                rays: 1,
                grazing: grazing as u64,
                own: own as u64 + by_own as u64,
                extra_occluded: extra as u64,
            }
        })
        .reduce(Tally::default, Tally::add)
}

/// Scenes with spheres and triangles near the origin, at 1e-3 and far from it, a
/// sliver-rich soup and a bumpy mesh away from the origin.
fn scenes() -> Vec<(String, Scene)> {
    let spheres = load("scenes/cs184/sky/CBspheres_lambertian.dae");
    let bunny = load("scenes/cs184/sky/CBbunny.dae");
    let mut v = vec![
        ("CBspheres_lambertian".to_string(), spheres.clone()),
        ("CBbunny".to_string(), bunny),
        ("random soup".to_string(), meshes::random_soup(3000, 5)),
    ];
    for (label, scale, offset) in [
        ("scale 1e-3", 1e-3, 0.0),
        ("translate 1e4", 1.0, 1e4),
        ("translate 1e5", 1.0, 1e5),
    ] {
        v.push((
            format!("CBspheres_lambertian {label}"),
            transformed(&spheres, scale, Vec3::splat(offset)),
        ));
    }
    v.push((
        "displaced sphere at 1e4".into(),
        transformed(
            &meshes::displaced_sphere(20_000),
            1.0,
            Vec3::new(1e4, -3e3, 2e3),
        ),
    ));
    v
}

fn build(scene: &Scene, mode: EmbreeMode) -> EmbreeAccel {
    AccelBuilder::new(1)
        .build_embree(scene, mode)
        .expect("Embree builds")
}

#[test]
fn spawned_rays_never_find_what_they_leave_on_the_default_path() {
    for (name, scene) in scenes() {
        let t = tally(&scene, &build(&scene, DEFAULT), 60_000);
        eprintln!("{name}: {t:?}");
        assert!(t.rays > 20_000 && t.grazing > 5_000, "{name}: {t:?}");
        assert_eq!(t.own, 0, "{name}: spawned rays hit what they left: {t:?}");
        assert!(t.extra_occluded * 10_000 <= t.rays, "{name}: {t:?}");
    }
}

/// The evidence for the default's shortcut: with no filter at all, the offset
/// origins alone keep spawned rays off their triangles, and ember's sphere test keeps
/// them off their sphere's near side. (Embree's own sphere primitive, unfiltered, does
/// not: the count is printed, and BENCHMARKS.md shows it.)
#[test]
fn offset_origins_alone_keep_rays_off_their_triangles() {
    for (name, scene) in scenes() {
        let offset = EmbreeMode {
            self_hits: EmbreeSelfHits::Offset,
            ..DEFAULT
        };
        let t = tally(&scene, &build(&scene, offset), 60_000);
        eprintln!("{name}, no filter: {t:?}");
        assert_eq!(t.own, 0, "{name}: {t:?}");
        if !scene.spheres.is_empty() {
            let embree_spheres = EmbreeMode {
                spheres: EmbreeSpheres::Embree,
                ..offset
            };
            let t = tally(&scene, &build(&scene, embree_spheres), 60_000);
            eprintln!("{name}, no filter, Embree's spheres: {t:?}");
        }
    }
}

/// A lane's answer does not depend on the lanes beside it: the same rays in other
/// packets (shuffled, other lanes active) get bit-identical hits on the default path.
#[test]
fn packet_composition_does_not_change_a_lanes_answer() {
    use ember::accel::{HitPacket, RayPacket};
    use ember::lanes::LANES;
    let scene = load("scenes/cs184/sky/CBspheres_lambertian.dae");
    let native = Bvh::build(&scene, BvhBuilder::Sah);
    let embree = build(&scene, DEFAULT);
    let cam = ember::camera::Camera::new(&scene.camera, &scene.bounds, 64, 48);
    let mut rays: Vec<Ray> = (0..6000)
        .filter_map(|i| spawned(&scene, &native, i).map(|(b, s, _)| if i % 2 == 0 { b } else { s }))
        .collect();
    rays.extend((0..64 * 48).map(|k| cam.generate_ray(k % 64, k / 64, glam::Vec2::splat(0.5))));
    let trace = |order: &[usize], stride: usize| {
        let mut out = vec![(u32::MAX, 0u32, false); rays.len()];
        for chunk in order.chunks(stride) {
            let mut packet = RayPacket::default();
            let mut active = 0;
            for (lane, &r) in chunk.iter().enumerate() {
                let ray = Ray {
                    t_max: rays[r].t_max,
                    ..rays[r]
                };
                packet.set(lane, &ray);
                active |= 1 << lane;
            }
            let mut hits = HitPacket::default();
            embree.intersect_packet(&packet, active, &mut hits);
            let occluded = embree.occluded_packet(&packet, active);
            for (lane, &r) in chunk.iter().enumerate() {
                out[r] = (
                    hits.prim[lane],
                    hits.t[lane].to_bits(),
                    occluded >> lane & 1 != 0,
                );
            }
        }
        out
    };
    let order: Vec<usize> = (0..rays.len()).collect();
    let mut shuffled = order.clone();
    let mut rng = Rng::from_seed(3);
    for i in (1..shuffled.len()).rev() {
        let j = ((rng.next_f32() * (i + 1) as f32) as usize).min(i);
        shuffled.swap(i, j);
    }
    let a = trace(&order, LANES);
    assert_eq!(a, trace(&shuffled, LANES));
    assert_eq!(a, trace(&shuffled, 5));
}
