//! The Embree backend's own contract, in builds with Embree: hit records in the
//! native convention, no self-hit at t = 0, bad input as an error, packet queries
//! equal to single-ray ones, and the benchmark tables that only such a build fills.
//! (Integration tests rather than unit tests, so that the Embree stages of
//! scripts/test build the library once instead of twice.)

#![cfg(any(feature = "embree", feature = "embree4"))]

use ember::accel::embree::{info, EmbreeAccel, EmbreeDevice, EmbreeMode, PacketWidth};
use ember::accel::{Accel, AccelBuilder, Backend, EmbreeQuality};
use ember::bench::meshes::{displaced_sphere, geometry_scene};
use ember::geometry::Ray;
use ember::scene::{PrimHit, Scene};
use glam::Vec3;
use std::sync::Arc;

/// One triangle in z = 0 and one unit sphere at z = −5: ids 0 and 1.
fn scene() -> Scene {
    let corners = vec![Vec3::ZERO, Vec3::X, Vec3::Y];
    geometry_scene(corners, &[[0, 1, 2]], &[(Vec3::new(0.0, 0.0, -5.0), 1.0)])
}

#[test]
fn barycentrics_and_ids_follow_the_native_convention() {
    let accel = EmbreeAccel::build(&scene(), EmbreeQuality::Medium).expect("builds");
    let down = Ray::new(Vec3::new(0.25, 0.5, 2.0), Vec3::NEG_Z);
    let h = accel.intersect(&down).expect("hits the triangle");
    // p = (1−b1−b2)·p0 + b1·p1 + b2·p2 with p1 = X, p2 = Y.
    assert_eq!(h.prim, 0);
    assert!((h.t - 2.0).abs() < 1e-6 && (h.b1 - 0.25).abs() < 1e-6 && (h.b2 - 0.5).abs() < 1e-6);
    let to_sphere = Ray::new(Vec3::new(0.0, -3.0, -5.0), Vec3::Y);
    let h = accel.intersect(&to_sphere).expect("hits the sphere");
    assert_eq!(h.prim, 1);
    assert!((h.t - 2.0).abs() < 1e-5, "t = {}", h.t);
    assert!(accel.occluded(&to_sphere));
    assert!(!accel.occluded(&Ray::segment(to_sphere.o, to_sphere.d, 1.5)));
    assert!(accel.memory_bytes() > 0);
}

#[test]
fn an_origin_on_the_surface_does_not_hit_it_at_t_zero() {
    let accel = EmbreeAccel::build(&scene(), EmbreeQuality::Low).expect("builds");
    let leaving = Ray::new(Vec3::new(0.25, 0.25, 0.0), Vec3::new(0.3, 0.2, 1.0));
    assert_eq!(accel.intersect(&leaving), None);
    assert!(!accel.occluded(&leaving));
}

#[test]
fn bad_indices_are_an_error_not_a_crash() {
    let mut s = scene();
    s.triangles[0].v[2] = 99;
    let err = EmbreeAccel::build(&s, EmbreeQuality::High)
        .err()
        .expect("rejected");
    assert!(err.to_string().contains("out of range"), "{err}");
}

#[test]
fn packet_hits_equal_single_ray_hits() {
    use ember::sampling::{uniform_sphere, Rng};
    let bumpy = displaced_sphere(5_000);
    let tris: Vec<[u32; 3]> = bumpy.triangles.iter().map(|t| t.v).collect();
    let balls = [
        (Vec3::new(1.6, 0.0, 0.0), 0.4),
        (Vec3::new(0.0, -1.5, 0.5), 0.3),
    ];
    let mesh = geometry_scene(bumpy.positions.clone(), &tris, &balls);
    let (centre, radius) = (mesh.bounds.centre(), mesh.bounds.diagonal().length());
    let mut rng = Rng::from_seed(11);
    // From a sphere around the scene towards points near its centre (some miss),
    // 1001 rays so the last packet of every width is partly masked off.
    let rays: Vec<Ray> = (0..1001)
        .map(|_| {
            let o = centre + radius * uniform_sphere(rng.next_2d());
            let target = centre + 0.3 * radius * uniform_sphere(rng.next_2d());
            Ray::new(o, (target - o).normalize())
        })
        .collect();
    for robust in [true, false] {
        let mode = EmbreeMode {
            robust,
            ..EmbreeMode::robust(EmbreeQuality::Medium)
        };
        let device = Arc::new(EmbreeDevice::new(1).expect("device"));
        let accel = EmbreeAccel::build_mode(device, &mesh, mode).expect("builds");
        let single: Vec<_> = rays.iter().map(|r| accel.intersect(r)).collect();
        let hits = single.iter().filter(|h| h.is_some()).count();
        assert!(
            hits > 300 && hits < 1000,
            "{hits} hits: test rays hit and miss"
        );
        for width in PacketWidth::ALL {
            let mut packed = vec![None; rays.len()];
            accel.intersect_packets(width, &rays, &mut packed);
            // Triangle hits are bit-identical; Embree's packet sphere kernels round
            // differently from its single-ray one, by an ulp or two of t.
            let agree = |p: Option<PrimHit>, s: Option<PrimHit>| match (p, s) {
                (Some(p), Some(s)) if p.prim as usize >= tris.len() => {
                    p.prim == s.prim && (p.t - s.t).abs() <= 1e-6 * s.t
                }
                (p, s) => p == s,
            };
            let differ: Vec<_> = (0..rays.len())
                .filter(|&i| !agree(packed[i], single[i]))
                .map(|i| (i, packed[i], single[i]))
                .collect();
            assert!(differ.is_empty(), "{width:?}, robust {robust}: {differ:?}");
        }
        assert_eq!(accel.scene_flags(), if robust { "ROBUST" } else { "NONE" });
    }
}

#[test]
fn info_reports_a_version() {
    let i = info().expect("device");
    assert!(i.version.0 >= 3, "{i}");
    assert!(ember::accel::backends_info().contains("Embree"));
}

/// Every combination of scene flags, build quality and query width gets a row of
/// `ember bench accel`'s Embree modes table.
#[test]
fn every_mode_gets_a_row() {
    use ember::bench::embree_modes::embree_modes;
    let scene = displaced_sphere(2_000);
    let camera = ember::bench::measure::tiled_camera_rays(&scene, 32, 16);
    let pool = ember::accel::tracing_pool(Some(1)).expect("pool");
    let builder = AccelBuilder::new(1);
    let rows = embree_modes(&scene, "sphere", &camera, &pool, &builder, 1).expect("Embree");
    assert_eq!(rows.len(), 2 * 3 * 4);
    assert_eq!(
        rows.iter().filter(|r| r.scene_flags == "ROBUST").count(),
        12
    );
    assert!(rows
        .iter()
        .all(|r| r.camera_mrays > 0.0 && r.build_ms > 0.0));
}

/// `ember bench render --accel auto` compares the native BVH with Embree.
#[test]
fn render_bench_auto_compares_native_with_embree() {
    use ember::accel::{AccelKind, BvhBuilder};
    use ember::bench::render::RenderBenchOptions;
    assert!(Backend::Embree.available());
    assert_eq!(
        RenderBenchOptions::accels_for(Backend::Auto, false),
        [
            AccelKind::Native(BvhBuilder::Sah),
            AccelKind::embree(EmbreeQuality::Medium)
        ]
    );
}
