//! Comparison with the Mitsuba 3 reference renders in tests/data/references, as
//! their README prescribes: image mean, and RMSE of 8×8 block averages against
//! the combined noise floor of the reference and of this render.

use crate::common;

use common::{load, render_halves, repo};
use ember::accel::{AccelKind, BvhBuilder};
use ember::film::Image;
use ember::image_io::read_image;
use ember::integrators::{DirectStrategy, Estimator, Roulette};
use ember::render::RenderSettings;

struct Reference {
    /// The standard error of the reference's own image mean, per channel.
    noise_mean: [f64; 3],
    noise_box8: f64,
    image: Image,
}

fn reference(file: &str) -> Reference {
    let text =
        std::fs::read_to_string(repo("tests/data/references/manifest.json")).expect("manifest");
    let v: serde_json::Value = serde_json::from_str(&text).expect("manifest json");
    let e = v["images"]
        .as_array()
        .unwrap()
        .iter()
        .find(|e| e["file"] == file)
        .expect("manifest entry");
    let arr = |k: &str| -> [f64; 3] {
        let a = e[k].as_array().unwrap();
        [
            a[0].as_f64().unwrap(),
            a[1].as_f64().unwrap(),
            a[2].as_f64().unwrap(),
        ]
    };
    Reference {
        noise_mean: arr("noise_mean_rgb"),
        noise_box8: e["noise_rmse_box8"].as_f64().unwrap(),
        image: read_image(&repo(&format!("tests/data/references/{file}"))).expect("reference exr"),
    }
}

/// How the image means are compared.
#[derive(Clone, Copy, PartialEq)]
enum MeanOf {
    /// Plain linear mean.
    All,
    /// Linear mean over the pixels whose reference value is below the threshold: drops
    /// CBempty's two ceiling hot-spot pixels (~478), which the reference has 0.48 % above
    /// the closed form (ember meets it: `transport_analytic.rs`). In the 8×8-pixel
    /// blocks they added a systematic 0.003 to the RMSE.
    ExcludingHotSpot(f32),
}

fn masked_mean(img: &Image, reference: &Image, limit: f32) -> ([f64; 3], usize) {
    let mut s = [0f64; 3];
    let mut n = 0;
    for (p, r) in img.pixels.iter().zip(&reference.pixels) {
        if r.max_element() < limit {
            for c in 0..3 {
                s[c] += p[c] as f64;
            }
            n += 1;
        }
    }
    (s.map(|v| v / n as f64), n)
}

/// `img` with the pixels where `reference` reaches `limit` set to zero.
fn mask(img: &Image, reference: &Image, limit: f32) -> Image {
    let pixels = img
        .pixels
        .iter()
        .zip(&reference.pixels)
        .map(|(p, r)| {
            if r.max_element() < limit {
                *p
            } else {
                ember::Color::ZERO
            }
        })
        .collect();
    Image {
        pixels,
        ..img.clone()
    }
}

trait Masked {
    fn masked(&self, reference: &Image, limit: f32) -> Self;
}

impl Masked for common::HalfRenders {
    fn masked(&self, reference: &Image, limit: f32) -> Self {
        common::HalfRenders {
            a: mask(&self.a, reference, limit),
            b: mask(&self.b, reference, limit),
            avg: mask(&self.avg, reference, limit),
        }
    }
}

/// Renders `scene` at 160×120 with max depth `m` and checks it against `file`.
fn check(scene_rel: &str, file: &str, m: u32, spp: u32, mean_of: MeanOf) {
    check_with(scene_rel, file, m, spp, mean_of, Estimator::Path);
}

