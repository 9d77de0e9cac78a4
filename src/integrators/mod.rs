//! Light transport, behind two interfaces the render driver calls
//! (`crate::render` owns the pixel loop; nothing here imports it):
//!
//! - [`SampleIntegrator`]: estimates the radiance of pixel samples (pbrt-v4's
//!   `RayIntegrator`, Mitsuba's `SamplingIntegrator`): the path tracer (`path`, every
//!   CS184 mode: `-m 0` emitted light, `-m 1` direct lighting, `-m N` global
//!   illumination, with the chosen direct-lighting strategy) and the debug views
//!   (`debug`);
//! - [`SplatIntegrator`]: traces paths from the lights and splats them into the
//!   pixels that see them (Mitsuba's `AdjointIntegrator`): the light tracer.
//!
//! Both are written over the BSDFs and lights' one implementation.

pub mod debug;
pub mod light_tracing;
pub mod path;
mod vertex;

pub use light_tracing::LightTracer;
pub use path::PathIntegrator;

use crate::accel::Accel;
use crate::camera::Camera;
use crate::lanes::Real;
use crate::lights::Light;
use crate::names::{display_from_table, Named};
use crate::sampling::SamplerKind;
use crate::scene::Scene;
use crate::Color;

/// Samples `first .. first + count` of pixel `(x, y)` (column from the left, row
/// from the top).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PixelSamples {
    pub x: u32,
    pub y: u32,
    pub first: u32,
    pub count: u32,
    /// Light found after fewer scattering events than this does not count: the render
    /// driver estimates it with samples of its own there (`render::split`). 0: all counts.
    pub min_bounces: u32,
}

/// What one pixel sample gives.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SampleValue {
    pub radiance: Color,
    /// Whether the sample's camera ray met a surface.
    pub met_surface: bool,
}

/// An integrator that estimates the radiance of each pixel sample.
pub trait SampleIntegrator: Sync {
    /// Renders the samples of `blocks`, starting them in order and a block only while
    /// `stop` says no; `done(i, values)` receives block `i`'s values in sample order once
    /// all are done. Blocks never started are not reported.
    fn render_blocks(
        &self,
        blocks: &[PixelSamples],
        stop: &(dyn Fn() -> bool + Sync),
        done: &mut dyn FnMut(usize, &[SampleValue]),
    );
}

/// One splat: pixel column, row and value (before division by paths per pixel).
pub type Splat = (u32, u32, Color);

/// An integrator that traces paths from the lights and splats them into pixels.
pub trait SplatIntegrator: Sync {
    /// Traces light paths `first .. first + count` of a render, pushing their splats;
    /// returns how many non-finite contributions were dropped.
    fn trace_paths(&self, first: u64, count: u64, splats: &mut Vec<Splat>) -> u32;
    /// The pixel-sample integrator for what only camera rays can see (0-bounce paths:
    /// emitters seen directly), when the scene has any.
    fn camera_part(&self) -> Option<&dyn SampleIntegrator>;
}

/// What every estimator is given: the scene, its acceleration structure, the camera,
/// the path settings, the engine that runs the lanes and the render's seed.
#[derive(Clone, Copy)]
pub struct Tracing<'a> {
    pub scene: &'a Scene,
    pub accel: &'a dyn Accel,
    pub camera: &'a Camera,
    pub s: PathSettings,
    pub engine: Engine,
    pub seed: u64,
}

/// The parameters of spec §7 that shape a path estimator.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PathSettings {
    pub max_depth: u32,
    pub accumulate: bool,
    pub light_samples: u32,
    pub strategy: DirectStrategy,
    pub roulette: Roulette,
    pub sampler: SamplerKind,
    /// Caustics go to light tracing (`Estimator::Caustics`): the path tracer drops
    /// the paths that light tracing takes, and light tracing takes only those.
    pub caustics_by_light: bool,
}

