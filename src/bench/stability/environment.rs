//! Case 10: an environment map with one small bright spot (a sun in a dim sky).
//! Sampling the map uniformly over the sphere (the course's first step) rarely finds
//! the sun; sampling it by luminance × sin θ (`-e`'s default) finds it almost every
//! time, so MIS with it converges much faster at the same spp.

use super::lights::StrategyRun;
use super::measure::{z_score, Budget};
use super::scenes::SceneBuilder;
use super::Row;
use crate::film::Image;
use crate::integrators::{DirectStrategy, Roulette};
use crate::lights::environment::{EnvSampling, EnvironmentMap};
use crate::materials::Material;
use crate::render::RenderSettings;
use crate::scene::{CameraDesc, Scene};
use crate::{Color, Vec3};
use anyhow::Result;
use std::sync::Arc;

/// Size of `sun_sky_map` (and of `scenes/env_sun.exr`, which is that map).
pub const SUN_SKY_SIZE: (u32, u32) = (64, 32);
/// The sun's texels: columns 40–41, rows 9–10 (about 37° above the horizon, from +X/−Z).
const SUN_TEXELS: [(u32, u32); 4] = [(40, 9), (41, 9), (40, 10), (41, 10)];
const SUN_RADIANCE: Color = Color::new(400.0, 360.0, 300.0);

/// A deterministic 64 × 32 latitude-longitude test map: a blue sky brightening toward
/// the zenith, a dark brown ground below the horizon, and a 2 × 2-texel sun that gives
/// most of the light (about 10 times the sky's irradiance on a floor).
pub fn sun_sky_map() -> Image {
    let (w, h) = SUN_SKY_SIZE;
    let mut img = Image::new(w, h);
    for (i, p) in img.pixels.iter_mut().enumerate() {
        let (x, y) = (i as u32 % w, i as u32 / w);
        let cos_theta = (std::f32::consts::PI * (y as f32 + 0.5) / h as f32).cos();
        *p = if SUN_TEXELS.contains(&(x, y)) {
            SUN_RADIANCE
        } else if cos_theta > 0.0 {
            Color::new(0.25, 0.35, 0.6) * (0.5 + 0.5 * cos_theta)
        } else {
            Color::new(0.08, 0.06, 0.04)
        };
    }
    img
}

/// A grey floor and a white diffuse sphere under `env`.
pub fn sun_sky_scene(env: EnvironmentMap) -> Scene {
    let mut b = SceneBuilder::default();
    let grey = b.material(Material::lambertian(Color::splat(0.5)));
    let white = b.material(Material::lambertian(Color::splat(0.8)));
    b.quad(
        Vec3::new(-4.0, 0.0, -4.0),
        Vec3::new(0.0, 0.0, 8.0),
        Vec3::new(8.0, 0.0, 0.0),
        grey,
    );
    b.sphere(Vec3::new(0.0, 1.0, 0.0), 1.0, white);
    let mut scene = b.finish(CameraDesc {
        forward: Vec3::new(0.0, -0.5, -1.0).normalize(),
        up: Vec3::Y,
        tan_half_x: Some(0.6),
        tan_half_y: None,
        ..CameraDesc::default()
    });
    scene.set_environment(Arc::new(env));
    scene
}

pub struct EnvironmentCase {
    pub runs: Vec<StrategyRun>,
}

/// The methods of case 10: (name, direct-light strategy, how the map is sampled).
pub const ENV_METHODS: [(&str, DirectStrategy, EnvSampling); 3] = [
    (
        "MIS, map importance",
        DirectStrategy::Mis,
        EnvSampling::Importance,
    ),
    (
        "MIS, map uniform",
        DirectStrategy::Mis,
        EnvSampling::Uniform,
    ),
    ("BSDF only", DirectStrategy::Bsdf, EnvSampling::Importance),
];

pub fn sun_sky(b: &Budget) -> Result<EnvironmentCase> {
    let map = EnvironmentMap::from_image(sun_sky_map(), "sun_sky_map")?;
    let mut runs = Vec::new();
    for (name, strategy, sampling) in ENV_METHODS {
        let job = b.job(sun_sky_scene(map.clone().with_sampling(sampling)))?;
        let settings = b.settings(RenderSettings {
            max_depth: 1,
            strategy: Some(strategy),
            roulette: Roulette::Off,
            ..Default::default()
        });
        let warnings = job.warnings(&settings);
        let mut run = StrategyRun::from_halves(strategy, &job.halves(&settings), warnings);
        run.name = name;
        runs.push(run);
    }
    Ok(EnvironmentCase { runs })
}

impl EnvironmentCase {
    pub fn run(&self, name: &str) -> &StrategyRun {
        self.runs
            .iter()
            .find(|r| r.name == name)
            .expect("method run")
    }

    pub fn rows(&self) -> Vec<Row> {
        let best = self.run(ENV_METHODS[0].0).clone();
        self.runs
            .iter()
            .map(|r| {
                let note = format!(
                    "noise ×{:.1} of MIS with map importance sampling (variance ×{:.0}); {:.1} σ from its mean",
                    r.noise / best.noise,
                    (r.noise / best.noise).powi(2),
                    z_score((r.mean, r.se), (best.mean, best.se))
                );
                r.row("10 environment sun", None, note)
            })
            .collect()
    }
}
