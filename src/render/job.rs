//! The one owner of a render: scene, acceleration structure and camera (which owns the
//! resolution), rendered over a rectangle of pixels. The CLI, the benches and the tests all
//! render through a `RenderJob`.

use super::pilot::{self, PilotScore};
use super::{render_warnings, RenderOutput, RenderSettings, Shading, StopToken};
use crate::accel::{self, Accel, AccelError, AccelKind};
use crate::camera::Camera;
use crate::color::luminance;
use crate::film::Image;
use crate::integrators::{Estimator, PathSettings};
use crate::scene::Scene;
use std::sync::Mutex;

/// Pixels `[x0, x1) × [y0, y1)` of the camera's image (column from the left, row from the top).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PixelRect {
    pub x0: u32,
    pub y0: u32,
    pub x1: u32,
    pub y1: u32,
}

impl PixelRect {
    /// The whole `width × height` image.
    pub fn full(width: u32, height: u32) -> PixelRect {
        PixelRect {
            x0: 0,
            y0: 0,
            x1: width,
            y1: height,
        }
    }

    pub fn width(&self) -> u32 {
        self.x1 - self.x0
    }

    pub fn height(&self) -> u32 {
        self.y1 - self.y0
    }

    pub fn area(&self) -> u64 {
        self.width() as u64 * self.height() as u64
    }
}

/// A scene ready to render: its acceleration structure and its camera.
pub struct RenderJob {
    pub scene: Scene,
    pub accel: Box<dyn Accel>,
    pub camera: Camera,
    /// The pilots run so far (`RenderJob::estimator`), by the settings they ran with.
    pilots: Mutex<Vec<(PathSettings, Estimator, [PilotScore; 2])>>,
}

impl RenderJob {
    /// The scene's own camera (spec §4) at `width × height`, over an accelerator of `kind`.
    /// The build runs on the current rayon pool.
    pub fn new(scene: Scene, kind: AccelKind, width: u32, height: u32) -> Result<Self, AccelError> {
        let camera = Camera::new(&scene.camera, &scene.bounds, width, height);
        Self::with_camera(scene, kind, camera)
    }

    /// A job with a camera of the caller's choosing (e.g. moved for a test).
    pub fn with_camera(scene: Scene, kind: AccelKind, camera: Camera) -> Result<Self, AccelError> {
        let accel = accel::build(&scene, kind)?;
        Ok(Self::with_accel(scene, accel, camera))
    }

    /// A job over an accelerator already built (or wrapped, as the benches do).
    pub fn with_accel(scene: Scene, accel: Box<dyn Accel>, camera: Camera) -> Self {
        RenderJob {
            scene,
            accel,
            camera,
            pilots: Mutex::new(Vec::new()),
        }
    }

    /// The estimator `s` renders this job with: its own, or auto's choice. Where the
    /// scene alone cannot decide (`Estimator::fixed_for`), a pilot render of each
    /// candidate decides (`render::pilot`), once per job and path settings.
    pub fn estimator(&self, s: &RenderSettings) -> Estimator {
        self.estimator_choice(s).0
    }

    /// As [`RenderJob::estimator`], with the pilot's scores (path tracing, light
    /// tracing) when a pilot chose.
    pub fn estimator_choice(&self, s: &RenderSettings) -> (Estimator, Option<[PilotScore; 2]>) {
        if let Some(e) = s.estimator {
            return (e, None);
        }
        if s.shading != Shading::Radiance {
            return (Estimator::Path, None);
        }
        if let Some(e) = Estimator::fixed_for(&self.scene, s.max_depth) {
            // Caustics' light paths are counted per sample index, not per pixel:
            // adaptive pixels path-trace alone.
            if e == Estimator::Caustics && s.adaptive.is_some() {
                return (Estimator::Path, None);
            }
            return (e, None);
        }
        let key = s.path_settings(&self.scene);
        let known = |pilots: &[(PathSettings, Estimator, [PilotScore; 2])]| {
            pilots
                .iter()
                .find(|(k, ..)| *k == key)
                .map(|&(_, e, p)| (e, p))
        };
        if let Some((e, scores)) = known(&self.pilots.lock().unwrap_or_else(|e| e.into_inner())) {
            return (e, Some(scores));
        }
        // Not under the lock: the pilot runs on rayon, whose threads may ask meanwhile.
        let (e, scores) = pilot::choose(self, s);
        let mut pilots = self.pilots.lock().unwrap_or_else(|e| e.into_inner());
        if known(&pilots).is_none() {
            pilots.push((key, e, scores));
        }
        (e, Some(scores))
    }