impl PathSettings {
    /// Lanes where light found after `bounces` scattering events counts (`bounces` are
    /// small integers, exact as floats): up to `max_depth` when accumulating, else at
    /// `max_depth` only (spec §7). The path and light tracers both ask this.
    #[inline(always)]
    pub fn counts_l<L: crate::lanes::Lanes>(&self, l: L, bounces: L::F) -> L::M {
        let max = l.f(self.max_depth as f32);
        if self.accumulate {
            bounces.le(max)
        } else {
            bounces.eq(max)
        }
    }
}

/// Veach's power heuristic (β = 2) for `nf` samples of pdf `f` against `ng` of pdf `g`.
#[inline(always)]
pub fn power_heuristic<F: Real>(nf: F, f_pdf: F, ng: F, g_pdf: F) -> F {
    let (zero, one) = (nf.splat_as(0.0), nf.splat_as(1.0));
    let f = nf * f_pdf;
    let g = ng * g_pdf;
    let d = f * f + g * g;
    let w = F::select(d.gt(zero), f * f / d, zero);
    F::select(f.abs().eq(nf.splat_as(f32::INFINITY)), one, w)
}

/// How light arriving directly from emitters is estimated at each scattering vertex.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DirectStrategy {
    /// `-H`: uniform hemisphere directions; only emitters that rays can hit are seen.
    Hemisphere,
    /// Light sampling (`-l` samples per area light, one per delta light).
    Light,
    /// Light sampling and BSDF sampling combined by the power heuristic.
    Mis,
    /// MIS at glossy vertices, light sampling alone at diffuse ones: where a lobe is
    /// broad, BSDF-sampled emission adds little but its cost (and at the depth cap a
    /// ray of its own), so only glossy vertices pay for it.
    MisGlossy,
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
            DirectStrategy::MisGlossy,
            "mis-glossy",
            "MIS at glossy surfaces, light sampling alone at diffuse ones",
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
    /// light is sampled by a cosine about +Y that is poor near the horizon. So a
    /// glossy scene gets MIS at its glossy vertices only (the diffuse ones keep light
    /// sampling), and a scene with an ambient or environment light MIS everywhere.
    pub fn auto_for(scene: &crate::scene::Scene) -> DirectStrategy {
        let glossy = scene.materials.iter().any(|m| m.flags().glossy);
        let ambient = scene.lights.iter().any(|l| l.is_environment());
        match (ambient, glossy) {
            (true, _) => DirectStrategy::Mis,
            (false, true) => DirectStrategy::MisGlossy,
            (false, false) => DirectStrategy::Light,
        }
    }
}

/// How paths (camera paths, or light paths for light tracing) run on the CPU. The image
/// is the same bit for bit either way (the transport is one code over its lane type);
/// only the speed differs.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Engine {
    /// Packets wherever the render allows them ([`crate::render::RenderSettings::packet_blocker`]).
    #[default]
    Auto,
    /// One path at a time.
    Scalar,
    /// Sixteen paths at a time, one per SIMD lane; renders the engine cannot run
    /// are refused by the CLI (a library caller gets one path at a time).
    Packet,
}

impl Named for Engine {
    const WHAT: &'static str = "engine";
    const TABLE: &'static [(Self, &'static str, &'static str)] = &[
        (
            Engine::Auto,
            "auto",
            "Sixteen paths per SIMD pass for every path- or light-traced render; the debug views (--shading) one at a time",
        ),
        (Engine::Scalar, "scalar", "One path at a time (the same code at one lane)"),
        (
            Engine::Packet,
            "packet",
            "Sixteen paths per SIMD pass (AVX-512, AVX2 or portable code); an error where the render cannot use them",
        ),
    ];
}
display_from_table!(Engine);

