//! The render driver: it owns the pixel loop (tiles over rayon, fixed or adaptive
//! sample counts, `pixels.rs`) and the splatting loop of adjoint integrators
//! (`splats.rs`), and builds the integrator the settings ask for. Integrators see
//! only blocks of pixel samples or numbered light paths (`crate::integrators`).
//! `RenderJob` (job.rs) owns what is rendered.

pub mod adaptive;
mod job;
mod memory;
pub mod pilot;
mod pixels;
mod progressive;
mod splats;
mod split;
mod stop;

/// Camera paths' engine, chosen with the render settings.
pub use crate::integrators::Engine;
pub use job::{average, Halves, PixelRect, RenderJob};
pub use memory::{available_bytes, render_bytes};
pub use progressive::{pass_seed, pass_spp, render_passes, Film};
pub use stop::{StopReason, StopToken};

use crate::accel::Accel;
use crate::camera::Camera;
use crate::film::{heat_map, Image};
use crate::integrators::debug::{DebugView, View};
use crate::integrators::{
    light_tracing, DirectStrategy, Estimator, LightTracer, PathIntegrator, PathSettings, Roulette,
    SampleIntegrator, Tracing,
};
use crate::names::{display_from_table, Named};
use crate::sampling::SamplerKind;
use crate::scene::Scene;
use crate::Color;
use split::{DirectSplit, MAX_SPLIT_BOUNCES};
use std::sync::atomic::{AtomicU64, Ordering};

/// What each pixel shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Shading {
    /// Radiance (the physically based image).
    #[default]
    Radiance,
    /// `0.5·n + 0.5` of the shading normal.
    Normals,
    /// BVH nodes + primitives tested per camera ray: the image holds the raw counts
    /// (mean over the pixel's rays, in every channel); [`RenderOutput::cost_heat_map`]
    /// colours them.
    BvhCost,
}

impl Named for Shading {
    const WHAT: &'static str = "shading";
    const TABLE: &'static [(Self, &'static str, &'static str)] = &[
        (Shading::Radiance, "radiance", "The physically based image"),
        (
            Shading::Normals,
            "normals",
            "0.5·n + 0.5 of the shading normal (course parts 1-2)",
        ),
        (
            Shading::BvhCost,
            "bvh-cost",
            "Heat map of BVH nodes + primitives tested per camera ray",
        ),
    ];
}
display_from_table!(Shading);

/// Adaptive sampling (spec §7): stop a pixel once `1.96·σ/√n ≤ tol·μ`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Adaptive {
    pub batch: u32,
    pub tol: f32,
    /// A pixel whose samples so far are all equal (σ = 0) keeps sampling until it has
    /// this many (`StopRule::Neighbourhood`: non-zero constants only).
    pub min_samples_if_constant: u32,
    pub rule: StopRule,
}

/// When a pixel whose samples are all equal may stop.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StopRule {
    /// The course's rule on the pixel's own samples, after `min_samples_if_constant`.
    /// Biased where light is rare (stability case 7); kept for comparison.
    PerPixel,
    /// `render::adaptive` (default): a pixel of zeros after a count set by how often its
    /// neighbours find light; a constant non-zero pixel after `min_samples_if_constant`.
    Neighbourhood,
}

impl Adaptive {
    pub fn new(batch: u32, tol: f32) -> Self {
        Adaptive {
            batch: batch.max(1),
            tol,
            min_samples_if_constant: 4 * batch.max(1),
            rule: StopRule::Neighbourhood,
        }
    }
}

/// How to render; the resolution belongs to the camera (`RenderJob`).
#[derive(Clone, Debug)]
pub struct RenderSettings {
    pub spp: u32,
    pub light_samples: u32,
    pub max_depth: u32,
    pub accumulate: bool,
    /// Camera paths (with `strategy`) or light tracing; `None` chooses for the job
    /// (`RenderJob::estimator`).
    pub estimator: Option<Estimator>,
    /// Direct-lighting estimator of camera paths; `None` chooses one for the scene
    /// (`DirectStrategy::auto_for`) where the integrator is built.
    pub strategy: Option<DirectStrategy>,
    pub roulette: Roulette,
    pub adaptive: Option<Adaptive>,
    pub shading: Shading,
    pub seed: u64,
    /// Which numbers pixel samples draw.
    pub sampler: SamplerKind,
    /// Index of the first sample of every pixel: a render takes samples
    /// `spp_offset .. spp_offset + spp`, so renders of disjoint sample ranges (sample
    /// shards, `--spp-offset`) merge into one render of all of them. Not with `adaptive`.
    pub spp_offset: u32,
    pub engine: Engine,
    /// Samples of light of at most one bounce per pixel sample, in the pixels where
    /// that light is noisy (lights' outlines, glossy highlights), which estimate it
    /// apart there (`split.rs`); 0: none.
    pub direct_split: u32,
}

