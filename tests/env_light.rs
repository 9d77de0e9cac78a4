//! The environment light (`-e FILE.exr`): constant maps against the hemisphere light's
//! closed form, importance sampling against its pdf (chi-square), bad maps, the CLI
//! flag, and MIS with importance sampling against uniform sampling on a sunny map.

use crate::common;

use common::{chi2_p_value, command, integrate_bins, mean_and_stderr, run, sidak_significance};
use ember::accel::{AccelKind, BvhBuilder};
use ember::camera::Camera;
use ember::film::Image;
use ember::geometry::Aabb;
use ember::integrators::{DirectStrategy, Roulette};
use ember::lights::environment::{EnvMapError, EnvSampling};
use ember::lights::{EnvironmentMap, Light};
use ember::materials::Material;
use ember::render::{RenderJob, RenderSettings};
use ember::sampling::Rng;
use ember::scene::{CameraDesc, Scene, Triangle, NO_LIGHT};
use ember::{Color, Vec3};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// The committed test map (`ember::bench::stability::environment::sun_sky_map`).
fn sun_map_path() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/env_sun.exr")
}

fn sun_map() -> EnvironmentMap {
    EnvironmentMap::load(&sun_map_path()).unwrap()
}

/// `scenes/env_sun.exr` is exactly the generator's map (set EMBER_WRITE_ENV_MAP=1 to rewrite it).
#[cfg(feature = "bench")]
#[test]
fn committed_sun_map_is_the_generated_one() {
    let want = ember::bench::stability::environment::sun_sky_map();
    if std::env::var_os("EMBER_WRITE_ENV_MAP").is_some() {
        ember::image_io::write_image(&want, &sun_map_path()).unwrap();
    }
    let got = ember::image_io::read_image(&sun_map_path()).unwrap();
    assert_eq!((got.width, got.height), (want.width, want.height));
    assert_eq!(got.pixels, want.pixels);
}

/// A deterministic map of `w × h` texels from `f(x, y)`.
fn map_of(w: u32, h: u32, f: impl Fn(u32, u32) -> Color) -> EnvironmentMap {
    let mut img = Image::new(w, h);
    for (i, p) in img.pixels.iter_mut().enumerate() {
        *p = f(i as u32 % w, i as u32 / w);
    }
    EnvironmentMap::from_image(img, "test map").unwrap()
}

/// Upper half `c`, lower half black: the hemisphere light of radiance `c` as a map.
fn hemisphere_map(c: Color) -> EnvironmentMap {
    map_of(16, 8, |_, y| if y < 4 { c } else { Color::ZERO })
}

/// A huge Lambertian floor (front +Y, albedo `a`) and `light`; a camera 1 above it looks
/// straight down, so every pixel sees an unoccluded upward surface.
fn floor_job(a: f32, light: Light) -> RenderJob {
    let l = 1000.0;
    let mut scene = Scene {
        positions: vec![
            Vec3::new(-l, 0.0, -l),
            Vec3::new(-l, 0.0, l),
            Vec3::new(l, 0.0, l),
            Vec3::new(l, 0.0, -l),
        ],
        triangles: [[0, 1, 2], [0, 2, 3]]
            .map(|v| Triangle {
                v,
                n: None,
                material: 0,
                light: NO_LIGHT,
            })
            .to_vec(),
        materials: vec![Material::lambertian(Color::splat(a))],
        bounds: Aabb::new(Vec3::new(-l, 0.0, -l), Vec3::new(l, 0.0, l)),
        ..Default::default()
    };
    scene.lights.push(light);
    let desc = CameraDesc {
        forward: Vec3::NEG_Y,
        up: Vec3::Z,
        tan_half_x: Some(0.8),
        tan_half_y: None,
        ..CameraDesc::default()
    };
    let mut cam = Camera::new(&desc, &scene.bounds, 16, 16);
    cam.eye = Vec3::new(0.3, 1.0, -0.2);
    RenderJob::with_camera(scene, AccelKind::Native(BvhBuilder::Sah), cam).unwrap()
}

/// Green-channel pixel mean and its standard error.
fn render_floor(job: &RenderJob, strategy: DirectStrategy, max_depth: u32, spp: u32) -> (f64, f64) {
    let s = RenderSettings {
        spp,
        max_depth,
        strategy: Some(strategy),
        roulette: Roulette::Off,
        seed: 11,
        ..Default::default()
    };
    let out = job.render(&s);
    let v = common::finite_luminance(&out);
    mean_and_stderr(&v)
}

