//! `--integrator auto` between path tracing and light tracing, where the scene alone
//! cannot decide (`Estimator::fixed_for`): a small render of each, twice with
//! independent seeds, and the one with the lower noise × work wins. Noise is the
//! variance of the averaged image (from the two renders' difference, as `Halves`
//! measures it); work is the rays traced, counted at the accelerator, so the choice
//! is deterministic: it does not depend on the clock, the thread count or the seed
//! of the render it is for.

use super::{pixels, splats, Halves, RenderJob, RenderSettings, StopToken};
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
    let path = score(job, s, &camera, Estimator::Path);
    let light = score(job, s, &camera, Estimator::LightTracing);
    // Ties (a black image) go to path tracing.
    let pick = if light.inefficiency() < path.inefficiency() {
        Estimator::LightTracing
    } else {
        Estimator::Path
    };
    (pick, [path, light])
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

fn score(job: &RenderJob, s: &RenderSettings, camera: &Camera, e: Estimator) -> PilotScore {
    let accel = CountingAccel {
        inner: job.accel.as_ref(),
        rays: AtomicU64::new(0),
    };
    let [a, b] = PILOT_SEEDS.map(|seed| render(job, s, camera, &accel, e, seed));
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
    e: Estimator,
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
    let t = settings.tracing(&job.scene, accel, camera);
    let rect = PixelRect::full(camera.width, camera.height);
    let (quiet, never) = (&|_| {}, &StopToken::never());
    if e == Estimator::LightTracing {
        let tracer = LightTracer::new(t);
        let paths = splats::paths_per_pixel(camera, PILOT_SPP);
        return splats::render(&tracer, camera, paths, rect, quiet, never);
    }
    let integrator = PathIntegrator::new(t);
    let frame = (camera.width, camera.height);
    pixels::render(&integrator, &settings, None, frame, rect, quiet, never)
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
