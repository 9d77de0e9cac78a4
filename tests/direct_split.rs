//! Light of at most one bounce, sampled apart where it is noisy (`render::split`):
//! the same expected image, with far less error on lights' outlines and glossy
//! highlights.

use crate::common;

use common::{load, render_halves, render_scene};
use ember::accel::{AccelKind, BvhBuilder};
use ember::film::Image;
use ember::integrators::Estimator;
use ember::render::RenderSettings;

/// A diffuse box: what the split finds is the light's outline.
const DIFFUSE: &str = "scenes/cs184/sky/CBspheres_lambertian.dae";
/// Microfacet spheres: the split finds the lights' glossy reflections too.
const GLOSSY: &str = "scenes/cs184/sky/CBspheres_microfacet_al_ag.dae";
const SIZE: (u32, u32) = (48, 36);

/// The CLI's choices for the scene (MIS on the glossy one), but plain path tracing.
fn settings(max_depth: u32, spp: u32, split: u32, seed: u64) -> RenderSettings {
    RenderSettings {
        spp,
        max_depth,
        direct_split: split,
        seed,
        strategy: None,
        ..Default::default()
    }
}

/// The same, light-traced: emitters seen directly come from its camera pass.
fn light_traced(max_depth: u32, spp: u32, split: u32, seed: u64) -> RenderSettings {
    RenderSettings {
        estimator: Some(Estimator::LightTracing),
        ..settings(max_depth, spp, split, seed)
    }
}

fn mse(a: &Image, b: &Image) -> f64 {
    a.rmse(b).powi(2)
}

/// At `-m 0` the image is emission seen directly alone: where the light's outline
/// crosses a pixel, sixteen split samples per pixel sample must cut the error
/// several times over. Counting the emission twice (in the paths as well) or not at
/// all would instead raise it far above the plain render's.
#[test]
fn split_samples_cut_the_outlines_error_at_depth_zero() {
    error_falls(DIFFUSE, 0, settings, 0.2);
}

/// Light tracing's camera pass, which gives it the emitters seen directly, likewise.
#[test]
fn light_tracings_camera_pass_splits_outlines_too() {
    error_falls(DIFFUSE, 0, light_traced, 0.2);
}

/// At `-m 1` on glossy spheres the split pixels are the lights' outline and their
/// reflections, and their direct light comes from the split samples alone: the error
/// must fall by half at least. Light at the first vertex counted twice (the paths'
/// own as well) or lost would raise it.
#[test]
fn split_samples_cut_the_highlights_error_at_depth_one() {
    error_falls(GLOSSY, 1, settings, 0.5);
}

/// Renders `scene` at depth `m`, 16 spp, over four seeds with and without the split,
/// against a 4096-spp render without it: the split's MSE must be below `ratio` times
/// the plain one's, with split pixels in a band of the frame, not all of it.
fn error_falls(scene: &str, m: u32, make: fn(u32, u32, u32, u64) -> RenderSettings, ratio: f64) {
    let scene = load(scene);
    let reference = render_scene(&scene, SIZE, &make(m, 4096, 0, 99)).image;
    let (mut plain, mut split) = (0.0, 0.0);
    for seed in 1..=4 {
        let without = render_scene(&scene, SIZE, &make(m, 16, 0, seed));
        let with = render_scene(&scene, SIZE, &make(m, 16, 16, seed));
        assert_eq!(without.split_pixels, 0);
        let pixels = u64::from(SIZE.0 * SIZE.1);
        let marked = with.split_pixels;
        assert!((1..pixels / 8).contains(&marked), "{marked} of {pixels}");
        plain += mse(&without.image, &reference);
        split += mse(&with.image, &reference);
    }
    assert!(plain > 0.0, "the split pixels should be noisy at 16 spp");
    assert!(
        split < ratio * plain,
        "split samples: MSE {split:.3e} against {plain:.3e} without"
    );
}

/// With paths (`-m 5`), the split leaves the expected image as it was: the mean of
/// the image with split samples and without differs by noise only (4.5 combined
/// standard errors of the two means). Counting the first vertex's light twice in the
/// split pixels, or losing the paths' light found after more bounces, would move it.
#[test]
fn split_samples_leave_the_expected_image_unchanged() {
    for name in [DIFFUSE, GLOSSY] {
        let scene = load(name);
        let kind = AccelKind::Native(BvhBuilder::Sah);
        let plain = render_halves(&scene, SIZE, &settings(5, 64, 0, 5), kind);
        let split = render_halves(&scene, SIZE, &settings(5, 64, 16, 5), kind);
        plain.assert_same_mean(&split, &format!("{name}: without vs with the split"));
        // The split pixels are the noisiest: their error is what falls.
        // (Less on the glossy spheres, whose indirect light carries more of the noise.)
        let bound = if name == DIFFUSE { 0.8 } else { 0.9 };
        let (n_split, n_plain) = (split.noise_per_pixel(), plain.noise_per_pixel());
        assert!(
            n_split < bound * n_plain,
            "{name}: noise per pixel {n_split:.3e} against {n_plain:.3e} without"
        );
    }
}
