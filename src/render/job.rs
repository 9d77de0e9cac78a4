//! The one owner of a render: scene, acceleration structure and camera (which owns the
//! resolution), rendered over a rectangle of pixels. The CLI, the benches and the tests all
//! render through a `RenderJob`.

use super::pilot::{self, CausticsSplit, PilotScore};
use super::{render_warnings, RenderOutput, RenderSettings, Shading, StopToken};
use crate::accel::{self, Accel, AccelError, AccelKind};
use crate::camera::Camera;
use crate::color::luminance;
use crate::film::Image;
use crate::integrators::{light_tracing, Estimator, PathSettings};
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

    /// Its pixels `(x, y)`, row by row.
    pub fn pixels(self) -> impl Iterator<Item = (u32, u32)> {
        (self.y0..self.y1).flat_map(move |y| (self.x0..self.x1).map(move |x| (x, y)))
    }

    /// Whether pixel `(x, y)` lies inside.
    pub fn contains(&self, (x, y): (u32, u32)) -> bool {
        (self.x0..self.x1).contains(&x) && (self.y0..self.y1).contains(&y)
    }

    /// The index of pixel `(x, y)` (inside) in a row-major list of this rectangle's.
    pub fn index(&self, (x, y): (u32, u32)) -> usize {
        ((y - self.y0) * self.width() + (x - self.x0)) as usize
    }

    /// This rectangle grown by `r` pixels on every side, within a `width × height` frame.
    pub fn grown(&self, r: u32, (width, height): (u32, u32)) -> PixelRect {
        PixelRect {
            x0: self.x0.saturating_sub(r),
            y0: self.y0.saturating_sub(r),
            x1: (self.x1 + r).min(width),
            y1: (self.y1 + r).min(height),
        }
    }
}

/// A scene ready to render: its acceleration structure and its camera.
pub struct RenderJob {
    pub scene: Scene,
    pub accel: Box<dyn Accel>,
    pub camera: Camera,
    /// The estimator pilots run so far (`RenderJob::estimator`), by the settings they ran with.
    pilots: PilotCache<(Estimator, [PilotScore; 2])>,
    /// The caustics pilots run so far (`RenderJob::caustics_split`), likewise.
    caustics_pilots: PilotCache<(CausticsSplit, [PilotScore; 2])>,
}

/// Pilot results by the path settings they ran with.
struct PilotCache<T>(Mutex<Vec<(PathSettings, T)>>);

impl<T: Copy> PilotCache<T> {
    fn new() -> Self {
        PilotCache(Mutex::new(Vec::new()))
    }

    /// The result for `key`, from `run` the first time it is asked for.
    fn get_or_run(&self, key: PathSettings, run: impl FnOnce() -> T) -> T {
        let known = |v: &[(PathSettings, T)]| v.iter().find(|(k, _)| *k == key).map(|&(_, t)| t);
        if let Some(t) = known(&self.0.lock().unwrap_or_else(|e| e.into_inner())) {
            return t;
        }
        // Not under the lock: the pilot runs on rayon, whose threads may ask meanwhile.
        let t = run();
        let mut v = self.0.lock().unwrap_or_else(|e| e.into_inner());
        match known(&v) {
            Some(first) => first,
            None => {
                v.push((key, t));
                t
            }
        }
    }
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
            pilots: PilotCache::new(),
            caustics_pilots: PilotCache::new(),
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
        let (e, scores) = self.pilots.get_or_run(key, || pilot::choose(self, s));
        (e, Some(scores))
    }

    /// How `Estimator::Caustics` shares a render with settings `s` between camera
    /// samples and light paths: the caustics pilot's choice (`render::pilot`), run
    /// once per job and path settings, so every band and sample range of a render
    /// traces the same light paths. With its scores (camera part, light part).
    /// `None` where no light path can make a caustic
    /// (`light_tracing::caustics_possible`): the estimator is path tracing alone.
    pub fn caustics_split(&self, s: &RenderSettings) -> Option<(CausticsSplit, [PilotScore; 2])> {
        if !light_tracing::caustics_possible(&self.scene, s.max_depth) {
            return None;
        }
        let key = s.path_settings(&self.scene);
        Some(
            self.caustics_pilots
                .get_or_run(key, || pilot::caustics_split(self, s)),
        )
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