impl RenderSettings {
    /// Split samples per pixel sample where light of few bounces is noisy: RMSE times
    /// time is lowest at 8 on CBbunny_microfacet_cu `-m 5` (4 to 16 within 5 %), and
    /// CBbunny's error is within 2 % of 16's (BENCHMARKS §3).
    pub const DEFAULT_DIRECT_SPLIT: u32 = 8;

    /// The direct-lighting estimator these settings use for `scene`.
    pub fn strategy_for(&self, scene: &Scene) -> DirectStrategy {
        self.strategy
            .unwrap_or_else(|| DirectStrategy::auto_for(scene))
    }

    /// Why these settings must render one path at a time, if they must: every radiance
    /// render (path or light tracing) runs in packets.
    pub fn packet_blocker(&self) -> Option<&'static str> {
        if self.shading != Shading::Radiance {
            return Some("debug shading (--shading)");
        }
        None
    }

    /// Whether renders with these settings run in packets.
    pub fn uses_packets(&self) -> bool {
        self.engine != Engine::Scalar && self.packet_blocker().is_none()
    }

    pub fn path_settings(&self, scene: &Scene) -> PathSettings {
        PathSettings {
            max_depth: self.max_depth,
            accumulate: self.accumulate,
            light_samples: self.light_samples,
            strategy: self.strategy_for(scene),
            roulette: self.roulette,
            sampler: self.sampler,
            caustics_by_light: false,
        }
    }

    /// What an estimator over `scene`, `accel` and `camera` is given with these settings.
    pub fn tracing<'a>(
        &self,
        scene: &'a Scene,
        accel: &'a dyn Accel,
        camera: &'a Camera,
    ) -> Tracing<'a> {
        Tracing {
            scene,
            accel,
            camera,
            s: self.path_settings(scene),
            engine: self.engine(),
            seed: self.seed,
        }
    }

    /// The engine that runs paths with these settings.
    fn engine(&self) -> Engine {
        if self.uses_packets() {
            Engine::Packet
        } else {
            Engine::Scalar
        }
    }
}

impl Default for RenderSettings {
    fn default() -> Self {
        RenderSettings {
            spp: 1,
            light_samples: 1,
            max_depth: 1,
            accumulate: true,
            estimator: Some(Estimator::Path),
            strategy: Some(DirectStrategy::Light),
            roulette: Roulette::default(),
            adaptive: None,
            shading: Shading::Radiance,
            seed: 0,
            sampler: SamplerKind::default(),
            spp_offset: 0,
            engine: Engine::Auto,
            direct_split: RenderSettings::DEFAULT_DIRECT_SPLIT,
        }
    }
}

pub struct RenderOutput {
    pub image: Image,
    /// Samples taken per pixel (differs from spp only with adaptive sampling).
    pub samples: Vec<u32>,
    /// Samples whose radiance was NaN or infinite and were counted as black (should be 0).
    pub nonfinite_samples: u64,
    /// Pixels whose light of few bounces had samples of its own (`split.rs`); in a
    /// render of passes, the most of any pass.
    pub split_pixels: u64,
}

impl RenderOutput {
    pub fn total_samples(&self) -> u64 {
        self.samples.iter().map(|&s| s as u64).sum()
    }

    /// This render of pixels `rect` placed in a black `width × height` frame (no samples
    /// outside `rect`), as a full-size image of one cell.
    pub fn into_frame(self, rect: PixelRect, width: u32, height: u32) -> RenderOutput {
        let mut image = Image::new(width, height);
        let mut samples = vec![0u32; (width * height) as usize];
        for y in rect.y0..rect.y1 {
            let src = ((y - rect.y0) * rect.width()) as usize;
            let dst = (y * width + rect.x0) as usize;
            let n = rect.width() as usize;
            image.pixels[dst..dst + n].copy_from_slice(&self.image.pixels[src..src + n]);
            samples[dst..dst + n].copy_from_slice(&self.samples[src..src + n]);
        }
        RenderOutput {
            image,
            samples,
            ..self
        }
    }

    /// The course's sample-rate image: blue few samples, red many (relative to spp).
    pub fn rate_image(&self, spp: u32) -> Image {
        let counts: Vec<f32> = self.samples.iter().map(|&s| s as f32).collect();
        heat_map(self.image.width, self.image.height, &counts, spp as f32)
    }

    /// The raw samples per pixel, in every channel (the rate map as data, for EXR).
    pub fn sample_count_image(&self) -> Image {
        Image {
            pixels: self
                .samples
                .iter()
                .map(|&s| Color::splat(s as f32))
                .collect(),
            ..self.image.clone()
        }
    }

