//! Whole-scene transport checks: estimators agree, nothing is ever NaN, and
//! renders do not depend on the thread count.

use crate::common;

use common::{load, render_halves, render_scene, repo};
use ember::accel::{AccelKind, BvhBuilder};
use ember::integrators::{DirectStrategy, Estimator};
use ember::render::{Adaptive, RenderJob, RenderSettings, Shading};
use std::path::Path;

#[test]
fn hemisphere_and_light_sampling_agree_on_cbspheres_lambertian() {
    let scene = load("scenes/cs184/sky/CBspheres_lambertian.dae");
    let base = RenderSettings {
        max_depth: 1,
        light_samples: 1,
        seed: 3,
        ..Default::default()
    };
    let run = |spp, strategy| {
        let s = RenderSettings {
            spp,
            strategy: Some(strategy),
            ..base.clone()
        };
        render_halves(&scene, (80, 60), &s, AccelKind::Native(BvhBuilder::Sah))
    };
    let light = run(32, DirectStrategy::Light);
    let hemi = run(256, DirectStrategy::Hemisphere);
    let mis = run(32, DirectStrategy::Mis);
    light.assert_same_mean(&hemi, "light vs hemisphere");
    light.assert_same_mean(&mis, "light vs MIS");
    // And light sampling is the less noisy one at equal samples, as it should be.
    assert!(light.noise_per_pixel() < hemi.noise_per_pixel() * (256f64 / 32.0).sqrt());
}

/// `MisGlossy`, auto's choice on glossy scenes, weights each path's direct light by
/// MIS at glossy vertices and takes it from light sampling alone at diffuse ones: the
/// weights still sum to one, so its mean is MIS's. Here the glossy side is checked (a
/// glossy vertex at the depth cap that did not trace its BSDF ray would lose 4.6 % of
/// this image at `-m 1`, over 40 standard errors); on this scene's small light the diffuse
/// side's share is too small to show, and the lit floor of `transport_analytic` checks it.
#[test]
fn mis_at_glossy_vertices_agrees_with_mis_everywhere() {
    let scene = load("scenes/cs184/sky/CBspheres_microfacet_al_ag.dae");
    for m in [1, 3] {
        let run = |strategy| {
            let s = RenderSettings {
                spp: 32,
                max_depth: m,
                strategy: Some(strategy),
                seed: 17,
                ..Default::default()
            };
            render_halves(&scene, (80, 60), &s, AccelKind::Native(BvhBuilder::Sah))
        };
        let (mis, mixed) = (run(DirectStrategy::Mis), run(DirectStrategy::MisGlossy));
        mis.assert_same_mean(&mixed, &format!("-m {m}: MIS vs MIS at glossy vertices"));
    }
}

/// Light-traced caustics off glossy metal (`Material::focuses`): path tracing drops
/// the paths that reach a light through a focusing conductor from a surface seen by
/// the camera, at a shadow ray or a BSDF-sampled ray, and light tracing takes exactly
/// those. The image mean must be path tracing's, on the microfacet spheres (α 0.025
/// and 0.25) and the copper bunny (α 0.05), at `-m 2` (the caustic alone) and `-m 4`.
/// (Light sampling at the metal, which MIS weighs too little here to show, is
/// `transport_analytic::caustics_off_smooth_metal_from_point_and_directional_lights`'.)
#[test]
fn caustics_off_glossy_metal_keep_path_tracings_mean() {
    for (name, m) in [
        ("CBspheres_microfacet_al_ag", 2),
        ("CBspheres_microfacet_al_ag", 4),
        ("CBbunny_microfacet_cu", 2),
        ("CBbunny_microfacet_cu", 4),
    ] {
        let scene = load(&format!("scenes/cs184/sky/{name}.dae"));
        let run = |estimator| {
            let s = RenderSettings {
                spp: 32,
                max_depth: m,
                estimator: Some(estimator),
                seed: 23,
                ..Default::default()
            };
            render_halves(&scene, (80, 60), &s, AccelKind::Native(BvhBuilder::Sah))
        };
        let (path_traced, caustics) = (run(Estimator::Path), run(Estimator::Caustics));
        let what = format!("{name} -m {m}: path vs caustics");
        path_traced.assert_same_mean(&caustics, &what);
    }
}