fn check_with(
    scene_rel: &str,
    file: &str,
    m: u32,
    spp: u32,
    mean_of: MeanOf,
    estimator: Estimator,
) {
    let r = reference(file);
    let scene = load(scene_rel);
    let job = common::job(&scene, 160, 120, AccelKind::Native(BvhBuilder::Sah));
    let settings = RenderSettings {
        estimator: Some(estimator),
        spp,
        max_depth: m,
        strategy: Some(if m > 1 {
            DirectStrategy::Mis
        } else {
            DirectStrategy::Light
        }),
        roulette: Roulette::default(),
        ..Default::default()
    };
    assert_eq!((r.image.width, r.image.height), (160, 120));
    let runs = Runs::render(&job, &settings, 1234);
    assert!(runs.halves.avg.all_finite());
    let limit = match mean_of {
        MeanOf::All => f32::INFINITY,
        MeanOf::ExcludingHotSpot(limit) => limit,
    };
    let (want, n) = masked_mean(&r.image, &r.image, limit);
    assert!(
        n + 8 >= r.image.pixels.len(),
        "{file}: the mask drops more than the hot spot"
    );

    // 1. Image mean: within T15 standard errors of the difference (ours from the spread
    // of the runs' means, the reference's from its manifest). No slack for systematic
    // differences: over 8 seeds per case every |z| stayed below 5.2.
    let (ours, se) = runs.masked_mean(&r.image, limit);
    for c in 0..3 {
        let tol = T15 * (se[c].powi(2) + r.noise_mean[c].powi(2)).sqrt();
        assert!(
            (ours[c] - want[c]).abs() <= tol,
            "{file}: mean[{c}] = {} vs reference {} (tol {tol}, se {})",
            ours[c],
            want[c],
            se[c]
        );
    }

    // 2. Block RMSE against the combined noise floor of both images. Were block means
    // Gaussian, the RMSE over 900 values would stay within 1.1 of the floor; fireflies and
    // splats give heavier tails: over 8 seeds per case the ratio ran 0.6-1.6. 2 holds
    // it, where the former bound (3x the floor plus 0.002) passed edges shifted by up to
    // 10x the noise in the quiet scenes.
    let h = runs.halves.masked(&r.image, limit);
    let reference = mask(&r.image, &r.image, limit);
    let rmse8 = h.avg.block_average(8).rmse(&reference.block_average(8));
    let expected = (r.noise_box8.powi(2) + h.noise_box8().powi(2)).sqrt();
    let tol = 2.0 * expected;
    eprintln!("{file}: box8 RMSE {rmse8:.5}, expected noise {expected:.5}, tol {tol:.5}; mean {ours:?} vs {want:?}, se {se:?}");
    assert!(
        rmse8 <= tol,
        "{file}: 8x8-block RMSE {rmse8} exceeds {tol} (noise floor {expected})"
    );
}

/// The two-sided Student t bound with 15 degrees of freedom (`RUNS` - 1) whose tail
/// probability is that of a normal's 4.5σ (6.8e-6).
const T15: f64 = 6.73;

/// Independent renders of one setting at `spp / RUNS` each: the spread of their image
/// means is the mean's standard error whatever the estimator (light tracing splats a
/// path into several pixels, so a per-pixel formula would understate it).
struct Runs {
    images: Vec<Image>,
    /// The first and second half of the runs, averaged, and the average of all.
    halves: common::HalfRenders,
}

const RUNS: usize = 16;

impl Runs {
    fn render(job: &ember::render::RenderJob, settings: &RenderSettings, seed: u64) -> Runs {
        assert_eq!(settings.spp % RUNS as u32, 0);
        let images: Vec<Image> = (0..RUNS as u64)
            .map(|k| {
                let s = RenderSettings {
                    spp: settings.spp / RUNS as u32,
                    seed: seed * RUNS as u64 + k,
                    ..settings.clone()
                };
                let out = job.render(&s);
                assert_eq!(out.nonfinite_samples, 0, "non-finite samples");
                out.image
            })
            .collect();
        let half = RUNS / 2;
        let halves = common::HalfRenders {
            a: average_of(&images[..half]),
            b: average_of(&images[half..]),
            avg: average_of(&images),
        };
        Runs { images, halves }
    }

    /// The mean over the pixels where the reference is below `limit`, and its standard
    /// error, per channel.
    fn masked_mean(&self, reference: &Image, limit: f32) -> ([f64; 3], [f64; 3]) {
        let means: Vec<[f64; 3]> = (self.images.iter())
            .map(|img| masked_mean(img, reference, limit).0)
            .collect();
        let (mut mean, mut se) = ([0.0; 3], [0.0; 3]);
        for c in 0..3 {
            let channel: Vec<f64> = means.iter().map(|m| m[c]).collect();
            (mean[c], se[c]) = common::mean_and_stderr(&channel);
        }
        (mean, se)
    }
}

fn average_of(images: &[Image]) -> Image {
    let mut avg = images[0].clone();
    for img in &images[1..] {
        for (a, p) in avg.pixels.iter_mut().zip(&img.pixels) {
            *a += *p;
        }
    }
    let n = images.len() as f32;
    avg.pixels.iter_mut().for_each(|a| *a /= n);
    avg
}

