//! The render driver: tiles over rayon, per-pixel deterministic sampling,
//! plain or adaptive sample counts.

use crate::accel::Accel;
use crate::camera::Camera;
use crate::color::{is_finite, luminance};
use crate::film::{heat_map, Image};
use crate::integrators::{
    debug, light_tracing, DirectStrategy, Estimator, PathIntegrator, PathSettings, Roulette,
};
use crate::sampling::Sampler;
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
    /// Heat map of BVH nodes + primitives tested per camera ray.
    BvhCost,
}

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
    /// `crate::adaptive` (default): a pixel of zeros only when its whole neighbourhood
    /// looked constant too; a constant non-zero pixel after `min_samples_if_constant`.
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

#[derive(Clone, Debug)]
pub struct RenderSettings {
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    pub light_samples: u32,
    pub max_depth: u32,
    pub accumulate: bool,
    /// Camera paths (with `strategy`) or light tracing.
    pub estimator: Estimator,
    pub strategy: DirectStrategy,
    pub roulette: Roulette,
    pub adaptive: Option<Adaptive>,
    pub shading: Shading,
    pub seed: u64,
}

impl RenderSettings {
    pub fn path_settings(&self) -> PathSettings {
        PathSettings {
            max_depth: self.max_depth,
            accumulate: self.accumulate,
            light_samples: self.light_samples,
            strategy: self.strategy,
            roulette: self.roulette,
        }
    }
}

impl Default for RenderSettings {
    fn default() -> Self {
        RenderSettings {
            width: 480,
            height: 360,
            spp: 1,
            light_samples: 1,
            max_depth: 1,
            accumulate: true,
            estimator: Estimator::Path,
            strategy: DirectStrategy::Light,
            roulette: Roulette::default(),
            adaptive: None,
            shading: Shading::Radiance,
            seed: 0,
        }
    }
}

pub struct RenderOutput {
    pub image: Image,
    /// Samples taken per pixel (differs from spp only with adaptive sampling).
    pub samples: Vec<u32>,
    /// Samples whose radiance was NaN or infinite and were counted as black (should be 0).
    pub nonfinite_samples: u64,
    /// For `Shading::BvhCost`: the count that maps to red.
    pub cost_scale: Option<f32>,
    /// Things the user should know about this render (e.g. lights a strategy cannot see).
    pub warnings: Vec<String>,
}

impl RenderOutput {
    pub fn total_samples(&self) -> u64 {
        self.samples.iter().map(|&s| s as u64).sum()
    }

    /// The course's sample-rate image: blue few samples, red many (relative to spp).
    pub fn rate_image(&self, spp: u32) -> Image {
        let counts: Vec<f32> = self.samples.iter().map(|&s| s as f32).collect();
        heat_map(self.image.width, self.image.height, &counts, spp as f32)
    }
}

const TILE: u32 = 16;

/// Renders `scene` through `accel`. `progress` is called with the number of pixels finished.
pub fn render(
    scene: &Scene,
    accel: &dyn Accel,
    camera: &Camera,
    settings: &RenderSettings,
    progress: &(dyn Fn(u64) + Sync),
) -> RenderOutput {
    if settings.estimator == Estimator::LightTracing && settings.shading == Shading::Radiance {
        return light_tracing::render(scene, accel, camera, settings, progress);
    }
    if let Some(a) = settings
        .adaptive
        .filter(|a| a.rule == StopRule::Neighbourhood && settings.shading == Shading::Radiance)
    {
        return crate::adaptive::render(scene, accel, camera, settings, a, progress);
    }
    let (w, h) = (settings.width, settings.height);
    let tiles: Vec<(u32, u32)> = (0..h.div_ceil(TILE))
        .flat_map(|ty| (0..w.div_ceil(TILE)).map(move |tx| (tx, ty)))
        .collect();
    let integrator = PathIntegrator::new(scene, accel, settings.path_settings());
    let results: Vec<Vec<PixelResult>> = tiles
        .par_iter()
        .map(|&(tx, ty)| {
            let mut out = Vec::with_capacity((TILE * TILE) as usize);
            for y in ty * TILE..((ty + 1) * TILE).min(h) {
                for x in tx * TILE..((tx + 1) * TILE).min(w) {
                    out.push(render_pixel(
                        scene,
                        accel,
                        camera,
                        settings,
                        &integrator,
                        x,
                        y,
                    ));
                }
            }
            progress(out.len() as u64);
            out
        })
        .collect();
    assemble(&tiles, results, settings, scene)
}

struct PixelResult {
    value: Color,
    samples: u32,
    nonfinite: u32,
}

fn render_pixel(
    scene: &Scene,
    accel: &dyn Accel,
    camera: &Camera,
    s: &RenderSettings,
    integrator: &PathIntegrator,
    x: u32,
    y: u32,
) -> PixelResult {
    let mut sampler = Sampler::new(s.seed, (y as u64) * (s.width as u64) + x as u64, 0);
    let (mut sum, mut s1, mut s2) = (Color::ZERO, 0f64, 0f64);
    let (mut n, mut nonfinite) = (0u32, 0u32);
    let batch = s.adaptive.map_or(s.spp.max(1), |a| a.batch);
    while n < s.spp.max(1) {
        for _ in 0..batch.min(s.spp.max(1) - n) {
            let ray = camera.generate_ray(x, y, sampler.next_2d());
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

fn assemble(
    tiles: &[(u32, u32)],
    results: Vec<Vec<PixelResult>>,
    s: &RenderSettings,
    scene: &Scene,
) -> RenderOutput {
    let (w, h) = (s.width, s.height);
    let mut image = Image::new(w, h);
    let mut samples = vec![0u32; (w * h) as usize];
    let mut nonfinite = 0u64;
    for (&(tx, ty), tile) in tiles.iter().zip(results) {
        let mut it = tile.into_iter();
        for y in ty * TILE..((ty + 1) * TILE).min(h) {
            for x in tx * TILE..((tx + 1) * TILE).min(w) {
                let p = it.next().expect("tile pixel count");
                let i = (y * w + x) as usize;
                image.pixels[i] = p.value;
                samples[i] = p.samples;
                nonfinite += p.nonfinite as u64;
            }
        }
    }
    let mut cost_scale = None;
    if s.shading == Shading::BvhCost {
        let costs: Vec<f32> = image.pixels.iter().map(|c| c.x).collect();
        let scale = percentile(&costs, 0.99).max(1.0);
        image = heat_map(w, h, &costs, scale);
        cost_scale = Some(scale);
    }
    RenderOutput {
        image,
        samples,
        nonfinite_samples: nonfinite,
        cost_scale,
        warnings: render_warnings(scene, s),
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
pub fn render_warnings(scene: &Scene, s: &RenderSettings) -> Vec<String> {
    let mut w = light_tracing::warnings(scene, s);
    let blind = match s.strategy {
        _ if s.estimator == Estimator::LightTracing => None,
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
        && !scene
            .materials
            .iter()
            .any(|m| matches!(m, crate::materials::Material::Emission { .. }))
    {
        w.push("the scene has no lights and no emissive surfaces: the image will be black".into());
    }
    w
}
