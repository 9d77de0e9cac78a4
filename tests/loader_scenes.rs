//! Every shipped scene loads, with counts checked against an independent scan
//! of the file and cameras checked against the reference manifest.

use ember::camera::Camera;
use ember::info::scene_info;
use ember::lights::{AreaLight, Light};
use ember::materials::{Bsdf, Material};
use ember::scene::collada::load;
use ember::scene::{Scene, NO_LIGHT};
use ember::Vec3;
use std::path::{Path, PathBuf};

const SCENES: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes");

fn scene_path(rel: &str) -> PathBuf {
    Path::new(SCENES).join(rel)
}

fn load_rel(rel: &str) -> Scene {
    load(&scene_path(rel)).unwrap_or_else(|e| panic!("{e}"))
}

/// All `.dae` files below `dir`, sorted, so that files added later are covered too.
fn dae_files(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut todo = vec![dir.to_path_buf()];
    while let Some(d) = todo.pop() {
        for entry in std::fs::read_dir(&d).unwrap_or_else(|e| panic!("{}: {e}", d.display())) {
            let p = entry.unwrap().path();
            if p.is_dir() {
                todo.push(p);
            } else if p.extension().is_some_and(|x| x == "dae") {
                out.push(p);
            }
        }
    }
    out.sort();
    out
}

/// Counts read straight from the XML, independently of the loader: the
/// `count`s of the instanced geometries' polygon elements (every shipped
/// polygon is a triangle), instanced spheres, and instanced lights whose
/// CGL/CMU462 extension says `<area>`.
#[derive(Debug, PartialEq)]
struct Expected {
    mesh_triangles: usize,
    spheres: usize,
    area_lights: usize,
}

fn scan(path: &Path) -> Expected {
    let text = std::fs::read_to_string(path).unwrap();
    let doc = roxmltree::Document::parse(&text).unwrap();
    let by_id = |url: &str| {
        let id = url.trim_start_matches('#');
        doc.descendants().find(|n| n.attribute("id") == Some(id))
    };
    let instances = |tag: &str| {
        doc.descendants()
            .filter(|n| n.tag_name().name() == tag)
            .filter_map(|n| by_id(n.attribute("url").unwrap()))
            .collect::<Vec<_>>()
    };
    let mut e = Expected {
        mesh_triangles: 0,
        spheres: 0,
        area_lights: 0,
    };
    for g in instances("instance_geometry") {
        let prims: Vec<_> = g
            .descendants()
            .filter(|n| matches!(n.tag_name().name(), "polylist" | "triangles"))
            .collect();
        for p in &prims {
            if let Some(vc) = p.children().find(|c| c.tag_name().name() == "vcount") {
                assert!(vc.text().unwrap().split_whitespace().all(|k| k == "3"));
            }
            e.mesh_triangles += p.attribute("count").unwrap().parse::<usize>().unwrap();
        }
        if prims.is_empty() && g.descendants().any(|n| n.tag_name().name() == "sphere") {
            e.spheres += 1;
        }
    }
    for l in instances("instance_light") {
        let area = l
            .descendants()
            .filter(|n| n.tag_name().name() == "technique")
            .filter(|t| matches!(t.attribute("profile"), Some("CGL" | "CMU462")))
            .any(|t| t.first_element_child().map(|c| c.tag_name().name()) == Some("area"));
        e.area_lights += area as usize;
    }
    e
}

