//! Pilot renders: small renders whose measured noise and work settle what the
//! scene alone cannot.
//!
//! - `--integrator auto` between path tracing and light tracing, where
//!   `Estimator::fixed_for` cannot decide: a small render of each, and the one with
//!   the lower noise × work wins.
//! - How many light paths `Estimator::Caustics` traces per camera sample: its two
//!   parts are measured apart and the share with the least predicted noise × work
//!   is taken (`CausticsSplit`).
//!
//! Each candidate renders twice with independent seeds; noise is the variance of the
//! averaged image (from the two renders' difference, as `Halves` measures it), and
//! work is the rays traced, counted at the accelerator, so every choice is
//! deterministic: it does not depend on the clock, the thread count or the seed of
//! the render it is for.

use super::{caustic_paths, pixels, splats, Halves, RenderJob, RenderSettings, StopToken};
use crate::accel::{Accel, BvhStats, TraversalStats};
use crate::camera::Camera;
use crate::geometry::Ray;
use crate::integrators::{Estimator, LightTracer, PathIntegrator};
use crate::lanes::rays::{HitPacket, RayPacket};
use crate::lanes::LaneBits;
use crate::render::{PixelRect, RenderOutput};
use crate::scene::PrimHit;
use std::sync::atomic::{AtomicU64, Ordering};

/// Width of the pilot image (its height keeps the camera's aspect ratio).
const PILOT_WIDTH: u32 = 64;
/// Samples per pixel of each of a candidate's two pilot renders.
const PILOT_SPP: u32 = 8;
/// Seeds of the two pilot renders: fixed, so renders of every seed and every shard
/// choose alike.
const PILOT_SEEDS: [u64; 2] = [0x9e37_79b9, 0x7f4a_7c15];

/// A candidate's pilot result: variance of its averaged image and rays it traced.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PilotScore {
    pub variance: f64,
    pub rays: u64,
}

impl PilotScore {
    /// Variance × work: what the render's error² would be for one unit of time.
    pub fn inefficiency(&self) -> f64 {
        self.variance * self.rays as f64
    }
}

/// The pilot's estimator for `job` with settings `s` (whose estimator is auto), and
/// each candidate's score (path tracing, light tracing).
pub fn choose(job: &RenderJob, s: &RenderSettings) -> (Estimator, [PilotScore; 2]) {
    let camera = pilot_camera(&job.camera);
    let path = score(job, s, &camera, Pass::Whole(Estimator::Path));
    let light = score(job, s, &camera, Pass::Whole(Estimator::LightTracing));
    // Ties (a black image) go to path tracing.
    let pick = if light.inefficiency() < path.inefficiency() {
        Estimator::LightTracing
    } else {
        Estimator::Path
    };
    (pick, [path, light])
}

/// Light paths per camera sample that the caustics pilot may choose, as divisors of
/// the pixel count: each sample index traces ⌈pixels / divisor⌉ light paths.
const CAUSTICS_DIVISORS: [u32; 7] = [1, 2, 4, 8, 16, 32, 64];
/// The divisor of the pilot's own light pass, and the choice when nothing tells
/// the candidates apart (a black image).
const PILOT_DIVISOR: u32 = 4;

/// How `Estimator::Caustics` shares a render between its camera samples and its
/// light paths.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CausticsSplit {
    /// Each sample index traces one light path per `divisor` pixels.
    pub divisor: u32,
    /// The light paths' predicted share of the render's rays (the progress bar's).
    pub light_rays: f64,
}

impl CausticsSplit {
    /// The divisor whose predicted variance × rays is least, from the pilot's
    /// camera part and its light part at [`PILOT_DIVISOR`]. The light part's
    /// variance grows and its rays shrink in proportion to the divisor; ties keep
    /// the pilot's divisor, then go to more light paths.
    pub fn best(camera: PilotScore, light: PilotScore) -> Self {
        let at = |d: u32| {
            let k = f64::from(d) / f64::from(PILOT_DIVISOR);
            let light_rays = light.rays as f64 / k;
            let rays = camera.rays as f64 + light_rays;
            let cost = (camera.variance + light.variance * k) * rays;
            (cost, if rays > 0.0 { light_rays / rays } else { 0.0 })
        };
        let divisor = CAUSTICS_DIVISORS
            .into_iter()
            .fold(
                PILOT_DIVISOR,
                |best, d| if at(d).0 < at(best).0 { d } else { best },
            );
        CausticsSplit {
            divisor,
            light_rays: at(divisor).1,
        }
    }
}

/// The caustics pilot for `job` with settings `s`: the split it chose, and the
/// scores of the camera part and of the light part (at [`PILOT_DIVISOR`]).
pub fn caustics_split(job: &RenderJob, s: &RenderSettings) -> (CausticsSplit, [PilotScore; 2]) {
    let camera = pilot_camera(&job.camera);
    let eye = score(job, s, &camera, Pass::CausticsCamera);
    let light = score(job, s, &camera, Pass::CausticsLight(PILOT_DIVISOR));
    (CausticsSplit::best(eye, light), [eye, light])
}

/// What a pilot render runs.
#[derive(Clone, Copy)]
enum Pass {
    /// A whole render of path tracing or light tracing.
    Whole(Estimator),
    /// The camera samples of `Estimator::Caustics` (without the paths its light takes).
    CausticsCamera,
    /// The light paths of `Estimator::Caustics`, one per this many pixels per sample.
    CausticsLight(u32),
}

