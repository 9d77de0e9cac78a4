//! The Embree backend's own contract, in builds with Embree: hit records in the
//! native convention, no self-hit at t = 0, bad input as an error, packet queries
//! equal to single-ray ones, the command line's `--accel` flags, and the benchmark
//! and report tables that only such a build fills. (Integration tests rather than
//! unit tests, and in one file rather than in the CLI's, benches' and report's, so
//! that the Embree stages of scripts/test build the library once and run only what
//! depends on the backend.)

use crate::common;

use common::{command, repo, run};
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

/// `--accel embree` renders; `ember info` counts the primitives the native BVH
/// holds when auto picks it; flags that only mean something to the native BVH are
/// refused with Embree.
#[test]
fn the_command_line_renders_with_embree_and_refuses_native_only_flags() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("e.png");
    run(command()
        .args(["--accel", "embree", "-r", "8", "6", "-f"])
        .arg(&out)
        .arg(repo("scenes/cs184/sky/CBempty.dae")))
    .success();
    assert_eq!(image::open(&out).unwrap().width(), 8);

    let spheres = repo("scenes/cs184/sky/CBspheres_lambertian.dae");
    let text = run(command().arg("info").arg(&spheres)).success().stdout();
    let line = text.lines().find(|l| l.starts_with("--accel auto"));
    let line = line.unwrap_or_else(|| panic!("no auto line in {text}"));
    assert!(
        line.contains("picks native SAH") && line.contains("14 primitives"),
        "{line}"
    );

    for args in [
        &["--shading", "bvh-cost", "--accel", "embree"][..],
        &["--bvh", "midpoint", "--accel", "embree"],
    ] {
        let o = run(command().args(args).arg(&spheres)).fails_with("ember: error: --");
        assert_eq!(o.code(), Some(1), "{args:?}: {}", o.stderr());
    }
}

/// `ember bench accel` measures robust and fast Embree beside the two native builders
/// (the modes table, left out here, has every other Embree setting).
#[test]
fn bench_accel_has_embree_rows() {
    let dir = tempfile::tempdir().unwrap();
    let bench = [
        "bench",
        "accel",
        "mesh:2000",
        "--no-embree-modes",
        "-t",
        "1",
    ];
    let few = ["--rays", "2000", "--repeats", "1", "--out"];
    run(command().args(bench).args(few).arg(dir.path())).success();
    let csv = std::fs::read_to_string(dir.path().join("accel.csv")).unwrap();
    let rows: Vec<&str> = csv.lines().skip(1).collect();
    assert_eq!(rows.len(), 4, "{csv}");
    let backend = |row: &&str| row.split(',').nth(3).unwrap_or("").to_string();
    let embree = rows.iter().filter(|r| backend(r).starts_with("Embree"));
    assert_eq!(embree.count(), 2, "{csv}");
}

/// `ember bench accel --scaling` gives Embree a row at each of its three qualities.
#[test]
fn scaling_has_a_row_per_embree_quality() {
    use ember::bench::scaling::{run_scaling, ScalingOptions};
    let opts = ScalingOptions {
        sizes: vec![1_000],
        rays: 2_000,
        threads: 1,
        repeats: 1,
        ..ScalingOptions::default()
    };
    let report = run_scaling(&opts, |_| ()).unwrap();
    let embree: Vec<_> = report.rows.iter().filter(|r| r.is_embree).collect();
    assert_eq!(report.rows.len(), 2 * 5);
    assert_eq!(embree.len(), 2 * 3);
    for r in embree {
        let m = &r.measured;
        let figures = [
            m.build_ms,
            m.camera_mrays,
            m.incoherent_mrays,
            m.shadow_mrays,
        ];
        for v in figures {
            assert!(v.is_finite() && v > 0.0, "{r:?}");
        }
    }
}

/// The write-up's timing table has an Embree column, and the command it prints for
/// that column renders.
#[test]
fn report_times_embree_with_a_command_that_renders() {
    use ember::report::plan::{timed_backends, timing_recipe, Budget};
    assert_eq!(
        timed_backends(),
        [Backend::Native, Backend::Embree, Backend::None]
    );
    let dir = tempfile::tempdir().unwrap();
    let scene = repo("scenes/cs184/sky/CBempty.dae");
    let recipe = timing_recipe(&scene, &Budget::quick(), Backend::Embree, 0);
    let out = dir.path().join("t.png");
    let o = run(command()
        .args(recipe.flags())
        .arg("-f")
        .arg(&out)
        .arg(&scene))
    .success();
    assert!(o.stdout().contains("Embree") || o.stderr().contains("Embree"));
    assert!(image::open(&out).unwrap().width() > 0);
}
