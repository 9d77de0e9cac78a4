//! Emitters seen directly, sampled apart where their edges cross pixels
//! (`render::edges`): the same expected image, with far less error on the outline.

use crate::common;

use common::{load, render_halves, render_scene};
use ember::accel::{AccelKind, BvhBuilder};
use ember::film::Image;
use ember::integrators::Estimator;
use ember::render::RenderSettings;

const SCENE: &str = "scenes/cs184/sky/CBspheres_lambertian.dae";
const SIZE: (u32, u32) = (48, 36);

fn settings(max_depth: u32, spp: u32, edges: u32, seed: u64) -> RenderSettings {
    RenderSettings {
        spp,
        max_depth,
        emitter_edges: edges,
        seed,
        ..Default::default()
    }
}

/// The same, light-traced: emitters seen directly come from its camera pass.
fn light_traced(max_depth: u32, spp: u32, edges: u32, seed: u64) -> RenderSettings {
    RenderSettings {
        estimator: Some(Estimator::LightTracing),
        ..settings(max_depth, spp, edges, seed)
    }
}

fn mse(a: &Image, b: &Image) -> f64 {
    a.rmse(b).powi(2)
}

/// At `-m 0` the image is emission seen directly alone: where the light's outline
/// crosses a pixel, sixteen emitter samples per pixel sample must cut the error
/// several times over. Counting the emission twice (in the paths as well) or not at
/// all would instead raise it far above the plain render's.
#[test]
fn emitter_samples_cut_the_outlines_error_at_depth_zero() {
    outline_error_falls(settings);
}

/// Light tracing's camera pass, which gives it the emitters seen directly, likewise.
#[test]
fn light_tracings_camera_pass_samples_outlines_apart_too() {
    outline_error_falls(light_traced);
}

fn outline_error_falls(make: fn(u32, u32, u32, u64) -> RenderSettings) {
    let scene = load(SCENE);
    let reference = render_scene(&scene, SIZE, &make(0, 4096, 0, 99)).image;
    let (mut plain, mut split) = (0.0, 0.0);
    for seed in 1..=4 {
        let without = render_scene(&scene, SIZE, &make(0, 16, 0, seed));
        let with = render_scene(&scene, SIZE, &make(0, 16, 16, seed));
        assert_eq!(without.outline_pixels, 0);
        // The light's outline, not the frame: a band a few pixels wide.
        let pixels = u64::from(SIZE.0 * SIZE.1);
        let marked = with.outline_pixels;
        assert!((1..pixels / 8).contains(&marked), "{marked} of {pixels}");
        plain += mse(&without.image, &reference);
        split += mse(&with.image, &reference);
    }
    assert!(plain > 0.0, "the light's outline should be noisy at 16 spp");
    assert!(
        split < 0.2 * plain,
        "emitter samples: MSE {split:.3e} against {plain:.3e} without"
    );
}

/// With paths (`-m 5`), the split leaves the expected image as it was: the mean of
/// the image with emitter samples and without differs by noise only (4.5 combined
/// standard errors of the two means). Losing the paths' own emission found after a
/// bounce, or their light sampling, in the marked pixels would move it.
#[test]
fn emitter_samples_leave_the_expected_image_unchanged() {
    let scene = load(SCENE);
    let kind = AccelKind::Native(BvhBuilder::Sah);
    let plain = render_halves(&scene, SIZE, &settings(5, 64, 0, 5), kind);
    let split = render_halves(&scene, SIZE, &settings(5, 64, 16, 5), kind);
    let (a, b) = (plain.avg.mean(), split.avg.mean());
    let se = (plain.noise_of_mean().powi(2) + split.noise_of_mean().powi(2)).sqrt();
    for c in 0..3 {
        assert!(
            ((a[c] - b[c]) as f64).abs() <= 4.5 * se,
            "channel {c}: without {a} vs with {b} (se {se})"
        );
    }
    // The marked pixels are the light's outline: their error is what falls.
    assert!(split.noise_per_pixel() < 0.8 * plain.noise_per_pixel());
}
