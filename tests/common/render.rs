//! Helpers shared by the integration tests.

use ember::accel::{AccelKind, BvhBuilder};
use ember::film::Image;
use ember::render::{RenderJob, RenderOutput, RenderSettings};
use ember::scene::{collada, Scene};
use std::path::PathBuf;

/// A path in the repository (`scenes/…`, `tests/data/references/…`).
pub fn repo(rel: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(rel)
}

pub fn load(rel: &str) -> Scene {
    let p = repo(rel);
    collada::load(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

/// `scene` through the native SAH BVH, seen by its own camera at `width × height`.
pub fn job(scene: &Scene, width: u32, height: u32, kind: AccelKind) -> RenderJob {
    RenderJob::new(scene.clone(), kind, width, height).expect("accel")
}

pub fn render_scene(
    scene: &Scene,
    (width, height): (u32, u32),
    settings: &RenderSettings,
) -> RenderOutput {
    job(scene, width, height, AccelKind::Native(BvhBuilder::Sah)).render(settings)
}

/// The luminance (`y`) of every pixel of `out`, which must hold no NaN or infinite
/// sample.
pub fn finite_luminance(out: &RenderOutput) -> Vec<f64> {
    assert_eq!(out.nonfinite_samples, 0);
    out.image.pixels.iter().map(|p| p.y as f64).collect()
}

/// Two renders with independent seeds, and their average: the halves give the
/// render's own noise the way the reference README measures it.
pub struct HalfRenders {
    pub a: Image,
    pub b: Image,
    pub avg: Image,
}

pub fn render_halves(
    scene: &Scene,
    (width, height): (u32, u32),
    settings: &RenderSettings,
    kind: AccelKind,
) -> HalfRenders {
    let h = job(scene, width, height, kind).halves(settings);
    assert_eq!(h.nonfinite(), 0, "non-finite samples");
    HalfRenders {
        avg: h.average(),
        a: h.a.image,
        b: h.b.image,
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

    /// Panics unless the averaged images of `self` and `other` (`what` names them)
    /// have the same mean in every channel within 4.5 combined standard errors: two
    /// unbiased estimators of one image differ by noise only.
    pub fn assert_same_mean(&self, other: &HalfRenders, what: &str) {
        let (a, b) = (self.avg.mean(), other.avg.mean());
        let se = (self.noise_of_mean().powi(2) + other.noise_of_mean().powi(2)).sqrt();
        for c in 0..3 {
            assert!(
                ((a[c] - b[c]) as f64).abs() <= 4.5 * se,
                "{what}: channel {c}: {a} vs {b} (se {se})"
            );
        }
    }
}

/// A uniformly random point of a uniformly chosen triangle of `scene` (which must
/// have one), and that triangle's index: three numbers drawn from `rng`.
pub fn random_triangle_point(scene: &Scene, rng: &mut ember::sampling::Rng) -> (glam::Vec3, u32) {
    let ntri = scene.triangles.len();
    let i = ((rng.next_f32() * ntri as f32) as usize).min(ntri - 1);
    let [a, b, c] = scene.triangle_positions(i);
    let (u, v) = (rng.next_f32(), rng.next_f32());
    let (u, v) = if u + v > 1.0 {
        (1.0 - u, 1.0 - v)
    } else {
        (u, v)
    };
    (a + u * (b - a) + v * (c - a), i as u32)
}