fn all_scenes(dir: &Path, out: &mut Vec<std::path::PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            all_scenes(&p, out);
        } else if p.extension().is_some_and(|x| x == "dae") {
            out.push(p);
        }
    }
}

#[test]
fn no_nan_or_inf_in_any_cs184_scene_at_m5() {
    let mut scenes = Vec::new();
    all_scenes(&repo("scenes/cs184"), &mut scenes);
    scenes.sort();
    assert!(scenes.len() >= 20);
    for p in scenes {
        let scene = ember::scene::collada::load(&p).unwrap();
        let s = RenderSettings {
            spp: 4,
            max_depth: 5,
            strategy: Some(DirectStrategy::Mis),
            ..Default::default()
        };
        let out = render_scene(&scene, (40, 30), &s);
        assert_eq!(out.nonfinite_samples, 0, "{}", p.display());
        assert!(out.image.all_finite(), "{}", p.display());
    }
}

fn render_threads(
    threads: usize,
    s: &RenderSettings,
    scene: &ember::scene::Scene,
) -> ember::film::Image {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| render_scene(scene, (48, 36), s).image)
}

#[test]
fn renders_are_identical_for_one_and_two_threads() {
    let scene = load("scenes/cs184/sky/CBspheres.dae");
    for s in [
        RenderSettings {
            spp: 8,
            max_depth: 5,
            strategy: Some(DirectStrategy::Mis),
            seed: 5,
            ..Default::default()
        },
        RenderSettings {
            spp: 64,
            max_depth: 2,
            adaptive: Some(Adaptive::new(8, 0.05)),
            seed: 9,
            ..Default::default()
        },
        RenderSettings {
            spp: 2,
            shading: Shading::Normals,
            ..Default::default()
        },
        // Light tracing splats across pixels from parallel chunks: still identical.
        RenderSettings {
            spp: 8,
            max_depth: 5,
            estimator: Some(Estimator::LightTracing),
            seed: 11,
            ..Default::default()
        },
    ] {
        assert_eq!(render_threads(1, &s, &scene), render_threads(2, &s, &scene));
    }
}

#[test]
fn adaptive_sampling_spends_more_samples_in_penumbrae_than_on_walls() {
    let scene = load("scenes/cs184/sky/CBspheres_lambertian.dae");
    let s = RenderSettings {
        spp: 512,
        max_depth: 1,
        adaptive: Some(Adaptive::new(32, 0.05)),
        seed: 2,
        ..Default::default()
    };
    let out = render_scene(&scene, (64, 48), &s);
    let max = *out.samples.iter().max().unwrap();
    let min = *out.samples.iter().min().unwrap();
    assert!(min >= 32 && max <= 512);
    assert!(
        max > 4 * min,
        "adaptive sampling did not adapt: {min}..{max}"
    );
    // Pixels seeing the light directly are constant (10) and stop early (after the minimum for constant pixels).
    let light_px = out
        .image
        .pixels
        .iter()
        .zip(&out.samples)
        .filter(|(p, _)| p.x >= 9.99)
        .map(|(_, &n)| n)
        .collect::<Vec<_>>();
    assert!(!light_px.is_empty() && light_px.iter().all(|&n| n <= 4 * 32));
}

#[test]
fn flush_to_zero_does_not_change_native_images() {
    let scene = load("scenes/cs184/sky/CBbunny.dae");
    let s = RenderSettings {
        spp: 4,
        max_depth: 5,
        strategy: Some(DirectStrategy::Mis),
        seed: 1,
        ..Default::default()
    };
    let plain = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    let ftz = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .start_handler(|_| ember::accel::set_flush_denormals())
        .build()
        .unwrap();
    let a = plain.install(|| render_scene(&scene, (40, 30), &s).image);
    let b = ftz.install(|| render_scene(&scene, (40, 30), &s).image);
    assert_eq!(a, b);
}