/// Structural invariants every loaded scene must satisfy.
fn check_invariants(name: &str, s: &Scene) {
    let np = s.positions.len() as u32;
    let nn = s.normals.len() as u32;
    for (i, t) in s.triangles.iter().enumerate() {
        assert!(
            t.v.iter().all(|&v| v < np),
            "{name}: triangle {i} position index"
        );
        if let Some(n) = t.n {
            assert!(
                n.iter().all(|&k| k < nn),
                "{name}: triangle {i} normal index"
            );
        }
        assert!(
            (t.material as usize) < s.materials.len(),
            "{name}: triangle {i} material"
        );
        assert!(t.light == NO_LIGHT || (t.light as usize) < s.lights.len());
    }
    assert!(
        s.positions.iter().all(|p| p.is_finite()),
        "{name}: positions"
    );
    assert!(s.normals.iter().all(|n| n.is_finite()), "{name}: normals");
    for sp in &s.spheres {
        assert!(
            sp.radius > 0.0 && sp.centre.is_finite(),
            "{name}: sphere {sp:?}"
        );
        assert!((sp.material as usize) < s.materials.len());
    }
    let c = &s.camera;
    assert!(
        (c.forward.length() - 1.0).abs() < 1e-5,
        "{name}: forward not unit"
    );
    assert!((c.up.length() - 1.0).abs() < 1e-5, "{name}: up not unit");
    assert!(
        c.forward.dot(c.up).abs() < 1e-5,
        "{name}: up not orthogonal"
    );
    check_area_light_quads(name, s);
}

/// Each area light owns exactly two triangles whose winding normal is the
/// emitting normal, which emit the light's radiance from the front, and which
/// cover the light's rectangle.
fn check_area_light_quads(name: &str, s: &Scene) {
    for (li, light) in s.lights.iter().enumerate() {
        let tris: Vec<usize> = (0..s.triangles.len())
            .filter(|&i| s.triangles[i].light == li as u32)
            .collect();
        let Light::Area(AreaLight {
            normal, radiance, ..
        }) = *light
        else {
            assert!(
                tris.is_empty(),
                "{name}: non-area light {li} owns triangles"
            );
            continue;
        };
        let area = light.as_area().expect("area light").area();
        assert_eq!(tris.len(), 2, "{name}: area light {li}");
        let mut total = 0.0;
        for &i in &tris {
            let [p0, p1, p2] = s.triangle_positions(i);
            let cross = (p1 - p0).cross(p2 - p0);
            total += 0.5 * cross.length();
            assert!(
                (cross.normalize() - normal).length() < 1e-5,
                "{name}: quad normal"
            );
            assert_eq!(s.triangles[i].n, None);
            assert_eq!(
                s.materials[s.triangles[i].material as usize],
                Material::light_surface(),
                "{name}: the light, not the material, emits"
            );
            let si = s.interaction(
                &ember::geometry::Ray::new(p0 + normal, -normal),
                &ember::scene::PrimHit {
                    t: 1.0,
                    prim: i as u32,
                    b1: 0.25,
                    b2: 0.25,
                },
            );
            assert_eq!(s.emission(&si, normal), radiance, "{name}: front");
            assert_eq!(s.emission(&si, -normal), ember::Color::ZERO, "{name}: back");
        }
        assert!(
            (total - area).abs() < 1e-5 * area.max(1.0),
            "{name}: quad area"
        );
    }
}

fn check_directory(dir: &str) {
    let files = dae_files(&Path::new(SCENES).join(dir));
    assert!(
        files.len() > 10,
        "{dir}: only {} scene files found",
        files.len()
    );
    for f in files {
        let name = f.display().to_string();
        let s = load(&f).unwrap_or_else(|e| panic!("{e}"));
        check_invariants(&name, &s);
        let expected = scan(&f);
        let area_lights = s
            .lights
            .iter()
            .filter(|l| matches!(l, Light::Area(AreaLight { .. })))
            .count();
        let got = Expected {
            mesh_triangles: s.triangles.len() - 2 * area_lights,
            spheres: s.spheres.len(),
            area_lights,
        };
        assert_eq!(got, expected, "{name}");
    }
}

#[test]
fn every_cs184_scene_loads_with_the_scanned_counts() {
    check_directory("cs184");
}

#[test]
fn every_cmu462_scene_loads_with_the_scanned_counts() {
    check_directory("cmu462");
}

