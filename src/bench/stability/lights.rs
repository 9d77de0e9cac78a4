//! Cases 1–3: where one direct-lighting estimator fails and another does not.
//! Point lights are invisible to every estimator that waits for a ray to hit a light;
//! small lights make such estimators noisy; glossy lobes make light sampling noisy.

use super::measure::{z_score, Budget, Halves};
use super::scenes::embedded;
use super::Row;
use crate::color::luminance;
use crate::integrators::{DirectStrategy, Roulette};
use crate::lights::{AreaLight, Light};
use crate::materials::Bsdf;
use crate::names::Named;
use crate::render::{RenderJob, RenderSettings};
use crate::scene::Scene;
use anyhow::{bail, Result};
use std::f64::consts::PI;

/// The four direct-lighting strategies, in report order (named by their `Display`).
pub const STRATEGIES: [DirectStrategy; 4] = [
    DirectStrategy::Hemisphere,
    DirectStrategy::Bsdf,
    DirectStrategy::Light,
    DirectStrategy::Mis,
];

fn direct(strategy: DirectStrategy) -> RenderSettings {
    RenderSettings {
        max_depth: 1,
        strategy: Some(strategy),
        roulette: Roulette::Off,
        ..Default::default()
    }
}

/// One strategy's render of a case.
#[derive(Clone, Debug)]
pub struct StrategyRun {
    pub strategy: DirectStrategy,
    pub name: &'static str,
    pub mean: f64,
    pub se: f64,
    /// RMS noise of one pixel (luminance).
    pub noise: f64,
    pub max_pixel: f64,
    pub warnings: Vec<String>,
    pub nonfinite: u64,
}

impl StrategyRun {
    pub(super) fn from_halves(
        strategy: DirectStrategy,
        h: &Halves,
        warnings: Vec<String>,
    ) -> StrategyRun {
        let (mean, se) = h.mean_and_se(None);
        let avg = h.average();
        let max_pixel = avg
            .pixels
            .iter()
            .map(|p| luminance(*p) as f64)
            .fold(0.0, f64::max);
        StrategyRun {
            strategy,
            name: strategy.name(),
            mean,
            se,
            noise: h.noise_per_pixel(),
            max_pixel,
            warnings,
            nonfinite: h.nonfinite(),
        }
    }

    pub fn row(&self, case: &str, expected: Option<f64>, note: String) -> Row {
        Row {
            case: case.into(),
            method: self.name.into(),
            mean: self.mean,
            stderr: self.se,
            expected,
            noise: self.noise,
            nonfinite: self.nonfinite,
            note,
        }
    }
}

/// The run of `strategy` (every case runs a fixed list, so it is there).
fn find_run(runs: &[StrategyRun], strategy: DirectStrategy) -> &StrategyRun {
    runs.iter()
        .find(|r| r.strategy == strategy)
        .expect("strategy run")
}

fn run_all(setup: &RenderJob, b: &Budget, strategies: &[DirectStrategy]) -> Vec<StrategyRun> {
    strategies
        .iter()
        .map(|&s| {
            let settings = b.settings(direct(s));
            let warnings = setup.warnings(&settings);
            StrategyRun::from_halves(s, &setup.halves(&settings), warnings)
        })
        .collect()
}

/// Case 1: a point light seen by each strategy, and the closed-form image mean.
pub struct PointLightCase {
    pub runs: Vec<StrategyRun>,
    /// Image mean of `ρ/π·I·cosθ/d²` by 16×16 quadrature per pixel.
    pub expected_mean: f64,
}

pub fn point_light(b: &Budget) -> Result<PointLightCase> {
    let setup = b.job(embedded("point_light.dae")?)?;
    let runs = run_all(&setup, b, &STRATEGIES);
    let expected_mean = point_light_image_mean(&setup)?;
    Ok(PointLightCase {
        runs,
        expected_mean,
    })
}

/// Direct light from the scene's point light on its Lambertian surfaces, averaged over
/// a 16×16 grid in every pixel (the scene has no occluders).
fn point_light_image_mean(setup: &RenderJob) -> Result<f64> {
    let Some(&Light::Point {
        position,
        intensity,
    }) = setup.scene.lights.first()
    else {
        bail!("point_light.dae: no point light")
    };
    let (w, h, k) = (setup.camera.width, setup.camera.height, 16u32);
    let mut sum = 0.0f64;
    for y in 0..h {
        for x in 0..w {
            for s in 0..k * k {
                let xi = glam::Vec2::new(
                    ((s % k) as f32 + 0.5) / k as f32,
                    ((s / k) as f32 + 0.5) / k as f32,
                );
                let ray = setup.camera.generate_ray(x, y, xi);
                let Some(hit) = setup.accel.intersect(&ray) else {
                    continue;
                };
                let si = setup.scene.interaction(&ray, &hit);
                let Bsdf::Lambertian(b) = setup.scene.materials[si.material as usize].bsdf else {
                    continue;
                };
                let albedo = b.albedo.vec3();
                let to = position - si.p;
                let cos = (to.normalize().dot(si.ng)).abs();
                let lo = albedo / std::f32::consts::PI * intensity * cos / to.length_squared();
                sum += luminance(lo) as f64;
            }
        }
    }
    Ok(sum / (w * h * k * k) as f64)
}