    /// The whole image.
    pub fn full_frame(&self) -> PixelRect {
        PixelRect::full(self.camera.width, self.camera.height)
    }

    /// Things the user should know before rendering with `s` (e.g. lights its estimator cannot see).
    pub fn warnings(&self, s: &RenderSettings) -> Vec<String> {
        render_warnings(self, s)
    }

    /// The whole image, without progress reports.
    pub fn render(&self, s: &RenderSettings) -> RenderOutput {
        self.render_rect(s, self.full_frame(), &|_| {})
    }

    /// Pixels `rect` of the image; `progress` is called with the number of pixels finished.
    pub fn render_rect(
        &self,
        s: &RenderSettings,
        rect: PixelRect,
        progress: &(dyn Fn(u64) + Sync),
    ) -> RenderOutput {
        super::render_rect(self, s, rect, progress, &StopToken::never())
    }

    /// As [`RenderJob::render_rect`], leaving the pixels not yet started black (0
    /// samples) once `stop` says so: the caller keeps what was rendered.
    pub fn render_rect_until(
        &self,
        s: &RenderSettings,
        rect: PixelRect,
        progress: &(dyn Fn(u64) + Sync),
        stop: &StopToken,
    ) -> RenderOutput {
        super::render_rect(self, s, rect, progress, stop)
    }

    /// Two renders of `s.spp / 2` samples with independent seeds derived from `s.seed`
    /// (`2·seed + 1` and `2·seed + 2`).
    pub fn halves(&self, s: &RenderSettings) -> Halves {
        let mut h = s.clone();
        h.spp = (s.spp / 2).max(1);
        h.seed = s.seed.wrapping_mul(2).wrapping_add(1);
        let a = self.render(&h);
        h.seed = s.seed.wrapping_mul(2).wrapping_add(2);
        let b = self.render(&h);
        Halves { a, b }
    }
}

/// Two independent renders of the same settings. Their difference is pure noise:
/// for a pixel with per-half variance σ², `Var(a − b) = 2σ²` and the average has
/// variance `σ²/2 = E[(a − b)²]/4`, so every standard error below comes from the halves.
pub struct Halves {
    pub a: RenderOutput,
    pub b: RenderOutput,
}

impl Halves {
    pub fn average(&self) -> Image {
        average(&self.a.image, &self.b.image)
    }

    pub fn nonfinite(&self) -> u64 {
        self.a.nonfinite_samples + self.b.nonfinite_samples
    }

    /// Samples taken per pixel by both halves together, averaged over the image.
    pub fn mean_samples(&self) -> f64 {
        (self.a.total_samples() + self.b.total_samples()) as f64
            / self.a.samples.len().max(1) as f64
    }

    /// Luminance mean of the averaged image over `pixels` (all when None) and its standard error.
    pub fn mean_and_se(&self, pixels: Option<&[usize]>) -> (f64, f64) {
        let all: Vec<usize>;
        let idx = match pixels {
            Some(p) => p,
            None => {
                all = (0..self.a.image.pixels.len()).collect();
                &all
            }
        };
        let n = idx.len().max(1) as f64;
        let (mut sum, mut var) = (0.0, 0.0);
        for &i in idx {
            let (la, lb) = (lum(&self.a.image, i), lum(&self.b.image, i));
            sum += 0.5 * (la + lb);
            var += 0.25 * (la - lb).powi(2);
        }
        (sum / n, (var / n).sqrt() / n.sqrt())
    }

    /// RMS noise of one pixel of the averaged image (luminance).
    pub fn noise_per_pixel(&self) -> f64 {
        let n = self.a.image.pixels.len().max(1) as f64;
        let s: f64 = (0..self.a.image.pixels.len())
            .map(|i| 0.25 * (lum(&self.a.image, i) - lum(&self.b.image, i)).powi(2))
            .sum();
        (s / n).sqrt()
    }
}

/// The pixel-wise mean of two images of the same size.
pub fn average(a: &Image, b: &Image) -> Image {
    let pixels = a
        .pixels
        .iter()
        .zip(&b.pixels)
        .map(|(x, y)| 0.5 * (*x + *y))
        .collect();
    Image {
        pixels,
        ..a.clone()
    }
}

#[inline]
fn lum(img: &Image, i: usize) -> f64 {
    luminance(img.pixels[i]) as f64
}