#[test]
fn cbspheres_has_two_spheres_one_area_light_and_a_ten_triangle_box() {
    let s = load_rel("cs184/sky/CBspheres.dae");
    assert_eq!(s.spheres.len(), 2);
    assert_eq!(s.triangles.len(), 10 + 2);
    assert_eq!(s.lights.len(), 1);
    let Light::Area(AreaLight {
        centre,
        normal,
        radiance,
        ..
    }) = s.lights[0]
    else {
        panic!("expected an area light, got {:?}", s.lights[0]);
    };
    let area = s.lights[0].as_area().expect("area light").area();
    // Spec §5: 0.6 × 0.8 at height 1.49, facing down, c = 10.
    assert!((centre - Vec3::new(0.0, 1.49, 0.0)).length() < 1e-5);
    assert!((normal - Vec3::NEG_Y).length() < 1e-6);
    assert!((area - 0.48).abs() < 1e-6);
    assert_eq!(radiance, Vec3::splat(10.0));
    // Sphere 1 (glass) sits at file (-0.4, 0.3, 0.3) → world (0.4, 0.3, 0.3).
    assert!((s.spheres[0].centre - Vec3::new(0.4, 0.3, 0.3)).length() < 1e-6);
    assert!((s.spheres[0].radius - 0.3).abs() < 1e-6);
    assert!(
        matches!(s.materials[s.spheres[0].material as usize].bsdf, Bsdf::Glass(g) if g.ior == 1.45)
    );
    assert!(matches!(
        s.materials[s.spheres[1].material as usize].bsdf,
        Bsdf::Mirror(_)
    ));
    // The room's ceiling bounds the scene.
    assert!((s.bounds.max.y - 1.5).abs() < 1e-6);
}

#[test]
fn cbbunny_triangle_count() {
    let s = load_rel("cs184/sky/CBbunny.dae");
    // 28586 mesh triangles (bunny and 10-triangle box) + the light's two.
    assert_eq!(s.triangles.len(), 28588);
    assert_eq!(s.lights.len(), 1);
}

#[test]
fn cbempty_is_lit_by_a_point_light() {
    let s = load_rel("cs184/sky/CBempty.dae");
    assert_eq!(s.lights.len(), 1);
    let Light::Point {
        position,
        intensity,
    } = s.lights[0]
    else {
        panic!("expected a point light, got {:?}", s.lights[0]);
    };
    assert_eq!(intensity, Vec3::splat(5.0));
    assert!((position.y - 1.49).abs() < 1e-5, "{position}");
}

#[test]
fn hemisphere_and_directional_lights_of_banana() {
    let s = load_rel("cs184/keenan/banana.dae");
    assert!(matches!(s.lights[0], Light::Ambient { radiance } if radiance == Vec3::ONE));
    let Light::Directional { direction, .. } = s.lights[1] else {
        panic!("{:?}", s.lights[1]);
    };
    assert!((direction.length() - 1.0).abs() < 1e-6);
    assert!(direction.y < 0.0, "the sun shines downward: {direction}");
}

/// Camera of the reference manifest (tests/data/references/manifest.json) at 160×120.
fn assert_camera(rel: &str, eye: [f32; 3], forward: [f32; 3], hfov: f64, vfov: f64) {
    let s = load_rel(rel);
    let cam = Camera::new(&s.camera, &s.bounds, 160, 120);
    assert!(
        (cam.eye - Vec3::from(eye)).length() < 1e-5,
        "{rel}: eye {}",
        cam.eye
    );
    assert!(
        (cam.forward - Vec3::from(forward)).length() < 1e-6,
        "{rel}: forward {}",
        cam.forward
    );
    assert!((cam.up - Vec3::Y).length() < 1e-6, "{rel}: up {}", cam.up);
    let (h, v) = cam.fov_degrees();
    assert!((h as f64 - hfov).abs() < 1e-4, "{rel}: hfov {h}");
    assert!((v as f64 - vfov).abs() < 1e-4, "{rel}: vfov {v}");
}