/// An upward surface under a hemisphere of radiance `c` reflects `a·c` (irradiance π·c):
/// the hemisphere light gives it exactly, the same light as a map gives it within the
/// map estimator's standard error, and so does a map that is `c` all round (the floor
/// hides the lower half).
#[test]
fn constant_maps_agree_with_the_hemisphere_light_furnace() {
    let (a, c) = (0.6f32, 1.5f32);
    let want = (a * c) as f64;
    let hemi = floor_job(
        a,
        Light::Ambient {
            radiance: Color::splat(c),
        },
    );
    let half = floor_job(
        a,
        Light::Environment(Arc::new(hemisphere_map(Color::splat(c)))),
    );
    let full = floor_job(
        a,
        Light::Environment(Arc::new(map_of(16, 8, |_, _| Color::splat(c)))),
    );
    for strategy in [
        DirectStrategy::Light,
        DirectStrategy::Mis,
        DirectStrategy::Bsdf,
    ] {
        for m in [1, 3] {
            let (h, h_se) = render_floor(&hemi, strategy, m, 16);
            if strategy != DirectStrategy::Bsdf {
                // Cosine sampling about +Y is exact on an upward floor.
                assert!(
                    (h - want).abs() < 1e-4 * want,
                    "hemisphere {strategy:?}: {h}"
                );
            }
            for (name, job) in [("half map", &half), ("full map", &full)] {
                let (mean, se) = render_floor(job, strategy, m, 16);
                // BSDF sampling of a constant sky is exact (weight a·c every time).
                let noisy = se > 0.0 || strategy == DirectStrategy::Bsdf;
                assert!(
                    noisy && se < 0.05 * want,
                    "{name} {strategy:?} m={m}: {mean} ± {se}"
                );
                // 4.5 standard errors: a false failure has probability < 1e-5 per case.
                let tol = 4.5 * (se * se + h_se * h_se).sqrt() + 1e-5 * want;
                assert!(
                    (mean - want).abs() <= tol && (mean - h).abs() <= tol,
                    "{name} {strategy:?} m={m}: {mean} ± {se}, hemisphere {h} ± {h_se}, exact {want}"
                );
            }
        }
    }
}

/// A map with a gradient, a ground and bright spots (not only the sun map's one).
fn patchy_map() -> EnvironmentMap {
    map_of(24, 12, |x, y| {
        let hash = (x.wrapping_mul(73_856_093) ^ y.wrapping_mul(19_349_663)) % 97;
        let base = Color::new(0.2, 0.3, 0.5) * (1.0 + y as f32 / 4.0) * (hash as f32 / 97.0);
        match (x, y) {
            (5, 3) => Color::new(40.0, 30.0, 20.0),
            (17, 8) | (18, 8) => Color::splat(12.0),
            (0, 0) | (23, 11) => Color::splat(6.0), // next to the poles and the seam
            _ => base,
        }
    })
}

fn chi2_env(env: &EnvironmentMap, seed: u64) -> Result<f64, String> {
    chi2_p_value(
        1_000_000,
        seed,
        |s: &mut Rng| env.sample_li(s.next_2d()).map(|ls| ls.wi),
        &|wi| env.pdf_li(wi) as f64,
    )
}

#[test]
fn importance_sampling_matches_its_pdf() {
    let maps = [
        ("sun map", sun_map()),
        ("patchy map", patchy_map()),
        (
            "patchy map, uniform",
            patchy_map().with_sampling(EnvSampling::Uniform),
        ),
    ];
    let significance = sidak_significance(maps.len());
    for (i, (name, env)) in maps.iter().enumerate() {
        let mass: f64 = integrate_bins(&|wi| env.pdf_li(wi) as f64).iter().sum();
        assert!((mass - 1.0).abs() < 1e-3, "{name}: ∫pdf dω = {mass}");
        let p = chi2_env(env, 40 + i as u64).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert!(p >= significance, "{name}: chi² p = {p:.2e}");
    }
}

/// The chi-square test must be able to fail: the sun map's sampler judged against a
/// pdf that forgets the sin θ of the lat-long mapping.
#[test]
fn chi2_rejects_a_pdf_without_sin_theta() {
    let env = patchy_map();
    let p = chi2_p_value(
        1_000_000,
        3,
        |s: &mut Rng| env.sample_li(s.next_2d()).map(|ls| ls.wi),
        &|wi| {
            let sin = (1.0 - wi.y as f64 * wi.y as f64).max(0.0).sqrt();
            env.pdf_li(wi) as f64 * sin / std::f64::consts::FRAC_PI_4
        },
    );
    assert!(p.as_ref().map_or(true, |p| *p < 1e-6), "{p:?}");
}