/// Light tracing splats anywhere and the adaptive rule looks at neighbours: a rectangle
/// of pixels (`render_rect`, as shards use) must still be exactly the crop of the image.
#[test]
fn a_pixel_rectangle_is_the_crop_of_the_full_image() {
    use ember::render::PixelRect;
    let scene = load("scenes/cs184/sky/CBspheres_lambertian.dae");
    let job = common::job(&scene, 40, 30, AccelKind::Native(BvhBuilder::Sah));
    let rect = PixelRect {
        x0: 7,
        y0: 3,
        x1: 29,
        y1: 17,
    };
    for s in [
        RenderSettings {
            spp: 4,
            max_depth: 3,
            estimator: Some(Estimator::LightTracing),
            seed: 4,
            ..Default::default()
        },
        RenderSettings {
            spp: 32,
            max_depth: 2,
            adaptive: Some(Adaptive::new(4, 0.05)),
            seed: 6,
            ..Default::default()
        },
    ] {
        let full = job.render(&s);
        let part = job.render_rect(&s, rect, &|_| {});
        for y in rect.y0..rect.y1 {
            for x in rect.x0..rect.x1 {
                let i = ((y - rect.y0) * rect.width() + (x - rect.x0)) as usize;
                assert_eq!(part.image.pixels[i], full.image.get(x, y), "{x},{y}");
                assert_eq!(part.samples[i], full.samples[(y * 40 + x) as usize]);
            }
        }
    }
}

/// `--integrator auto` between path tracing and light tracing on the scenes lit only
/// by point lights: its pilot must pick what a measurement prefers, by a wide margin
/// (at 160×120, 64 spp, `-m 5`, noise × CPU time: light tracing ~10⁴× better on
/// CBempty; path tracing 10³–10⁵× better on the others), and pick alike at every
/// thread count and seed.
#[test]
fn auto_picks_the_estimator_with_less_noise_per_ray() {
    let cases = [
        ("scenes/cs184/sky/CBempty.dae", Estimator::LightTracing),
        ("scenes/cmu462/basic/trigs1.dae", Estimator::Path),
        ("scenes/cmu462/basic/plane64.dae", Estimator::Path),
        ("scenes/stability/point_light.dae", Estimator::Path),
    ];
    for (path, want) in cases {
        let pilot =
            |threads, seed| on_pool(path, None, threads, seed, |job, s| job.estimator_choice(s));
        let (got, scores) = pilot(2, 0);
        let [path_score, light_score] = scores.expect("a pilot chose");
        assert_eq!(got, want, "{path}: {path_score:?} {light_score:?}");
        let (win, lose) = match want {
            Estimator::Path => (path_score, light_score),
            Estimator::LightTracing => (light_score, path_score),
            Estimator::Caustics => unreachable!("the pilot weighs path and light tracing"),
        };
        assert!(
            lose.inefficiency() > 10.0 * win.inefficiency(),
            "{path}: not a clear choice: {path_score:?} {light_score:?}"
        );
        assert_eq!(pilot(1, 7), (got, scores), "{path}");
    }
}

/// `ask` of a 160×120 job of the scene at `path` with `estimator`, `-m 5` and `seed`,
/// run on a pool of `threads`: the pilots' choices must depend on neither.
fn on_pool<T: Send>(
    path: &str,
    estimator: Option<Estimator>,
    threads: usize,
    seed: u64,
    ask: impl FnOnce(&RenderJob, &RenderSettings) -> T + Send,
) -> T {
    let scene = load(path);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    let job = common::job(&scene, 160, 120, AccelKind::Native(BvhBuilder::Sah));
    let s = RenderSettings {
        estimator,
        max_depth: 5,
        seed,
        ..Default::default()
    };
    pool.install(|| ask(&job, &s))
}

