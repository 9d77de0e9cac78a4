//! Embree's packet queries (`rtcIntersect16`/`rtcOccluded16` through the shim, with
//! each lane's skip applied by the filter) against its single-ray queries.

use crate::common;

use common::{load, random_triangle_point};
use ember::accel::embree::EmbreeAccel;
use ember::accel::{Accel, EmbreeQuality, HitPacket, RayPacket};
use ember::geometry::Ray;
use ember::lanes::LANES;
use ember::sampling::{uniform_sphere, Rng};
use glam::Vec3;

/// Rays leaving triangles (skipping them), segments between surface points, and rays
/// from outside aimed at corners.
fn rays(scene: &ember::scene::Scene, n: usize) -> Vec<Ray> {
    let mut rng = Rng::from_seed(17);
    (0..n)
        .map(|k| {
            let (p, prim) = random_triangle_point(scene, &mut rng);
            match k % 3 {
                0 => Ray {
                    skip: prim,
                    ..Ray::new(p, uniform_sphere(rng.next_2d()))
                },
                1 => {
                    let (q, _) = random_triangle_point(scene, &mut rng);
                    Ray {
                        skip: prim,
                        ..Ray::segment(p, q - p, 1.0 - 1e-4)
                    }
                }
                _ => {
                    let o = scene.bounds.centre() + 5.0 * uniform_sphere(rng.next_2d());
                    Ray::new(o, p - o)
                }
            }
        })
        .collect()
}

#[test]
fn packets_find_what_single_rays_find() {
    for path in [
        "scenes/cs184/sky/CBbunny.dae",
        "scenes/cs184/sky/CBspheres_lambertian.dae",
    ] {
        let scene = load(path);
        let embree = EmbreeAccel::build(&scene, EmbreeQuality::Medium).expect("embree");
        let rays = rays(&scene, 4800);
        let mut differ = Vec::new();
        for (k, chunk) in rays.chunks(LANES).enumerate() {
            let mut packet = RayPacket::default();
            for (i, r) in chunk.iter().enumerate() {
                packet.set(i, r);
            }
            // Every other packet leaves lanes out; they must stay as they were.
            let active = if k % 2 == 0 {
                0xffff
            } else {
                0b1011_0110_1110_0101
            };
            let mut hits = HitPacket::default();
            embree.intersect_packet(&packet, active, &mut hits);
            let occluded = embree.occluded_packet(&packet, active);
            for (i, r) in chunk.iter().enumerate() {
                if active >> i & 1 == 0 {
                    assert_eq!(hits.prim[i], ember::geometry::NO_PRIM);
                    assert_eq!(occluded >> i & 1, 0);
                    continue;
                }
                let (got, want) = (hits.hit(i), embree.intersect(r));
                let same = match (got, want) {
                    (Some(g), Some(w)) => g.prim == w.prim && (g.t - w.t).abs() <= 1e-5 * w.t,
                    (g, w) => g.is_none() && w.is_none(),
                };
                if !same || (occluded >> i & 1 != 0) != embree.occluded(r) {
                    differ.push(format!("{r:?}: packet {got:?}, single {want:?}"));
                }
            }
        }
        assert!(
            differ.is_empty(),
            "{path}: {} of {} rays differ; first: {}",
            differ.len(),
            rays.len(),
            differ[0]
        );
    }
}

#[test]
fn a_lane_never_hits_the_triangle_it_leaves() {
    let scene = load("scenes/cs184/sky/CBspheres_lambertian.dae");
    let embree = EmbreeAccel::build(&scene, EmbreeQuality::Medium).expect("embree");
    // From the floor's first triangle, straight along its plane and back into it.
    let [a, b, c] = scene.triangle_positions(0);
    let p = (a + b + c) / 3.0;
    let n = (b - a).cross(c - a).normalize();
    let mut packet = RayPacket::default();
    for i in 0..LANES {
        let d = if i % 2 == 0 { -n } else { n + 0.1 * Vec3::X };
        packet.set(
            i,
            &Ray {
                skip: 0,
                ..Ray::new(p, d)
            },
        );
    }
    let mut hits = HitPacket::default();
    embree.intersect_packet(&packet, 0xffff, &mut hits);
    assert!(hits.prim.iter().all(|&p| p != 0), "{:?}", hits.prim);
}