#[test]
fn cbspheres_lambertian_m1() {
    check(
        "scenes/cs184/sky/CBspheres_lambertian.dae",
        "CBspheres_lambertian_m1.exr",
        1,
        64,
        MeanOf::All,
    );
}

#[test]
fn cbspheres_lambertian_m5() {
    check(
        "scenes/cs184/sky/CBspheres_lambertian.dae",
        "CBspheres_lambertian_m5.exr",
        5,
        64,
        MeanOf::All,
    );
}

#[test]
fn cbbunny_m1() {
    check(
        "scenes/cs184/sky/CBbunny.dae",
        "CBbunny_m1.exr",
        1,
        64,
        MeanOf::All,
    );
}

#[test]
fn cbbunny_m5() {
    check(
        "scenes/cs184/sky/CBbunny.dae",
        "CBbunny_m5.exr",
        5,
        64,
        MeanOf::All,
    );
}

#[test]
fn cbempty_m1() {
    check(
        "scenes/cs184/sky/CBempty.dae",
        "CBempty_m1.exr",
        1,
        64,
        MeanOf::ExcludingHotSpot(20.0),
    );
}

#[test]
fn cbempty_m5() {
    check(
        "scenes/cs184/sky/CBempty.dae",
        "CBempty_m5.exr",
        5,
        128,
        MeanOf::ExcludingHotSpot(20.0),
    );
}

#[test]
fn cbspheres_glass_mirror_m8() {
    check(
        "scenes/cs184/sky/CBspheres.dae",
        "CBspheres_m8.exr",
        8,
        128,
        MeanOf::All,
    );
}

/// Path tracing with light-traced caustics (`--integrator caustics`) against the same
/// reference: the two estimators' paths must add up to every path, once.
#[test]
fn caustics_cbspheres_glass_mirror_m8() {
    check_with(
        "scenes/cs184/sky/CBspheres.dae",
        "CBspheres_m8.exr",
        8,
        64,
        MeanOf::All,
        Estimator::Caustics,
    );
}

/// The fireflies of light focused by the glass and mirror balls go: at 64 spp its
/// error against the reference is far below path tracing's (over 8 seeds each at
/// 160×120 the RMSE was 0.0139 against 0.0237, a ratio of 0.59; each estimate here
/// averages the MSE of 3 seeds, and the bar, 0.8, leaves room for their spread).
#[test]
fn caustics_lower_the_error_of_cbspheres_m8() {
    let r = reference("CBspheres_m8.exr");
    let scene = load("scenes/cs184/sky/CBspheres.dae");
    let job = common::job(&scene, 160, 120, AccelKind::Native(BvhBuilder::Sah));
    let rmse = |estimator| {
        let mse: f64 = (0..3)
            .map(|seed| {
                let settings = RenderSettings {
                    estimator: Some(estimator),
                    spp: 64,
                    max_depth: 8,
                    seed: 500 + seed,
                    ..Default::default()
                };
                let img = job.render(&settings).image;
                let sum: f64 = (img.pixels.iter().zip(&r.image.pixels))
                    .map(|(a, b)| f64::from((*a - *b).length_squared()))
                    .sum();
                sum / (3 * img.pixels.len()) as f64
            })
            .sum();
        (mse / 3.0).sqrt()
    };
    let (path, caustics) = (rmse(Estimator::Path), rmse(Estimator::Caustics));
    assert!(
        caustics < 0.8 * path,
        "RMSE with caustics by light tracing {caustics:.5}, path tracing {path:.5}"
    );
}

/// Light tracing (`--integrator light-tracing`) against the same references. It cannot
/// show specular surfaces to a pinhole camera, so CBspheres (mirror, glass) is not here.
#[test]
fn light_tracing_cbspheres_lambertian_m1_and_m5() {
    for (m, file) in [
        (1, "CBspheres_lambertian_m1.exr"),
        (5, "CBspheres_lambertian_m5.exr"),
    ] {
        check_with(
            "scenes/cs184/sky/CBspheres_lambertian.dae",
            file,
            m,
            64,
            MeanOf::All,
            Estimator::LightTracing,
        );
    }
}

#[test]
fn light_tracing_cbbunny_m5() {
    check_with(
        "scenes/cs184/sky/CBbunny.dae",
        "CBbunny_m5.exr",
        5,
        64,
        MeanOf::All,
        Estimator::LightTracing,
    );
}