/// The render's camera at the pilot's resolution (smaller images stay as they are).
fn pilot_camera(camera: &Camera) -> Camera {
    let mut c = *camera;
    if c.width > PILOT_WIDTH {
        let h = (u64::from(c.height) * u64::from(PILOT_WIDTH) + u64::from(c.width) / 2)
            / u64::from(c.width);
        c.height = (h as u32).max(1);
        c.width = PILOT_WIDTH;
    }
    c
}

fn score(job: &RenderJob, s: &RenderSettings, camera: &Camera, pass: Pass) -> PilotScore {
    let accel = CountingAccel {
        inner: job.accel.as_ref(),
        rays: AtomicU64::new(0),
    };
    let [a, b] = PILOT_SEEDS.map(|seed| render(job, s, camera, &accel, pass, seed));
    PilotScore {
        variance: Halves { a, b }.noise_per_pixel().powi(2),
        rays: accel.rays.into_inner(),
    }
}

fn render(
    job: &RenderJob,
    s: &RenderSettings,
    camera: &Camera,
    accel: &dyn Accel,
    pass: Pass,
    seed: u64,
) -> RenderOutput {
    let settings = RenderSettings {
        spp: PILOT_SPP,
        spp_offset: 0,
        adaptive: None,
        seed,
        ..s.clone()
    };
    // The engine the render itself would run (the image is the same either way).
    let mut t = settings.tracing(&job.scene, accel, camera);
    t.s.caustics_by_light = !matches!(pass, Pass::Whole(_));
    let rect = PixelRect::full(camera.width, camera.height);
    let (quiet, never) = (&|_| {}, &StopToken::never());
    let light_paths = match pass {
        Pass::Whole(Estimator::LightTracing) => Some(splats::paths_per_pixel(camera, PILOT_SPP)),
        Pass::CausticsLight(divisor) => Some(caustic_paths(&settings, camera, divisor)),
        Pass::Whole(_) | Pass::CausticsCamera => None,
    };
    if let Some(paths) = light_paths {
        let tracer = LightTracer::new(t);
        return splats::render(&tracer, None, camera, paths, rect, quiet, never);
    }
    let integrator = PathIntegrator::new(t);
    let frame = (camera.width, camera.height);
    pixels::render(
        &integrator,
        None,
        &settings,
        None,
        frame,
        rect,
        quiet,
        never,
    )
}

/// An accelerator that counts the rays it is asked to trace.
struct CountingAccel<'a> {
    inner: &'a dyn Accel,
    rays: AtomicU64,
}

impl CountingAccel<'_> {
    fn count(&self, n: u64) {
        self.rays.fetch_add(n, Ordering::Relaxed);
    }
}

impl Accel for CountingAccel<'_> {
    fn intersect(&self, ray: &Ray) -> Option<PrimHit> {
        self.count(1);
        self.inner.intersect(ray)
    }
    fn occluded(&self, ray: &Ray) -> bool {
        self.count(1);
        self.inner.occluded(ray)
    }
    fn intersect_packet(&self, rays: &RayPacket, active: LaneBits, hits: &mut HitPacket) {
        self.count(u64::from(active.count_ones()));
        self.inner.intersect_packet(rays, active, hits)
    }
    fn occluded_packet(&self, rays: &RayPacket, active: LaneBits) -> LaneBits {
        self.count(u64::from(active.count_ones()));
        self.inner.occluded_packet(rays, active)
    }
    fn intersect_counted(&self, ray: &Ray, stats: &mut TraversalStats) -> Option<PrimHit> {
        self.count(1);
        self.inner.intersect_counted(ray, stats)
    }
    fn name(&self) -> String {
        self.inner.name()
    }
    fn memory_bytes(&self) -> usize {
        self.inner.memory_bytes()
    }
    fn bvh_stats(&self) -> Option<BvhStats> {
        self.inner.bvh_stats()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn score(variance: f64, rays: u64) -> PilotScore {
        PilotScore { variance, rays }
    }

    /// (Vc + Vl·k)(Rc + Rl/k), k = divisor / PILOT_DIVISOR, is least at
    /// k = √(Vc·Rl / (Vl·Rc)); the divisors are powers of two from 1 to 64.
    #[test]
    fn caustics_split_takes_the_least_variance_times_rays() {
        let best = |camera, light| CausticsSplit::best(camera, light);
        // k = 4: divisor 16, where the light paths trace half of the rays.
        let split = best(score(1.0, 1000), score(0.25, 4000));
        assert_eq!(split.divisor, 16);
        assert!((split.light_rays - 0.5).abs() < 1e-12, "{split:?}");
        // Light paths that add almost no noise at most of the rays: as few as allowed.
        assert_eq!(best(score(1.0, 1000), score(1e-4, 4000)).divisor, 64);
        // Light paths that carry the noise at few rays: as many as allowed.
        assert_eq!(best(score(1e-3, 1000), score(1.0, 100)).divisor, 1);
        // Nothing to tell the divisors apart (a black image): the pilot's own.
        assert_eq!(
            best(score(0.0, 1000), score(0.0, 1000)).divisor,
            PILOT_DIVISOR
        );
    }
}
