//! Light transport. One path tracer serves every CS184 mode (`-m 0` emitted
//! light, `-m 1` direct lighting, `-m N` global illumination), with the
//! direct-lighting strategy chosen by the user; debug views live in `debug`.

pub mod debug;
pub mod light_tracing;
pub mod packet;
pub mod path;

pub use path::{PathIntegrator, PathSettings};

use crate::names::{display_from_table, Named};
use crate::sampling::Sampler;

/// How light arriving directly from emitters is estimated at each scattering vertex.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DirectStrategy {
    /// `-H`: uniform hemisphere directions; only emitters that rays can hit are seen.
    Hemisphere,
    /// Light sampling (`-l` samples per area light, one per delta light).
    Light,
    /// Light sampling and BSDF sampling combined by the power heuristic.
    Mis,
    /// BSDF sampling alone: no light sampling; emission found by the path's own
    /// BSDF-sampled rays counts in full. Like `Hemisphere`, it cannot see delta lights;
    /// it exists to show where BSDF sampling is the better half of MIS.
    Bsdf,
}

impl Named for DirectStrategy {
    const WHAT: &'static str = "direct-lighting estimator";
    const TABLE: &'static [(Self, &'static str, &'static str)] = &[
        (DirectStrategy::Light, "light", "Light sampling only"),
        (
            DirectStrategy::Mis,
            "mis",
            "Light and BSDF sampling, power heuristic",
        ),
        (
            DirectStrategy::Hemisphere,
            "hemisphere",
            "Uniform hemisphere sampling (same as -H)",
        ),
        (
            DirectStrategy::Bsdf,
            "bsdf",
            "BSDF sampling alone, no light sampling (cannot see point/directional lights)",
        ),
    ];
}
display_from_table!(DirectStrategy);

impl DirectStrategy {
    /// The better default for `scene`, from `ember bench converge` (BENCHMARKS.md):
    /// light sampling is 5–50 % more efficient on purely diffuse scenes (MIS pays for
    /// BSDF-sampled emission that carries little weight), while MIS is an order of
    /// magnitude better as soon as glossy surfaces reflect a light, or when an ambient
    /// light is sampled by a cosine about +Y that is poor near the horizon.
    pub fn auto_for(scene: &crate::scene::Scene) -> DirectStrategy {
        let glossy = scene.materials.iter().any(|m| m.flags().glossy);
        let ambient = scene.lights.iter().any(|l| l.is_environment());
        if glossy || ambient {
            DirectStrategy::Mis
        } else {
            DirectStrategy::Light
        }
    }
}

/// Which way paths are built.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Estimator {
    /// Paths start at the camera (`PathIntegrator`, with its `DirectStrategy`).
    #[default]
    Path,
    /// Paths start on the lights and connect to the camera (`light_tracing`).
    LightTracing,
}

impl Named for Estimator {
    const WHAT: &'static str = "estimator";
    const TABLE: &'static [(Self, &'static str, &'static str)] = &[
        (
            Estimator::Path,
            "path",
            "Path tracing from the camera, direct-lighting strategy chosen from the scene",
        ),
        (
            Estimator::LightTracing,
            "light-tracing",
            "Light tracing: paths start on the lights and connect to the camera (not for mirrors/glass)",
        ),
    ];
}
display_from_table!(Estimator);

impl Estimator {
    /// Light tracing where `ember bench stability` (the CBempty case) shows path tracing
    /// failing: every light is a point light, so the light reaches most of the scene
    /// indirectly, through the few surfaces near it, which camera paths find by chance
    /// and light paths find at once. Only when nothing specular or self-emitting is
    /// present, which light tracing cannot show (see `light_tracing`).
    pub fn auto_for(scene: &crate::scene::Scene) -> Estimator {
        let point_lights_only = !scene.lights.is_empty()
            && scene.lights.iter().all(|l| {
                matches!(
                    l,
                    crate::lights::Light::Point { .. } | crate::lights::Light::Spot(_)
                )
            });
        let specular = scene.materials.iter().any(|m| m.is_delta());
        if point_lights_only && !specular && !scene.has_unsampled_emitters() {
            Estimator::LightTracing
        } else {
            Estimator::Path
        }
    }
}

/// Russian roulette policy. The depth cap `-m` is never a roulette decision.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Roulette {
    Off,
    /// From bounce `start` on, continue with probability `min(1, max channel of throughput)`, at least `min_prob`.
    Throughput {
        start: u32,
        min_prob: f32,
    },
    /// From bounce `start` on, continue with the fixed probability `prob`.
    Fixed {
        start: u32,
        prob: f32,
    },
}

impl Default for Roulette {
    fn default() -> Self {
        Roulette::Throughput {
            start: 3,
            min_prob: 0.05,
        }
    }
}

impl Roulette {
    /// The first bounce at which roulette may end a path; `None` when it is off.
    pub fn start(&self) -> Option<u32> {
        match *self {
            Roulette::Off => None,
            Roulette::Throughput { start, .. } | Roulette::Fixed { start, .. } => Some(start),
        }
    }

    /// Continuation probability after `bounces` scattering events with throughput `beta`.
    pub fn continue_prob(&self, bounces: u32, beta: crate::Color) -> f32 {
        match *self {
            Roulette::Off => 1.0,
            Roulette::Throughput { start, min_prob } if bounces >= start => {
                beta.max_element().clamp(min_prob, 1.0)
            }
            Roulette::Fixed { start, prob } if bounces >= start => prob.clamp(1e-6, 1.0),
            _ => 1.0,
        }
    }

    /// Plays roulette for a path with throughput `beta` (relative to its start):
    /// `None` ends the path; `Some(q)` is the survival probability to divide the
    /// throughput by (1 when no roulette is played, and then nothing is drawn).
    pub fn play(&self, bounces: u32, beta: crate::Color, sampler: &mut Sampler) -> Option<f32> {
        let q = self.continue_prob(bounces, beta);
        if q < 1.0 && sampler.next_f32() >= q {
            return None;
        }
        Some(q)
    }
}
