//! The render driver: tiles over rayon, per-pixel deterministic sampling,
//! plain or adaptive sample counts. `RenderJob` (job.rs) owns what is rendered.

mod job;
mod memory;
mod progressive;
mod stop;

pub use job::{average, Halves, PixelRect, RenderJob};
pub use memory::{available_bytes, render_bytes};
pub use progressive::{pass_seed, pass_spp, render_passes, Film};
pub use stop::{StopReason, StopToken};

use crate::camera::Camera;
use crate::color::{is_finite, luminance};
use crate::film::{heat_map, Image};
use crate::integrators::packet::{PacketPathIntegrator, TileWork};
use crate::integrators::{
    debug, light_tracing, DirectStrategy, Estimator, PathIntegrator, PathSettings, Roulette,
};
use crate::names::{display_from_table, Named};
use crate::sampling::PixelStreams;
use crate::scene::Scene;
use crate::Color;
use rayon::prelude::*;

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

/// How camera paths run on the CPU. The image is the same bit for bit either way
/// (`integrators::packet`); only the speed differs.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Engine {
    /// Packets wherever the render allows them ([`RenderSettings::packet_blocker`]).
    #[default]
    Auto,
    /// One path at a time.
    Scalar,
    /// Sixteen paths at a time, one per SIMD lane; renders the engine cannot run
    /// are refused by the CLI (a library caller gets the scalar engine).
    Packet,
}

impl Named for Engine {
    const WHAT: &'static str = "engine";
    const TABLE: &'static [(Self, &'static str, &'static str)] = &[
        (
            Engine::Auto,
            "auto",
            "Sixteen paths per SIMD pass where the render allows (Lambertian surfaces, area lights, pinhole, light sampling or MIS, no -a), else one at a time",
        ),
        (Engine::Scalar, "scalar", "One path at a time"),
        (
            Engine::Packet,
            "packet",
            "Sixteen paths per SIMD pass (AVX-512, AVX2 or portable code); an error where the render needs the scalar engine",
        ),
    ];
}
display_from_table!(Engine);

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
    /// `crate::adaptive` (default): a pixel of zeros after a count set by how often its
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
    /// Camera paths (with `strategy`) or light tracing; `None` chooses for the scene
    /// (`Estimator::auto_for`).
    pub estimator: Option<Estimator>,
    /// Direct-lighting estimator of camera paths; `None` chooses one for the scene
    /// (`DirectStrategy::auto_for`) where the integrator is built.
    pub strategy: Option<DirectStrategy>,
    pub roulette: Roulette,
    pub adaptive: Option<Adaptive>,
    pub shading: Shading,
    pub seed: u64,
    /// Index of the first sample of every pixel: a render takes samples
    /// `spp_offset .. spp_offset + spp`, so renders of disjoint sample ranges (sample
    /// shards, `--spp-offset`) merge into one render of all of them. Not with `adaptive`.
    pub spp_offset: u32,
    pub engine: Engine,
}

impl RenderSettings {
    /// Which way these settings build paths in `scene`.
    pub fn estimator_for(&self, scene: &Scene) -> Estimator {
        self.estimator.unwrap_or_else(|| Estimator::auto_for(scene))
    }

    /// The direct-lighting estimator these settings use for `scene`.
    pub fn strategy_for(&self, scene: &Scene) -> DirectStrategy {
        self.strategy
            .unwrap_or_else(|| DirectStrategy::auto_for(scene))
    }

    /// Why these settings must render `job` one path at a time, if they must: the
    /// packet engine covers plain radiance renders by path tracing of what
    /// `packet::unsupported` accepts.
    pub fn packet_blocker(&self, scene: &Scene, camera: &Camera) -> Option<&'static str> {
        if self.shading != Shading::Radiance {
            return Some("debug shading (--shading)");
        }
        if self.adaptive.is_some() {
            return Some("adaptive sampling (-a)");
        }
        if self.estimator_for(scene) != Estimator::Path {
            return Some("light tracing");
        }
        crate::integrators::packet::unsupported(scene, camera, &self.path_settings(scene))
    }

    /// Whether `job` renders by packets with these settings.
    pub fn uses_packets(&self, job: &RenderJob) -> bool {
        self.engine != Engine::Scalar && self.packet_blocker(&job.scene, &job.camera).is_none()
    }

    pub fn path_settings(&self, scene: &Scene) -> PathSettings {
        PathSettings {
            max_depth: self.max_depth,
            accumulate: self.accumulate,
            light_samples: self.light_samples,
            strategy: self.strategy_for(scene),
            roulette: self.roulette,
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
            spp_offset: 0,
            engine: Engine::Auto,
        }
    }
}