    /// For `Shading::BvhCost`: the heat map (blue 0, red `scale`) and the scale, which
    /// is the 99th percentile of the pixels' counts unless given (a fixed scale lets
    /// images of two builders compare).
    pub fn cost_heat_map(&self, scale: Option<f32>) -> (Image, f32) {
        let costs: Vec<f32> = self.image.pixels.iter().map(|c| c.x).collect();
        let scale = scale.unwrap_or_else(|| percentile(&costs, 0.99).max(1.0));
        (
            heat_map(self.image.width, self.image.height, &costs, scale),
            scale,
        )
    }

    /// For `Shading::BvhCost`: the mean count per camera ray (pixels weighted by their rays).
    pub fn mean_cost_per_ray(&self) -> f64 {
        let rays = self.total_samples().max(1) as f64;
        let pixels = self.image.pixels.iter().zip(&self.samples);
        pixels.map(|(c, &n)| c.x as f64 * n as f64).sum::<f64>() / rays
    }
}

/// Renders pixels `rect` of `job`. `progress` is called with the number of pixels finished.
/// Once `stop` says so, the remaining pixels are left black with 0 samples.
fn render_rect(
    job: &RenderJob,
    settings: &RenderSettings,
    rect: PixelRect,
    progress: &(dyn Fn(u64) + Sync),
    stop: &StopToken,
) -> RenderOutput {
    let (scene, accel, camera) = (&job.scene, job.accel.as_ref(), &job.camera);
    let frame = (camera.width, camera.height);
    // The pixel loop over `rect` with these settings.
    let pixels = |integrator: &dyn SampleIntegrator,
                  split: Option<&DirectSplit>,
                  adaptive: Option<Adaptive>,
                  progress: &(dyn Fn(u64) + Sync)| {
        pixels::render(
            integrator, split, settings, adaptive, frame, rect, progress, stop,
        )
    };
    let view = match settings.shading {
        Shading::Radiance => None,
        Shading::Normals => Some(View::Normals),
        Shading::BvhCost => Some(View::TraversalCost),
    };
    if let Some(view) = view {
        let debug = DebugView {
            scene,
            accel,
            camera,
            view,
            seed: settings.seed,
            sampler: settings.sampler,
        };
        return pixels(&debug, None, None, progress);
    }
    let mut t = settings.tracing(scene, accel, camera);
    match job.estimator(settings) {
        Estimator::LightTracing => {
            let tracer = LightTracer::new(t);
            let paths = splats::paths_per_pixel(camera, settings.spp.max(1));
            // Its camera part (emitters seen directly) splits them too.
            let split = DirectSplit::new(t, settings.direct_split, 0);
            splats::render(&tracer, split.as_ref(), camera, paths, rect, progress, stop)
        }
        Estimator::Path => {
            let integrator = PathIntegrator::new(t);
            let split = DirectSplit::new(t, settings.direct_split, MAX_SPLIT_BOUNCES);
            pixels(&integrator, split.as_ref(), settings.adaptive, progress)
        }
        Estimator::Caustics => {
            t.s.caustics_by_light = true;
            let integrator = PathIntegrator::new(t);
            let direct = DirectSplit::new(t, settings.direct_split, MAX_SPLIT_BOUNCES);
            let direct = direct.as_ref();
            // Nothing to add where no light path can make a caustic (CMU462's glass
            // and mirror spheres, with no other surface to receive one).
            let Some((split, _)) = job.caustics_split(settings) else {
                return pixels(&integrator, direct, None, progress);
            };
            let tracer = LightTracer::new(t);
            let camera_share = ProgressShare::new(progress, split.light_rays, false);
            let light_share = ProgressShare::new(progress, split.light_rays, true);
            let camera_progress = |n| camera_share.report(n);
            let mut out = pixels(&integrator, direct, None, &camera_progress);
            let paths = caustic_paths(settings, camera, split.divisor);
            let light_progress = |n| light_share.report(n);
            // No camera part: the camera samples above saw the emitters.
            let none = None;
            let caustics =
                splats::render(&tracer, none, camera, paths, rect, &light_progress, stop);
            for (p, c) in out.image.pixels.iter_mut().zip(&caustics.image.pixels) {
                *p += *c;
            }
            out.nonfinite_samples += caustics.nonfinite_samples;
            out
        }
    }
}

/// One part of a render of two parts, each counting the whole render's pixels: the
/// light paths report their predicted share of the rays (`CausticsSplit`) and the
/// camera samples the rest, so the bar moves through both as the time does and the
/// two add up to the render's count.
struct ProgressShare<'a> {
    progress: &'a (dyn Fn(u64) + Sync),
    reported: AtomicU64,
    /// The camera samples' share, in millionths.
    camera_ppm: u64,
    light: bool,
}