/// Which way paths are built.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Estimator {
    /// Paths start at the camera (`PathIntegrator`, with its `DirectStrategy`).
    #[default]
    Path,
    /// Paths start on the lights and connect to the camera (`light_tracing`).
    LightTracing,
    /// Path tracing, with light tracing for the caustics it finds only by chance, or
    /// never: paths whose first surface from the camera does not focus light and
    /// whose last surface before a light does (`x₁ D … D F L`; focusing: mirrors,
    /// glass and smooth metal, `Material::focuses`). From an area light the path
    /// tracer finds them by chance (through a smooth metal also by light sampling)
    /// and drops them here; from a point, spot or directional light it cannot find them
    /// at all (`starts_caustic_paths`). The two take disjoint sets
    /// of paths, so their sum is unbiased (README). How many light paths it traces
    /// per camera sample is a pilot's choice (`render::pilot::CausticsSplit`). Its
    /// light paths are numbered by camera sample index, so sample ranges merge, and
    /// a band of the image traces them all (they land anywhere). Adaptive sampling
    /// does not apply (`RenderSettings::adaptive` is ignored; the command line
    /// refuses it, and auto path-traces adaptive renders).
    Caustics,
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
        (
            Estimator::Caustics,
            "caustics",
            "Path tracing, with light tracing (1 light path per 1 to 64 camera samples, as a small pilot render finds best for the scene) for the light that mirrors, glass and smooth metal (microfacet alpha at most 0.3) focus onto surfaces the camera sees: far fewer fireflies under area lights, and the caustics of point, spot and directional lights, which path tracing cannot find; auto's choice wherever a light shines on such a surface. Not with -a",
        ),
    ];
}
display_from_table!(Estimator);

impl Estimator {
    /// The estimator `--integrator auto` takes when the scene alone decides, or `None`
    /// when both path and light tracing could win and a pilot render must choose
    /// (`RenderJob::estimator`).
    ///
    /// - Path tracing at `max_depth` ≤ 1: a point light's direct light is then exact
    ///   per camera sample, which light tracing only approaches by chance.
    /// - Path tracing with light-traced caustics (`Caustics`) wherever a light
    ///   shines on a focusing surface and a surface that is not can receive the
    ///   caustic (`light_tracing::caustics_possible`). From area lights it was
    ///   1.15–2.6× more efficient (noise² × time) than path tracing on every such
    ///   shipped scene with mirrors or glass, CS184's CBcoil the closest, and
    ///   1.7× on the microfacet spheres and the copper bunny (BENCHMARKS §3); from point,
    ///   spot and directional lights path tracing misses the caustic altogether.
    ///   Not where emissive surfaces that are not lights sit in the scene. Only
    ///   BSDF sampling finds those, at every bounce, so their noise dwarfs the
    ///   caustics' (CMU462's `sky/CBspheres`, `CBgems` and `CBcoil`: 10× path
    ///   tracing's noise on CS184's versions, and the same noise with light-traced
    ///   caustics, for 1.01–1.11× the noise² × time).
    /// - Path tracing wherever light tracing cannot show the whole image (anything
    ///   specular or self-emitting, see `light_tracing`) and where any light is not a
    ///   point or spot light (area and environment lights are sampled well from the
    ///   camera).
    /// - Otherwise either can win by orders of magnitude: CBempty, whose point light
    ///   lights the room through the ceiling just above it, wants light tracing
    ///   (stability case 9); CMU462's `basic/trigs1.dae`, lit directly, wants path
    ///   tracing.
    pub fn fixed_for(scene: &crate::scene::Scene, max_depth: u32) -> Option<Estimator> {
        if max_depth <= 1 {
            return Some(Estimator::Path);
        }
        if light_tracing::caustics_possible(scene, max_depth) && !scene.has_unsampled_emitters() {
            return Some(Estimator::Caustics);
        }
        let point_lights_only = !scene.lights.is_empty()
            && scene.lights.iter().all(|l| {
                matches!(
                    l,
                    crate::lights::Light::Point { .. } | crate::lights::Light::Spot(_)
                )
            });
        let specular = scene.materials.iter().any(|m| m.is_delta());
        if point_lights_only && !specular && !scene.has_unsampled_emitters() {
            None
        } else {
            Some(Estimator::Path)
        }
    }
}