/// Light tracing on CBempty. The two hot-spot pixels are left out as for path tracing:
/// the reference has them 0.48 % above the closed form, which both of ember's estimators
/// meet to 0.005 % (`transport_analytic::point_light_hot_spot_matches_the_closed_form`).
#[test]
fn light_tracing_cbempty_m1_and_m5() {
    for (m, file) in [(1, "CBempty_m1.exr"), (5, "CBempty_m5.exr")] {
        check_with(
            "scenes/cs184/sky/CBempty.dae",
            file,
            m,
            32,
            MeanOf::ExcludingHotSpot(20.0),
            Estimator::LightTracing,
        );
    }
}

/// The per-pixel test: 16 renders at 32 spp with independent seeds, a Welch t per
/// pixel and channel against the reference and its noise (Šidák, 1 % family-wise): with
/// the estimator `--integrator auto` picks for CBempty, no pixel fails but the two the
/// reference has wrong (the issue allowed 0.25 % of them, 48 pixels). The Welch test is
/// case 9's (`ember::bench`, feature `bench`).
#[cfg(feature = "bench")]
#[test]
fn cbempty_m5_per_pixel_with_the_default_estimator() {
    use ember::bench::stability::light_paths::{reference as noisy_reference, welch_pixel_test};
    let scene = load("scenes/cs184/sky/CBempty.dae");
    let job = common::job(&scene, 160, 120, AccelKind::Native(BvhBuilder::Sah));
    let auto = |max_depth| {
        job.estimator(&RenderSettings {
            estimator: None,
            max_depth,
            ..RenderSettings::default()
        })
    };
    let estimator = auto(5);
    assert_eq!(estimator, Estimator::LightTracing);
    // Direct light alone is exact per camera sample: auto path-traces at -m 1.
    assert_eq!(auto(1), Estimator::Path);
    let (reference, noise) =
        noisy_reference(&repo("tests/data/references"), "CBempty_m5.exr").unwrap();
    let renders: Vec<Image> = (0..16)
        .map(|k| {
            let s = RenderSettings {
                spp: 32,
                max_depth: 5,
                estimator: None,
                strategy: None,
                seed: 500 + k,
                ..Default::default()
            };
            let out = common::render_scene(&scene, (160, 120), &s);
            assert_eq!(out.nonfinite_samples, 0);
            out.image
        })
        .collect();
    let t = welch_pixel_test(&renders, &reference, noise);
    eprintln!(
        "CBempty_m5 per pixel: {:.3}% pass ({} high, {} low)",
        100.0 * t.pass_rate,
        t.fail_high,
        t.fail_low
    );
    assert_only_the_hot_spot_fails(&t.failing, &reference);
}

/// The Welch test is Šidák-corrected to 1 % family-wise, so a correct render fails no
/// pixel but the reference's two hot-spot pixels, which it has 0.48 % above the closed
/// form (`transport_analytic::point_light_hot_spot_matches_the_closed_form`).
#[cfg(feature = "bench")]
pub fn assert_only_the_hot_spot_fails(failing: &[usize], reference: &Image) {
    for &i in failing {
        let (x, y) = (i % reference.width as usize, i / reference.width as usize);
        assert!(
            reference.pixels[i].max_element() >= 20.0,
            "pixel ({x}, {y}) fails: {} in the reference",
            reference.pixels[i]
        );
    }
}

/// Not a test: prints the masked CBempty m5 mean at high spp (EMBER_SPP), to check for bias by hand.
#[test]
#[ignore = "a probe for checking bias by hand (it asserts nothing): EMBER_SPP=8192 cargo test --release --test suite references::cbempty_m5_high_spp_probe -- --ignored --nocapture"]
fn cbempty_m5_high_spp_probe() {
    let spp: u32 = std::env::var("EMBER_SPP")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(2048);
    let r = reference("CBempty_m5.exr");
    let scene = load("scenes/cs184/sky/CBempty.dae");
    let s = RenderSettings {
        spp,
        max_depth: 5,
        strategy: Some(DirectStrategy::Mis),
        seed: 99,
        ..Default::default()
    };
    let h = render_halves(&scene, (160, 120), &s, AccelKind::Native(BvhBuilder::Sah));
    let (ours, n) = masked_mean(&h.avg, &r.image, 20.0);
    let (want, _) = masked_mean(&r.image, &r.image, 20.0);
    eprintln!(
        "spp {spp}: masked mean {ours:?} vs {want:?} over {n} px; se {}",
        h.noise_per_pixel() / (n as f64).sqrt()
    );
}