impl<'a> ProgressShare<'a> {
    fn new(progress: &'a (dyn Fn(u64) + Sync), light_share: f64, light: bool) -> Self {
        ProgressShare {
            progress,
            reported: AtomicU64::new(0),
            camera_ppm: ((1.0 - light_share.clamp(0.0, 1.0)) * 1e6).round() as u64,
            light,
        }
    }

    /// Of `n` pixels counted so far, how many this part reports: monotone in `n`.
    fn share(&self, n: u64) -> u64 {
        let camera = (u128::from(n) * u128::from(self.camera_ppm) / 1_000_000) as u64;
        if self.light {
            n - camera
        } else {
            camera
        }
    }

    fn report(&self, n: u64) {
        let before = self.reported.fetch_add(n, Ordering::Relaxed);
        (self.progress)(self.share(before + n) - self.share(before));
    }
}

/// The light paths of `Estimator::Caustics` for the camera samples `settings` takes:
/// one path per `divisor` pixels for each sample index, numbered by it, so the
/// renders of disjoint sample ranges (`spp_offset`) merge into the render of all of
/// them. The divisor is the caustics pilot's (`pilot::CausticsSplit`), the same for
/// every render of a job and its settings.
fn caustic_paths(settings: &RenderSettings, camera: &Camera, divisor: u32) -> std::ops::Range<u64> {
    let per_sample = splats::pixel_count(camera).div_ceil(u64::from(divisor.max(1)));
    let first = u64::from(settings.spp_offset);
    first * per_sample..(first + u64::from(settings.spp)) * per_sample
}

fn percentile(v: &[f32], q: f32) -> f32 {
    let mut s: Vec<f32> = v.iter().copied().filter(|x| x.is_finite()).collect();
    if s.is_empty() {
        return 0.0;
    }
    s.sort_by(|a, b| a.total_cmp(b));
    s[((s.len() - 1) as f32 * q) as usize]
}

/// Cases where the chosen estimator cannot converge to the right image, said out loud.
fn render_warnings(job: &RenderJob, s: &RenderSettings) -> Vec<String> {
    let scene = &job.scene;
    let light_tracing = job.estimator(s) == Estimator::LightTracing;
    let mut w = if light_tracing && s.shading == Shading::Radiance {
        light_tracing::warnings(scene, s.max_depth)
    } else {
        Vec::new()
    };
    if light_tracing && s.adaptive.is_some() {
        w.push("adaptive sampling (-a) does not apply to light tracing: ignored".into());
    }
    let blind = match s.strategy_for(scene) {
        _ if light_tracing => None,
        DirectStrategy::Hemisphere => Some("hemisphere sampling (-H)"),
        DirectStrategy::Bsdf => Some("BSDF sampling alone"),
        DirectStrategy::Light | DirectStrategy::Mis | DirectStrategy::MisGlossy => None,
    };
    if let (Some(name), Shading::Radiance, true) = (blind, s.shading, s.max_depth > 0) {
        let delta = scene.lights.iter().filter(|l| l.is_delta()).count();
        if delta > 0 {
            w.push(format!(
                "{name} cannot reach the scene's {delta} point/directional light(s): \
                 their light is missing from this image; use light sampling or MIS"
            ));
        }
    }
    if s.shading == Shading::Radiance && !scene.has_emitting_surface() {
        w.extend(darkness_warning(scene));
    }
    w
}

/// A scene that nothing lights renders black: no lights at all, or lights that all
/// have zero power (the course's `*_unlit.dae` scenes, whose only light is an ambient
/// light of radiance 0, are meant for `-e`).
fn darkness_warning(scene: &Scene) -> Option<String> {
    let lights = &scene.lights;
    if lights.is_empty() {
        return Some(
            "the scene has no lights and no emissive surfaces: the image will be black".into(),
        );
    }
    if lights.iter().any(|l| l.power(1.0) > 0.0) {
        return None;
    }
    let kinds: Vec<&str> = lights.iter().map(|l| l.kind()).collect();
    let lights = match kinds.len() {
        1 => format!("its one light ({}) has zero power", kinds[0]),
        n => format!("its {n} lights ({}) all have zero power", kinds.join(", ")),
    };
    Some(format!(
        "no light in the scene emits anything ({lights}), so the image will be black; \
         light it with an environment map: -e FILE.exr"
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn progress_shares_add_up_to_the_count_in_any_order_of_reports() {
        let total = AtomicU64::new(0);
        let sink = |n| {
            total.fetch_add(n, Ordering::Relaxed);
        };
        let (camera, light) = (
            ProgressShare::new(&sink, 0.2, false),
            ProgressShare::new(&sink, 0.2, true),
        );
        for n in [1, 7, 3, 0, 9] {
            camera.report(n);
        }
        assert_eq!(total.load(Ordering::Relaxed), 20 * 4 / 5);
        for n in [2, 11, 7] {
            light.report(n);
        }
        assert_eq!(total.load(Ordering::Relaxed), 20);
    }
}