/// Whether `light` starts the light paths of `Estimator::Caustics`, so that each path
/// is counted once:
/// - area, point, spot and directional lights: the path tracer drops exactly the
///   caustic paths that end on them, found by light sampling at a focusing glossy
///   vertex or by a BSDF-sampled ray leaving one (`PathIntegrator::direct_lights`,
///   `area_light_on_line`); through mirrors and glass it never reaches a point or a
///   single direction at all, so without light tracing those caustics would be
///   missing;
/// - ambient and environment lights: the path tracer finds their light through
///   focusing surfaces by BSDF sampling, and keeps it.
pub fn starts_caustic_paths(light: &Light) -> bool {
    match light {
        Light::Area(_) | Light::Point { .. } | Light::Spot(_) | Light::Directional { .. } => true,
        Light::Ambient { .. } | Light::Environment(_) => false,
    }
}

/// Russian roulette policy. The depth cap `-m` is never a roulette decision.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Roulette {
    Off,
    /// From bounce `start` on, continue with probability `min(1, max channel of throughput)`, at least `min_prob`.
    /// The throughput is read without refraction's `(ηi/ηt)²` radiance factors (as
    /// pbrt-v4's `etaScale` and Mitsuba's `η²`): they cancel when the path leaves the
    /// medium again, so they say nothing about what the path will carry.
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
            start: Roulette::DEFAULT_START,
            min_prob: 0.05,
        }
    }
}

impl Roulette {
    /// The default first bounce of roulette: 5, as Mitsuba's `rr_depth`. With
    /// stratified samples roulette's variance falls more slowly with the sample count
    /// than the rest of the error, so an early start pays only for few samples (the
    /// measurements: docs/scene-semantics.md, "Russian roulette").
    pub const DEFAULT_START: u32 = 5;

    /// The first bounce at which roulette may end a path; `None` when it is off.
    pub fn start(&self) -> Option<u32> {
        match *self {
            Roulette::Off => None,
            Roulette::Throughput { start, .. } | Roulette::Fixed { start, .. } => Some(start),
        }
    }

    /// Continuation probability after `bounces` scattering events with throughput
    /// `beta`, per lane: 1 where the lane is not in `lanes` (`bounces` are small
    /// integers, exact as floats).
    #[inline(always)]
    pub fn continue_prob_l<L: crate::lanes::Lanes>(
        &self,
        l: L,
        bounces: L::F,
        lanes: crate::lanes::LaneBits,
        beta: crate::lanes::V3<L::F>,
    ) -> L::F {
        use crate::lanes::{clamp, LaneMask};
        let one = l.f(1.0);
        let (start, q) = match *self {
            Roulette::Off => return one,
            Roulette::Throughput { start, min_prob } => {
                (start, clamp(beta.max_element(), l.f(min_prob), one))
            }
            Roulette::Fixed { start, prob } => (start, l.f(prob.clamp(1e-6, 1.0))),
        };
        let playing = bounces.ge(l.f(start as f32)).bits() & lanes;
        L::F::select(l.mask(playing), q, one)
    }

    /// Plays roulette for the paths of `lanes` after `bounces` scattering events, with
    /// throughput `beta`, the probability read from `read` (the throughput as roulette
    /// sees it) and the uniform numbers `u` (drawn only if some lane plays), sparing
    /// the lanes of `spared` (they go on for sure): the lanes that go on with a finite,
    /// non-zero throughput, and the throughput divided by the probability.
    #[inline(always)]
    pub fn play_l<L: crate::lanes::Lanes>(
        &self,
        l: L,
        bounces: L::F,
        (lanes, spared): (crate::lanes::LaneBits, crate::lanes::LaneBits),
        (beta, read): (crate::lanes::V3<L::F>, crate::lanes::V3<L::F>),
        u: impl FnOnce() -> L::F,
    ) -> (crate::lanes::LaneBits, crate::lanes::V3<L::F>) {
        use crate::lanes::LaneMask;
        let q = self.continue_prob_l(l, bounces, lanes & !spared, read);
        let play = lanes & q.lt(l.f(1.0)).bits();
        let survive = match play {
            0 => lanes,
            _ => lanes & !(play & u().ge(q).bits()),
        };
        let beta = beta / q;
        (survive & (beta.is_finite() & !beta.is_zero()).bits(), beta)
    }
}