pub struct RenderOutput {
    pub image: Image,
    /// Samples taken per pixel (differs from spp only with adaptive sampling).
    pub samples: Vec<u32>,
    /// Samples whose radiance was NaN or infinite and were counted as black (should be 0).
    pub nonfinite_samples: u64,
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

const TILE: u32 = 16;
const TILE_PIXELS: usize = (TILE * TILE) as usize;

/// The tiles covering `rect`, as their top-left pixels, in a scattered order: every
/// stretch of the list samples the whole image, so progress (and its ETA) measured in
/// pixels tracks the work, and a stopped render is spread over the frame, not
/// a band of background at the top. The image does not depend on the order.
fn tiles(rect: PixelRect) -> Vec<(u32, u32)> {
    let rows: Vec<(u32, u32)> = (rect.y0..rect.y1)
        .step_by(TILE as usize)
        .flat_map(|y| {
            (rect.x0..rect.x1)
                .step_by(TILE as usize)
                .map(move |x| (x, y))
        })
        .collect();
    scattered(rows.len()).map(|i| rows[i]).collect()
}

/// `0..n` in a scattered order (every index once): work scheduled in this order
/// samples the whole image early, so progress measured in pixels tracks the work.
pub(crate) fn scattered(n: usize) -> impl Iterator<Item = usize> {
    let stride = scatter_stride(n);
    (0..n).map(move |i| i * stride % n)
}

/// A step near `n / φ` with no factor in common with `n`, so `i · step mod n` visits
/// every index once, jumping across the image.
fn scatter_stride(n: usize) -> usize {
    let gcd = |mut a: usize, mut b: usize| {
        while b != 0 {
            (a, b) = (b, a % b);
        }
        a
    };
    (((n as f64) * 0.618_034) as usize..n.max(1))
        .find(|&s| s > 0 && gcd(s, n) == 1)
        .unwrap_or(1)
}

/// The pixels of the tile at `(x0, y0)` inside `rect`, row by row.
fn tile_pixels(rect: PixelRect, (x0, y0): (u32, u32)) -> impl Iterator<Item = (u32, u32)> {
    (y0..(y0 + TILE).min(rect.y1))
        .flat_map(move |y| (x0..(x0 + TILE).min(rect.x1)).map(move |x| (x, y)))
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
    if settings.shading == Shading::Radiance {
        if settings.estimator_for(&job.scene) == Estimator::LightTracing {
            return light_tracing::render(job, settings, rect, progress, stop);
        }
        if let Some(a) = settings
            .adaptive
            .filter(|a| a.rule == StopRule::Neighbourhood)
        {
            return crate::adaptive::render(job, settings, a, rect, progress, stop);
        }
    }
    let tiles = tiles(rect);
    if settings.uses_packets(job) {
        let packet = PacketPathIntegrator::new(
            &job.scene,
            job.accel.as_ref(),
            &job.camera,
            settings.path_settings(&job.scene),
        );
        if let Some(packet) = packet {
            return render_packets(&packet, settings, rect, &tiles, progress, stop);
        }
    }
    let integrator = PathIntegrator::new(
        &job.scene,
        job.accel.as_ref(),
        settings.path_settings(&job.scene),
    );
    // Every tile's slot is allocated up front, so memory does not grow while rendering.
    let mut results = vec![PixelResult::NOT_RENDERED; tiles.len() * TILE_PIXELS];
    results
        .par_chunks_mut(TILE_PIXELS)
        .zip(tiles.par_iter())
        .for_each(|(slots, &tile)| {
            let mut n = 0;
            for (slot, (x, y)) in slots.iter_mut().zip(tile_pixels(rect, tile)) {
                if stop.should_stop() {
                    break;
                }
                *slot = render_pixel(job, settings, &integrator, x, y);
                n += 1;
            }
            progress(n);
        });
    assemble(rect, &tiles, &results)
}

/// `render_rect` by the packet engine: each tile's pixels, all their samples.
fn render_packets(
    packet: &PacketPathIntegrator,
    settings: &RenderSettings,
    rect: PixelRect,
    tiles: &[(u32, u32)],
    progress: &(dyn Fn(u64) + Sync),
    stop: &StopToken,
) -> RenderOutput {
    let spp = settings.spp.max(1);
    let mut results = vec![PixelResult::NOT_RENDERED; tiles.len() * TILE_PIXELS];
    let should_stop = || stop.should_stop();
    results
        .par_chunks_mut(TILE_PIXELS)
        .zip(tiles.par_iter())
        .for_each(|(slots, &tile)| {
            let pixels: Vec<(u32, u32)> = tile_pixels(rect, tile).collect();
            let mut sums = vec![None; pixels.len()];
            let work = TileWork {
                pixels: &pixels,
                spp,
                spp_offset: settings.spp_offset,
                seed: settings.seed,
                stop: &should_stop,
            };
            packet.render_tile(&work, &mut sums);
            let mut n = 0;
            for (slot, sum) in slots.iter_mut().zip(sums) {
                if let Some(p) = sum {
                    *slot = PixelResult {
                        value: p.sum / spp as f32,
                        samples: spp,
                        nonfinite: p.nonfinite,
                    };
                    n += 1;
                }
            }
            progress(n);
        });
    assemble(rect, tiles, &results)
}

#[derive(Clone, Copy)]
struct PixelResult {
    value: Color,
    samples: u32,
    nonfinite: u32,
}

impl PixelResult {
    /// A pixel skipped because the render was stopped.
    const NOT_RENDERED: PixelResult = PixelResult {
        value: Color::ZERO,
        samples: 0,
        nonfinite: 0,
    };
}

fn render_pixel(
    job: &RenderJob,
    s: &RenderSettings,
    integrator: &PathIntegrator,
    x: u32,
    y: u32,
) -> PixelResult {
    let (camera, scene, accel) = (&job.camera, &job.scene, job.accel.as_ref());
    let pixel = (y as u64) * (camera.width as u64) + x as u64;
    let (mut sum, mut s1, mut s2) = (Color::ZERO, 0f64, 0f64);
    let (mut n, mut nonfinite) = (0u32, 0u32);
    let batch = s.adaptive.map_or(s.spp.max(1), |a| a.batch);
    let streams = PixelStreams::new(s.seed, pixel);
    while n < s.spp.max(1) {
        for _ in 0..batch.min(s.spp.max(1) - n) {
            let index = s.spp_offset as u64 + n as u64;
            let mut sampler = streams.sample(index);
            let ray = camera.sample_ray(x, y, &mut sampler);
            let mut v = match s.shading {
                Shading::Radiance => integrator.li(ray, &mut sampler),
                Shading::Normals => debug::normal_color(scene, accel, &ray),
                Shading::BvhCost => Color::splat(debug::traversal_cost(accel, &ray)),
            };
            if !is_finite(v) {
                nonfinite += 1;
                v = Color::ZERO;
            }
            sum += v;
            let lum = luminance(v) as f64;
            s1 += lum;
            s2 += lum * lum;
            n += 1;
        }
        if let Some(a) = s.adaptive {
            if converged(a, n, s1, s2) {
                break;
            }
        }
    }
    PixelResult {
        value: sum / n as f32,
        samples: n,
        nonfinite,
    }
}

/// The spec's stopping rule, plus a minimum count for pixels that look constant.
fn converged(a: Adaptive, n: u32, s1: f64, s2: f64) -> bool {
    if n < 2 {
        return false;
    }
    let nf = n as f64;
    let mu = s1 / nf;
    let var = ((s2 - s1 * s1 / nf) / (nf - 1.0)).max(0.0);
    if var == 0.0 && n < a.min_samples_if_constant {
        return false;
    }
    1.96 * var.sqrt() / nf.sqrt() <= a.tol as f64 * mu
}

/// The image of `rect` (its own size, row-major) from the tiles' pixels.
fn assemble(rect: PixelRect, tiles: &[(u32, u32)], results: &[PixelResult]) -> RenderOutput {
    let (w, h) = (rect.width(), rect.height());
    let mut image = Image::new(w, h);
    let mut samples = vec![0u32; (w * h) as usize];
    let mut nonfinite = 0u64;
    for (&tile, pixels) in tiles.iter().zip(results.chunks(TILE_PIXELS)) {
        for ((x, y), p) in tile_pixels(rect, tile).zip(pixels) {
            let i = ((y - rect.y0) * w + (x - rect.x0)) as usize;
            image.pixels[i] = p.value;
            samples[i] = p.samples;
            nonfinite += p.nonfinite as u64;
        }
    }
    RenderOutput {
        image,
        samples,
        nonfinite_samples: nonfinite,
    }
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
fn render_warnings(scene: &Scene, s: &RenderSettings) -> Vec<String> {
    let light_tracing = s.estimator_for(scene) == Estimator::LightTracing;
    let mut w = if light_tracing {
        light_tracing::warnings(scene, s)
    } else {
        Vec::new()
    };
    let blind = match s.strategy_for(scene) {
        _ if light_tracing => None,
        DirectStrategy::Hemisphere => Some("hemisphere sampling (-H)"),
        DirectStrategy::Bsdf => Some("BSDF sampling alone"),
        DirectStrategy::Light | DirectStrategy::Mis => None,
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
    if s.shading == Shading::Radiance
        && scene.lights.is_empty()
        && !scene.materials.iter().any(|m| m.flags().emissive)
    {
        w.push("the scene has no lights and no emissive surfaces: the image will be black".into());
    }
    w
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scattered_tiles_cover_every_tile_once_and_jump_across_the_image() {
        for (w, h) in [(1, 1), (16, 16), (480, 360), (100, 37)] {
            let rect = PixelRect::full(w, h);
            let t = tiles(rect);
            let mut sorted = t.clone();
            sorted.sort_unstable();
            sorted.dedup();
            assert_eq!(sorted.len(), t.len());
            assert_eq!(t.len() as u32, w.div_ceil(TILE) * h.div_ceil(TILE));
        }
        // The first tenth of a 480x360 frame's tiles reaches its bottom half.
        let t = tiles(PixelRect::full(480, 360));
        assert!(t[..t.len() / 10].iter().any(|&(_, y)| y >= 180));
    }
}
