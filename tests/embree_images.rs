//! Whole-image agreement of the native BVH and Embree: the same render, same seed,
//! through both backends. Paths diverge only where the backends legitimately differ
//! (edge hits, ties), so the images agree to far below their own noise.

use crate::common;

use common::{load, render_halves};
use ember::accel::{AccelKind, BvhBuilder, EmbreeQuality};
use ember::integrators::DirectStrategy;
use ember::render::RenderSettings;

fn agree(scene_rel: &str) {
    let scene = load(scene_rel);
    let s = RenderSettings {
        spp: 32,
        max_depth: 5,
        strategy: Some(DirectStrategy::Mis),
        seed: 17,
        ..Default::default()
    };
    let native = render_halves(&scene, (160, 120), &s, AccelKind::Native(BvhBuilder::Sah));
    let embree = render_halves(
        &scene,
        (160, 120),
        &s,
        AccelKind::embree(EmbreeQuality::Medium),
    );
    let (mn, me) = (native.avg.mean(), embree.avg.mean());
    // Means: within 3 standard errors of one render's mean (the renders share seeds, so
    // they are strongly correlated and usually much closer than that).
    let se = native.noise_of_mean().max(embree.noise_of_mean());
    for c in 0..3 {
        assert!(
            ((mn[c] - me[c]) as f64).abs() <= 3.0 * se,
            "{scene_rel}: mean[{c}] native {} vs Embree {} (se {se})",
            mn[c],
            me[c]
        );
    }
    // 8×8 blocks: the difference is at most the noise floor of one render's blocks.
    let rmse8 = native
        .avg
        .block_average(8)
        .rmse(&embree.avg.block_average(8));
    let floor = native.noise_box8().max(embree.noise_box8());
    eprintln!("{scene_rel}: box8 RMSE native vs Embree {rmse8:.2e}, noise floor {floor:.2e}; identical pixels {}", native.avg.pixels.iter().zip(&embree.avg.pixels).filter(|(a, b)| a == b).count());
    assert!(
        rmse8 <= floor,
        "{scene_rel}: box8 RMSE {rmse8} above the noise floor {floor}"
    );
}

#[test]
fn cbspheres_lambertian_native_and_embree_images_agree() {
    agree("scenes/cs184/sky/CBspheres_lambertian.dae");
}

#[test]
fn cbbunny_native_and_embree_images_agree() {
    agree("scenes/cs184/sky/CBbunny.dae");
}

#[test]
fn cbspheres_glass_mirror_native_and_embree_images_agree() {
    agree("scenes/cs184/sky/CBspheres.dae");
}

/// An Embree render is the same image bit for bit at 1 and 2 threads, by default and
/// with camera rays in packets (the one variant whose lanes share an Embree query).
#[test]
fn embree_renders_do_not_depend_on_the_thread_count() {
    use ember::accel::{EmbreeMode, EmbreeQueries};
    let scene = load("scenes/cs184/sky/CBspheres_lambertian.dae");
    let s = RenderSettings {
        spp: 8,
        max_depth: 5,
        seed: 5,
        ..Default::default()
    };
    let default = EmbreeMode::robust(EmbreeQuality::Medium);
    let camera_packets = EmbreeMode {
        queries: EmbreeQueries::CameraPackets,
        ..default
    };
    for mode in [default, camera_packets] {
        let job = common::job(&scene, 96, 72, AccelKind::Embree(mode));
        let images: Vec<_> = [1, 2]
            .map(|t| {
                let pool = ember::accel::tracing_pool(Some(t)).expect("pool");
                pool.install(|| job.render(&s)).image
            })
            .into();
        assert!(images[0].pixels == images[1].pixels, "{mode}");
    }
}