/// Light samples carry the map's own radiance and a pdf that `pdf_li` reproduces.
#[test]
fn samples_carry_the_texel_and_pdf_li() {
    let env = sun_map();
    let mut s = Rng::from_seed(5);
    let mut sun = 0;
    for _ in 0..20_000 {
        let ls = env.sample_li(s.next_2d()).expect("sample");
        assert_eq!(ls.li, env.le(ls.wi));
        assert!((ls.pdf - env.pdf_li(ls.wi)).abs() <= 2e-3 * ls.pdf);
        sun += (ls.li.x > 100.0) as u32;
    }
    // The sun gives most of ∫ L dω, so most samples land on it.
    assert!(sun > 10_000, "{sun} of 20000 samples on the sun");
}

fn temp_exr(dir: &Path, name: &str, img: &Image) -> PathBuf {
    let p = dir.join(name);
    ember::image_io::write_image(img, &p).unwrap();
    p
}

fn one_line(e: &EnvMapError, needles: &[&str]) {
    let msg = e.to_string();
    assert!(!msg.contains('\n'), "{msg}");
    for n in needles {
        assert!(msg.contains(n), "{msg:?} lacks {n:?}");
    }
}

#[test]
fn bad_maps_are_one_line_errors() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("missing.exr");
    one_line(
        &EnvironmentMap::load(&missing).unwrap_err(),
        &["missing.exr", "cannot read"],
    );
    let text = dir.path().join("notes.exr");
    std::fs::write(&text, "not an image").unwrap();
    one_line(
        &EnvironmentMap::load(&text).unwrap_err(),
        &["notes.exr", "not an OpenEXR"],
    );
    let png = dir.path().join("map.png");
    ember::image_io::write_image(&Image::new(4, 2), &png).unwrap();
    one_line(
        &EnvironmentMap::load(&png).unwrap_err(),
        &["map.png", "not an OpenEXR"],
    );
    let truncated = dir.path().join("truncated.exr");
    let bytes = std::fs::read(sun_map_path()).unwrap();
    std::fs::write(&truncated, &bytes[..bytes.len() / 2]).unwrap();
    one_line(
        &EnvironmentMap::load(&truncated).unwrap_err(),
        &["truncated.exr"],
    );
    one_line(
        &EnvironmentMap::from_image(Image::new(0, 0), "empty.exr").unwrap_err(),
        &["empty.exr", "no texels", "0x0"],
    );
    let mut img = Image::new(4, 2);
    img.pixels[6] = Color::new(1.0, f32::NAN, 0.0);
    let nan = temp_exr(dir.path(), "nan.exr", &img);
    one_line(
        &EnvironmentMap::load(&nan).unwrap_err(),
        &["nan.exr", "(2, 1)", "NaN"],
    );
    img.pixels[6] = Color::new(1.0, 1.0, -0.5);
    let neg = temp_exr(dir.path(), "neg.exr", &img);
    one_line(
        &EnvironmentMap::load(&neg).unwrap_err(),
        &["neg.exr", "(2, 1)", "-0.5"],
    );
    img.pixels[6] = Color::new(f32::INFINITY, 1.0, 1.0);
    let inf = temp_exr(dir.path(), "inf.exr", &img);
    one_line(
        &EnvironmentMap::load(&inf).unwrap_err(),
        &["inf.exr", "inf"],
    );
}

/// `-e` replaces the scene's hemisphere light; area lights after it keep their surfaces.
#[test]
fn set_environment_replaces_the_ambient_light() {
    let mut scene = common::load("scenes/cs184/sky/CBspheres_lambertian.dae");
    scene.lights.insert(
        0,
        Light::Ambient {
            radiance: Color::ONE,
        },
    );
    for t in scene.triangles.iter_mut().filter(|t| t.light != NO_LIGHT) {
        t.light += 1;
    }
    let areas = scene
        .lights
        .iter()
        .filter(|l| l.as_area().is_some())
        .count();
    assert!(areas > 0);
    scene.set_environment(Arc::new(sun_map()));
    assert!(!scene
        .lights
        .iter()
        .any(|l| matches!(l, Light::Ambient { .. })));
    assert_eq!(
        scene
            .lights
            .iter()
            .filter(|l| l.as_area().is_some())
            .count(),
        areas
    );
    assert!(matches!(scene.lights.last(), Some(Light::Environment(_))));
    let lit: Vec<_> = scene
        .triangles
        .iter()
        .filter(|t| t.light != NO_LIGHT)
        .collect();
    assert!(!lit.is_empty());
    for t in lit {
        assert!(scene.lights[t.light as usize].as_area().is_some());
    }
}