/// `--integrator auto` light-traces caustics, by rule, wherever a light shines on
/// mirrors or glass, another surface can receive the caustic and paths bounce (`-m`
/// 2 or more), unless emissive surfaces that are not lights are in the scene: from
/// area lights it measured more efficient than path tracing on every scene ember
/// ships (BENCHMARKS §3); from directional lights (CMU462's `carim_*`) path tracing
/// misses the caustic. It path-traces at `-m 1`, with `-a`, and where no light
/// starts a caustic path or nothing receives one.
#[test]
fn auto_light_traces_caustics_where_a_light_shines_on_mirrors_or_glass() {
    let auto = |path: &str, max_depth, adaptive: bool| {
        let scene = load(path);
        let job = common::job(&scene, 32, 24, AccelKind::Native(BvhBuilder::Sah));
        let s = RenderSettings {
            estimator: None,
            max_depth,
            adaptive: adaptive.then(|| Adaptive::new(4, 0.05)),
            ..Default::default()
        };
        let (estimator, pilot) = job.estimator_choice(&s);
        assert!(pilot.is_none(), "{path}: a rule decides, not a pilot");
        estimator
    };
    for path in [
        "scenes/cornell.dae",
        "scenes/cs184/sky/CBspheres.dae",
        "scenes/cs184/sky/CBspheres_refract.dae",
        "scenes/cs184/sky/CBspheres_tex.dae",
        "scenes/cs184/sky/CBgems.dae",
        "scenes/cs184/sky/CBcoil.dae",
        "scenes/stability/caustic.dae",
        "scenes/cmu462/basic/carim_glass.dae",
        "scenes/cmu462/basic/carim_mirror.dae",
        "scenes/cs184/sky/CBbunny_microfacet_cu.dae",
        "scenes/cs184/sky/CBspheres_microfacet_al_ag.dae",
    ] {
        assert_eq!(auto(path, 5, false), Estimator::Caustics, "{path}");
        assert_eq!(auto(path, 2, false), Estimator::Caustics, "{path} -m 2");
        assert_eq!(auto(path, 1, false), Estimator::Path, "{path} -m 1");
        assert_eq!(auto(path, 5, true), Estimator::Path, "{path} -a");
    }
    // No mirror, glass or smooth metal; a glass ball alone (nothing to receive a
    // caustic); an emissive surface that is not a light, found only by BSDF sampling
    // (its noise dwarfs the caustics').
    for path in [
        "scenes/cs184/sky/CBspheres_lambertian.dae",
        "scenes/cmu462/basic/sphere_glass.dae",
        "scenes/cmu462/sky/CBspheres.dae",
    ] {
        assert_eq!(auto(path, 5, false), Estimator::Path, "{path}");
    }
}

/// The caustics pilot gives the light paths the share their noise earns: few on
/// CMU462's `carim_glass`, where they cost most of the rays and add almost no noise
/// (sunlight through the glass figure lights a few pixels at its foot), more on
/// `cornell.dae`, whose glass and mirror balls cast caustics across the box. Its
/// choice does not depend on the thread count or the render's seed, so every band
/// and sample range of a render traces the same light paths.
#[test]
fn caustics_pilot_shares_light_paths_by_their_noise_and_rays() {
    let split = |path, threads, seed| {
        let caustics = Some(Estimator::Caustics);
        on_pool(path, caustics, threads, seed, |job, s| {
            job.caustics_split(s).expect("caustics are possible")
        })
    };
    let (carim, scores) = split("scenes/cmu462/basic/carim_glass.dae", 2, 0);
    let (cornell, _) = split("scenes/cornell.dae", 2, 0);
    assert!(
        carim.divisor >= 4 * cornell.divisor,
        "carim_glass {carim:?} {scores:?}, cornell.dae {cornell:?}"
    );
    assert_eq!(
        split("scenes/cmu462/basic/carim_glass.dae", 1, 9),
        (carim, scores)
    );
}

/// Without mirrors or glass, or without another surface to receive their caustics,
/// there are none to hand to light tracing: the caustics estimator is path tracing,
/// bit for bit. With them (CBspheres) the two
/// differ, and the caustics image does not depend on the thread count.
#[test]
fn caustics_estimator_is_path_tracing_without_specular_surfaces() {
    let settings = |estimator| RenderSettings {
        estimator: Some(estimator),
        spp: 8,
        max_depth: 5,
        seed: 3,
        ..Default::default()
    };
    let bits = |img: &ember::film::Image| -> Vec<[u32; 3]> {
        (img.pixels.iter())
            .map(|p| [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()])
            .collect()
    };
    // Nor where nothing receives them: CMU462's glass ball alone under a
    // directional and an ambient light.
    for scene in [
        "scenes/cs184/sky/CBspheres_lambertian.dae",
        "scenes/cmu462/basic/sphere_glass.dae",
    ] {
        let scene = load(scene);
        let path = render_scene(&scene, (64, 48), &settings(Estimator::Path));
        let caustics = render_scene(&scene, (64, 48), &settings(Estimator::Caustics));
        assert_eq!(bits(&path.image), bits(&caustics.image));
    }

    let specular = load("scenes/cs184/sky/CBspheres.dae");
    let path = render_threads(1, &settings(Estimator::Path), &specular);
    let caustics = render_threads(1, &settings(Estimator::Caustics), &specular);
    assert_ne!(bits(&path), bits(&caustics));
    let two = render_threads(2, &settings(Estimator::Caustics), &specular);
    assert_eq!(bits(&caustics), bits(&two));
}
