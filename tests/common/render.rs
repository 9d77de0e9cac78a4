//! Helpers shared by the integration tests.

use ember::accel::{self, AccelKind, BvhBuilder};
use ember::camera::Camera;
use ember::film::Image;
use ember::render::{render, RenderOutput, RenderSettings};
use ember::scene::{collada, Scene};
use std::path::PathBuf;

/// A path under the shared folder beside the repository.
pub fn shared(rel: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../shared")
        .join(rel)
}

pub fn load(rel: &str) -> Scene {
    let p = shared(rel);
    collada::load(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

pub fn render_scene(scene: &Scene, settings: &RenderSettings) -> RenderOutput {
    render_with(scene, settings, AccelKind::Native(BvhBuilder::Sah))
}

pub fn render_with(scene: &Scene, settings: &RenderSettings, kind: AccelKind) -> RenderOutput {
    let accel = accel::build(scene, kind).expect("accel");
    let cam = Camera::new(
        &scene.camera,
        &scene.bounds,
        settings.width,
        settings.height,
    );
    render(scene, accel.as_ref(), &cam, settings, &|_| {})
}

/// Two renders with independent seeds, and their average: the halves give the
/// render's own noise the way the reference README measures it.
pub struct HalfRenders {
    pub a: Image,
    pub b: Image,
    pub avg: Image,
}

pub fn render_halves(scene: &Scene, settings: &RenderSettings, kind: AccelKind) -> HalfRenders {
    let mut s = settings.clone();
    s.spp = settings.spp / 2;
    s.seed = settings.seed.wrapping_mul(2).wrapping_add(1);
    let a = render_with(scene, &s, kind);
    s.seed = settings.seed.wrapping_mul(2).wrapping_add(2);
    let b = render_with(scene, &s, kind);
    assert_eq!(
        a.nonfinite_samples + b.nonfinite_samples,
        0,
        "non-finite samples"
    );
    let avg = Image {
        pixels: a
            .image
            .pixels
            .iter()
            .zip(&b.image.pixels)
            .map(|(x, y)| 0.5 * (*x + *y))
            .collect(),
        ..a.image.clone()
    };
    HalfRenders {
        a: a.image,
        b: b.image,
        avg,
    }
}

impl HalfRenders {
    /// RMS noise of one pixel of the averaged image: RMSE(A − B)/2.
    pub fn noise_per_pixel(&self) -> f64 {
        self.a.rmse(&self.b) / 2.0
    }

    /// The same after 8×8 block averaging.
    pub fn noise_box8(&self) -> f64 {
        self.a.block_average(8).rmse(&self.b.block_average(8)) / 2.0
    }

    /// Standard error of the image mean of one channel (pixels taken as independent).
    pub fn noise_of_mean(&self) -> f64 {
        self.noise_per_pixel() / (self.avg.pixels.len() as f64).sqrt()
    }
}