#[test]
fn cli_renders_with_e_and_refuses_bad_maps() {
    let dir = tempfile::tempdir().unwrap();
    let scene = common::repo("scenes/cs184/sky/CBspheres_lambertian.dae");
    let out = dir.path().join("env.exr");
    run(command()
        .args(["-s", "2", "-m", "2", "-r", "24", "18", "-q", "-e"])
        .arg(sun_map_path())
        .arg("-f")
        .arg(&out)
        .arg(&scene))
    .success();
    let img = ember::image_io::read_image(&out).unwrap();
    assert!(img.pixels.iter().all(|p| p.is_finite()));
    let meta = ember::image_io::read_metadata(&out).unwrap();
    assert!(meta
        .get("ember.env_map")
        .is_some_and(|m| m.ends_with("env_sun.exr")));
    assert!(meta.get("ember.env_map.fnv1a64").is_some());

    let bad = dir.path().join("bad.png");
    run(command()
        .args(["-s", "1", "-r", "8", "6", "-e", "no/such/map.exr", "-f"])
        .arg(&bad)
        .arg(&scene))
    .fails_with("no/such/map.exr");
    assert!(!bad.exists(), "a failed render left {}", bad.display());
    run(command()
        .args([
            "-s",
            "1",
            "-r",
            "8",
            "6",
            "--integrator",
            "light-tracing",
            "-e",
        ])
        .arg(sun_map_path())
        .arg("-f")
        .arg(&bad)
        .arg(&scene))
    .fails_with("light tracing")
    .fails_with("-e");
    assert!(!bad.exists());
}

/// Case 10 of `ember bench stability` at a small budget: on a map whose light comes
/// mostly from a small sun, MIS with importance sampling of the map is far less noisy
/// than MIS with uniform sampling of the sphere, and both agree on the mean.
#[cfg(feature = "bench")]
#[test]
fn mis_with_map_importance_beats_uniform_on_a_sun() {
    use ember::bench::stability::environment::{sun_sky, ENV_METHODS};
    use ember::bench::stability::Budget;
    let case = sun_sky(&Budget {
        width: 40,
        height: 30,
        spp: 16,
        seed: 3,
    })
    .unwrap();
    let imp = case.run(ENV_METHODS[0].0);
    let uni = case.run(ENV_METHODS[1].0);
    let bsdf = case.run(ENV_METHODS[2].0);
    for r in [imp, uni, bsdf] {
        assert_eq!(r.nonfinite, 0, "{}", r.name);
        println!(
            "{}: mean {:.4} ± {:.1e}, noise/pixel {:.3e}",
            r.name, r.mean, r.se, r.noise
        );
    }
    let z = (imp.mean - uni.mean).abs() / (imp.se * imp.se + uni.se * uni.se).sqrt();
    assert!(
        z < 4.5,
        "means differ by {z:.1} σ: {} vs {}",
        imp.mean,
        uni.mean
    );
    // Uniform sampling finds the sun (4 texels, ~0.03 sr) with probability ~0.25 %:
    // its noise is many times importance sampling's; 3× is a wide margin.
    assert!(
        uni.noise > 3.0 * imp.noise,
        "noise {} vs {}",
        uni.noise,
        imp.noise
    );
    assert!(
        bsdf.noise > 3.0 * imp.noise,
        "noise {} vs {}",
        bsdf.noise,
        imp.noise
    );
}

/// `ember export -e` writes the map in Mitsuba's orientation: Mitsuba's lookup of a
/// direction (`u = atan2(x, −z)/2π`, `v = acos(y)/π`) finds ember's texel for it.
#[test]
fn export_writes_the_map_in_mitsubas_orientation() {
    let dir = tempfile::tempdir().unwrap();
    run(command()
        .arg("export")
        .arg(common::repo("scenes/cs184/sky/CBspheres_lambertian.dae"))
        .arg("-e")
        .arg(sun_map_path())
        .arg("--out")
        .arg(dir.path()))
    .success();
    let xml = std::fs::read_to_string(dir.path().join("CBspheres_lambertian.xml")).unwrap();
    assert!(xml.contains("CBspheres_lambertian_env.exr"), "{xml}");
    let img =
        ember::image_io::read_image(&dir.path().join("CBspheres_lambertian_env.exr")).unwrap();
    let env = sun_map();
    let (w, h) = (env.width(), env.height());
    for j in 0..h {
        for i in 0..w {
            let uv = ember::Vec2::new((i as f32 + 0.5) / w as f32, (j as f32 + 0.5) / h as f32);
            let d = ember::lights::environment::uv_to_dir(uv);
            let u_m = (d.x.atan2(-d.z) / std::f32::consts::TAU).rem_euclid(1.0);
            let v_m = d.y.clamp(-1.0, 1.0).acos() / std::f32::consts::PI;
            let x = ((u_m * img.width as f32) as u32).min(img.width - 1);
            let y = ((v_m * img.height as f32) as u32).min(img.height - 1);
            assert_eq!(
                img.pixels[(y * img.width + x) as usize],
                env.le(d),
                "texel ({i}, {j})"
            );
        }
    }
}