#[test]
fn cbspheres_lambertian_camera_matches_the_manifest() {
    assert_camera(
        "cs184/sky/CBspheres_lambertian.dae",
        [0.0, 0.75, 4.802344],
        [0.0, 0.0, -1.0],
        49.134351,
        37.849295,
    );
}

#[test]
fn cbbunny_camera_matches_the_manifest() {
    assert_camera(
        "cs184/sky/CBbunny.dae",
        [0.0, 0.75, -4.802344],
        [0.0, 0.0, 1.0],
        49.13434,
        37.849287,
    );
}

#[test]
fn cbgems_short_camera_matrix_is_padded_with_a_warning() {
    let s = load_rel("cs184/sky/CBgems.dae");
    assert!((s.camera.forward - Vec3::NEG_Z).length() < 1e-6);
    assert!(
        s.warnings.iter().any(|w| w.contains("15 numbers")),
        "{:?}",
        s.warnings
    );
}

#[test]
fn cmu462_cbgems_dangling_light_is_a_warning() {
    let s = load_rel("cmu462/sky/CBgems.dae");
    assert!(
        s.warnings.iter().any(|w| w.contains("#Hemi-light")),
        "{:?}",
        s.warnings
    );
}

#[test]
fn triangles_are_wound_toward_their_normals() {
    let s = load_rel("cs184/sky/CBbunny.dae");
    for (i, t) in s.triangles.iter().enumerate() {
        let Some(n) = t.n else { continue };
        let [p0, p1, p2] = s.triangle_positions(i);
        let sum: Vec3 = n.iter().map(|&k| s.normals[k as usize]).sum();
        assert!((p1 - p0).cross(p2 - p0).dot(sum) >= 0.0, "triangle {i}");
    }
}

#[test]
fn own_cornell_scene() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell.dae");
    let s = load(&path).unwrap_or_else(|e| panic!("{e}"));
    check_invariants("cornell.dae", &s);
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    assert_eq!(s.spheres.len(), 2);
    assert_eq!(s.triangles.len(), 10 + 2);
    // <translate> then <scale>: centre file (−0.45, 0.35, 0.4) → world (0.45, 0.4, 0.35).
    assert!((s.spheres[0].centre - Vec3::new(0.45, 0.4, 0.35)).length() < 1e-6);
    assert!((s.spheres[0].radius - 0.4).abs() < 1e-6);
    assert!((s.spheres[1].radius - 0.35).abs() < 1e-6);
    // Floor, ceiling and back wall are white; left red; right green.
    let albedo = |i: usize| match s.materials[s.triangles[i].material as usize].bsdf {
        Bsdf::Lambertian(b) => b.albedo.vec3(),
        m => panic!("triangle {i}: {m:?}"),
    };
    assert_eq!(albedo(0), Vec3::splat(0.7));
    assert_eq!(albedo(6), Vec3::new(0.63, 0.065, 0.05));
    assert_eq!(albedo(8), Vec3::new(0.14, 0.45, 0.091));
    let info = scene_info(&s, 640, 480);
    assert!(info.contains("spheres: 2"), "{info}");
    assert!(info.contains("lights: 1\n  [0] area:"), "{info}");
    assert!(info.contains("(10 mesh, 2 area-light)"), "{info}");
}

#[test]
fn scene_info_reports_camera_bounds_and_warnings() {
    let s = load_rel("cs184/sky/CBgems.dae");
    let info = scene_info(&s, 160, 120);
    for needle in [
        "camera (160x120)",
        "eye (0, 0.75, 4.802344)",
        "forward (0, 0, -1)",
        "hfov 49.1343",
        "vfov 37.849",
        "bounds: min (-1, 0, -1) max (1, 1.5, 1)",
        "glass: ior 1.45",
        "warnings: 1",
        "15 numbers",
    ] {
        assert!(info.contains(needle), "missing {needle:?} in\n{info}");
    }
}