impl PointLightCase {
    pub fn rows(&self) -> Vec<Row> {
        let case = "1 point light";
        self.runs
            .iter()
            .map(|r| {
                let note = if r.warnings.is_empty() {
                    format!(
                        "sees the light; mean/expected = {:.4}",
                        r.mean / self.expected_mean
                    )
                } else {
                    format!(
                        "black image (max pixel {:.1e}); ember warns: {}",
                        r.max_pixel,
                        r.warnings.join("; ")
                    )
                };
                r.row(case, Some(self.expected_mean), note)
            })
            .collect()
    }
}

/// Case 2: a small light (the file's 0.1 × 0.1, scaled by `size`, radiance scaled by
/// `1/size²` so the irradiance stays put).
pub struct SmallLightCase {
    pub size: f32,
    /// Solid angle of the light from the floor point straight below it: the largest
    /// it subtends anywhere on the floor.
    pub max_solid_angle: f64,
    pub runs: Vec<StrategyRun>,
}

impl SmallLightCase {
    /// Lower bound on noise(hemisphere)/noise(light) at equal spp. Uniform hemisphere
    /// sampling hits a light of solid angle Ω with probability p ≤ Ω/2π; a hit scores
    /// about μ/p, a miss 0, so its relative standard deviation per sample is at least
    /// √(1/p − 1) ≥ √(2π/Ω − 1). Light sampling of a small light scores nearly μ every
    /// time (relative deviation ≪ 1: only cos·cos'/d² varies over the light).
    pub fn predicted_min_ratio(&self) -> f64 {
        (2.0 * PI / self.max_solid_angle - 1.0).sqrt()
    }

    pub fn run(&self, strategy: DirectStrategy) -> &StrategyRun {
        find_run(&self.runs, strategy)
    }

    pub fn rows(&self) -> Vec<Row> {
        let case = format!("2 small light {:.3}", 0.1 * self.size);
        let light = self.run(DirectStrategy::Light).clone();
        self.runs
            .iter()
            .map(|r| {
                let note = format!(
                    "noise ×{:.1} of light sampling (hemisphere bound √(2π/Ω−1) = {:.1}); {:.1} σ from light sampling's mean",
                    r.noise / light.noise,
                    self.predicted_min_ratio(),
                    z_score((r.mean, r.se), (light.mean, light.se))
                );
                r.row(&case, None, note)
            })
            .collect()
    }
}

pub fn small_light(b: &Budget, size: f32) -> Result<SmallLightCase> {
    let scene = scale_area_lights(embedded("small_light.dae")?, size);
    let Some(&Light::Area(AreaLight { centre, ex, ey, .. })) = scene.lights.first() else {
        bail!("small_light.dae: no area light")
    };
    let h = centre.y as f64; // the floor is y = 0
    let max_solid_angle = ex.cross(ey).length() as f64 / (h * h);
    let setup = b.job(scene)?;
    Ok(SmallLightCase {
        size,
        max_solid_angle,
        runs: run_all(&setup, b, &STRATEGIES),
    })
}

/// Every area light (and its emitting triangles) scaled by `k` about its centre, its
/// radiance by `1/k²`: the same power from a smaller or larger source.
pub fn scale_area_lights(mut scene: Scene, k: f32) -> Scene {
    for li in 0..scene.lights.len() as u32 {
        let Some(&a) = scene.lights[li as usize].as_area() else {
            continue;
        };
        scene.set_area_light(
            li,
            AreaLight {
                ex: k * a.ex,
                ey: k * a.ey,
                radiance: a.radiance / (k * k),
                ..a
            },
        );
    }
    scene
}

/// Case 3: light, BSDF and MIS estimators on a glossy surface under a large light
/// and on a rough one under a small light.
pub struct GlossyCase {
    pub scene: &'static str,
    pub runs: Vec<StrategyRun>,
}

pub const GLOSSY_SCENES: [&str; 2] = ["glossy_large_light.dae", "rough_small_light.dae"];

pub fn glossy(b: &Budget, scene: &'static str) -> Result<GlossyCase> {
    let setup = b.job(embedded(scene)?)?;
    Ok(GlossyCase {
        scene,
        runs: run_all(&setup, b, &STRATEGIES[1..]),
    })
}

impl GlossyCase {
    pub fn run(&self, strategy: DirectStrategy) -> &StrategyRun {
        find_run(&self.runs, strategy)
    }

    pub fn rows(&self) -> Vec<Row> {
        let case = if self.scene.starts_with("glossy") {
            "3 glossy, large light"
        } else {
            "3 rough, small light"
        };
        let best = self
            .runs
            .iter()
            .filter(|r| r.strategy != DirectStrategy::Mis)
            .map(|r| r.noise)
            .fold(f64::INFINITY, f64::min);
        let mis = self.run(DirectStrategy::Mis).clone();
        self.runs
            .iter()
            .map(|r| {
                let note = format!(
                    "noise ×{:.2} of the better single strategy; {:.1} σ from MIS's mean",
                    r.noise / best,
                    z_score((r.mean, r.se), (mis.mean, mis.se))
                );
                r.row(case, None, note)
            })
            .collect()
    }
}
