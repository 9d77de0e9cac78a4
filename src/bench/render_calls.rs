//! The acceleration-structure calls of a render, recorded once and replayed through
//! each backend: the rays `ember bench accel` traces this way are exactly the ones a
//! render traces, through the same four [`Accel`] methods (16-lane `intersect_packet`
//! and `occluded_packet` for the packet engine, `intersect` and `occluded` for the
//! scalar one), so a backend's time here is its share of a render's time, and the
//! render's own work (sampling, shading) is the rest.

use crate::accel::{self, Accel, AccelKind, BvhBuilder, HitPacket, RayPacket};
use crate::geometry::{Ray, NO_PRIM};
use crate::lanes::LaneBits;
use crate::render::{PixelRect, RenderJob, RenderSettings};
use crate::scene::{PrimHit, Scene};
use rayon::prelude::*;
use std::sync::{Arc, Mutex};
use std::time::Instant;

/// One call of a render, with its arguments.
#[derive(Clone, Copy, Debug)]
pub enum Call {
    IntersectPacket(RayPacket, LaneBits),
    OccludedPacket(RayPacket, LaneBits),
    Intersect(Ray),
    Occluded(Ray),
}

impl Call {
    /// Rays the call traces.
    pub fn rays(&self) -> u64 {
        match self {
            Call::IntersectPacket(_, a) | Call::OccludedPacket(_, a) => a.count_ones() as u64,
            Call::Intersect(_) | Call::Occluded(_) => 1,
        }
    }

    pub fn is_occlusion(&self) -> bool {
        matches!(self, Call::OccludedPacket(..) | Call::Occluded(_))
    }

    /// Runs the call on `accel`; returns something that depends on its answer.
    #[inline]
    fn run(&self, accel: &dyn Accel) -> u32 {
        match self {
            Call::IntersectPacket(rays, active) => {
                let mut hits = HitPacket::default();
                accel.intersect_packet(rays, *active, &mut hits);
                hits.prim.iter().fold(0, |a, &p| a ^ p)
            }
            Call::OccludedPacket(rays, active) => accel.occluded_packet(rays, *active),
            Call::Intersect(ray) => accel.intersect(ray).map_or(0, |h| h.prim),
            Call::Occluded(ray) => accel.occluded(ray) as u32,
        }
    }
}

/// Every call of one render, in the order one thread made them.
#[derive(Clone, Debug, Default)]
pub struct RenderCalls {
    pub calls: Vec<Call>,
}

/// Passes calls on to a backend, keeping a copy of each.
struct Recorder {
    inner: Box<dyn Accel>,
    calls: Arc<Mutex<Vec<Call>>>,
}

impl Recorder {
    fn keep(&self, call: Call) {
        self.calls.lock().expect("not poisoned").push(call);
    }
}

impl Accel for Recorder {
    fn intersect(&self, ray: &Ray) -> Option<PrimHit> {
        self.keep(Call::Intersect(*ray));
        self.inner.intersect(ray)
    }

    fn occluded(&self, ray: &Ray) -> bool {
        self.keep(Call::Occluded(*ray));
        self.inner.occluded(ray)
    }

    fn intersect_packet(&self, rays: &RayPacket, active: LaneBits, hits: &mut HitPacket) {
        self.keep(Call::IntersectPacket(*rays, active));
        self.inner.intersect_packet(rays, active, hits)
    }

    fn occluded_packet(&self, rays: &RayPacket, active: LaneBits) -> LaneBits {
        self.keep(Call::OccludedPacket(*rays, active));
        self.inner.occluded_packet(rays, active)
    }

    fn name(&self) -> String {
        self.inner.name()
    }

    fn memory_bytes(&self) -> usize {
        self.inner.memory_bytes()
    }
}

impl RenderCalls {
    /// The calls of `tiles` of the 16×16-pixel tiles of a `width × height` render of
    /// `scene` with `settings`, spread evenly over the image: the same calls, packet
    /// for packet, as the whole render makes for those tiles (the render driver's
    /// tiles start at multiples of 16), made on one thread through the native SAH BVH
    /// (the calls do not depend on the backend but for the rare path where two
    /// backends round a hit differently). With as many samples per pixel as the
    /// render, the packets are as coherent as the render's (at 64 spp a packet's
    /// sixteen lanes are samples of one pixel).
    pub fn record(
        scene: Scene,
        (width, height): (u32, u32),
        settings: &RenderSettings,
        tiles: usize,
    ) -> Result<RenderCalls, accel::AccelError> {
        const TILE: u32 = 16;
        let pool = accel::tracing_pool(Some(1)).expect("a one-thread pool");
        let calls = Arc::new(Mutex::new(Vec::new()));
        let inner = pool.install(|| accel::build(&scene, AccelKind::Native(BvhBuilder::Sah)))?;
        let camera = crate::camera::Camera::new(&scene.camera, &scene.bounds, width, height);
        let recorder = Recorder {
            inner,
            calls: calls.clone(),
        };
        let job = RenderJob::with_accel(scene, Box::new(recorder), camera);
        let (cols, rows) = (width.div_ceil(TILE), height.div_ceil(TILE));
        let all = (cols * rows) as usize;
        for k in 0..tiles.clamp(1, all) {
            // Spread evenly in raster order; an odd stride on an even column count
            // also spreads them across columns.
            let index = (k * all / tiles.clamp(1, all)) as u32;
            let (x0, y0) = (TILE * (index % cols), TILE * (index / cols));
            let rect = PixelRect {
                x0,
                y0,
                x1: (x0 + TILE).min(width),
                y1: (y0 + TILE).min(height),
            };
            pool.install(|| job.render_rect(settings, rect, &|_| {}));
        }
        drop(job);
        let calls = std::mem::take(&mut *calls.lock().expect("not poisoned"));
        Ok(RenderCalls { calls })
    }

    /// Rays traced by intersection calls and by occlusion calls.
    pub fn rays(&self) -> (u64, u64) {
        self.calls.iter().fold((0, 0), |(i, o), c| {
            if c.is_occlusion() {
                (i, o + c.rays())
            } else {
                (i + c.rays(), o)
            }
        })
    }

    /// Seconds `accel` takes for the intersection calls and for the occlusion calls,
    /// each set run on `pool` in chunks of consecutive calls (as a render's tiles).
    fn replay(&self, accel: &dyn Accel, pool: &rayon::ThreadPool) -> (f64, f64) {
        let time = |occlusion: bool| {
            let calls: Vec<&Call> = self
                .calls
                .iter()
                .filter(|c| c.is_occlusion() == occlusion)
                .collect();
            let start = Instant::now();
            let x = pool.install(|| {
                calls
                    .par_chunks(256)
                    .map(|chunk| chunk.iter().fold(0u32, |a, c| a ^ c.run(accel)))
                    .reduce(|| 0, |a, b| a ^ b)
            });
            std::hint::black_box(x);
            start.elapsed().as_secs_f64()
        };
        (time(false), time(true))
    }
}

/// What one backend did with a render's calls (medians over the rounds).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CallRates {
    pub intersect_mrays: f64,
    pub occluded_mrays: f64,
    /// Seconds for all the calls.
    pub seconds: f64,
}

impl RenderCalls {
    /// Replays the calls through every backend of `accels` on `pool`, `rounds` times,
    /// the backends in turn within each round so that a drift of the machine's speed
    /// weighs on all of them alike. Each timing replays the calls as many times as
    /// make about a quarter of a second for the first backend (a scene of a few
    /// primitives replays in a few milliseconds, too short to time on a busy machine).
    pub fn measure(
        &self,
        accels: &[&dyn Accel],
        pool: &rayon::ThreadPool,
        rounds: usize,
    ) -> Vec<CallRates> {
        let Some(first) = accels.first() else {
            return Vec::new();
        };
        let (i, o) = self.replay(*first, pool);
        let passes = (0.25 / (i + o).max(1e-6)).ceil().clamp(1.0, 1000.0) as usize;
        let mut times = vec![(Vec::new(), Vec::new()); accels.len()];
        for _ in 0..rounds.max(1) {
            for (accel, t) in accels.iter().zip(&mut times) {
                let (mut i, mut o) = (0.0, 0.0);
                for _ in 0..passes {
                    let (pi, po) = self.replay(*accel, pool);
                    i += pi;
                    o += po;
                }
                t.0.push(i / passes as f64);
                t.1.push(o / passes as f64);
            }
        }
        let (ri, ro) = self.rays();
        times
            .into_iter()
            .map(|(mut i, mut o)| {
                let (i, o) = (super::median(&mut i), super::median(&mut o));
                CallRates {
                    intersect_mrays: ri as f64 / i.max(1e-9) / 1e6,
                    occluded_mrays: ro as f64 / o.max(1e-9) / 1e6,
                    seconds: i + o,
                }
            })
            .collect()
    }

    /// How `accel`'s answers to the calls' spawned rays (lanes with a skip) differ
    /// from `reference`'s, which keeps the skip contract (the native BVH).
    pub fn self_hits(&self, accel: &dyn Accel, reference: &dyn Accel) -> SelfHits {
        let count = |call: &Call| -> SelfHits {
            let mut c = SelfHits::default();
            match call {
                Call::IntersectPacket(rays, active) => {
                    let spawned = spawned_lanes(rays, *active);
                    let (mut a, mut r) = (HitPacket::default(), HitPacket::default());
                    accel.intersect_packet(rays, spawned, &mut a);
                    reference.intersect_packet(rays, spawned, &mut r);
                    c.spawned += spawned.count_ones() as u64;
                    for i in lanes(spawned) {
                        let own = rays.skip[i];
                        c.own_hits += u64::from(a.prim[i] == own && r.prim[i] != own);
                        c.differ += u64::from(a.prim[i] != r.prim[i]);
                    }
                }
                Call::OccludedPacket(rays, active) => {
                    let spawned = spawned_lanes(rays, *active);
                    let a = accel.occluded_packet(rays, spawned);
                    let r = reference.occluded_packet(rays, spawned);
                    c.spawned_shadow += spawned.count_ones() as u64;
                    c.extra_occlusions += (a & !r).count_ones() as u64;
                    c.differ += (a ^ r).count_ones() as u64;
                }
                Call::Intersect(ray) if ray.skip != NO_PRIM => {
                    let (a, r) = (accel.intersect(ray), reference.intersect(ray));
                    let prim = |h: Option<PrimHit>| h.map_or(NO_PRIM, |h| h.prim);
                    c.spawned += 1;
                    c.own_hits += u64::from(prim(a) == ray.skip && prim(r) != ray.skip);
                    c.differ += u64::from(prim(a) != prim(r));
                }
                Call::Occluded(ray) if ray.skip != NO_PRIM => {
                    let (a, r) = (accel.occluded(ray), reference.occluded(ray));
                    c.spawned_shadow += 1;
                    c.extra_occlusions += u64::from(a && !r);
                    c.differ += u64::from(a != r);
                }
                _ => {}
            }
            c
        };
        self.calls
            .par_iter()
            .map(count)
            .reduce(SelfHits::default, SelfHits::add)
    }
}

/// The lanes of `active` whose ray left a surface.
fn spawned_lanes(rays: &RayPacket, active: LaneBits) -> LaneBits {
    lanes(active)
        .filter(|&i| rays.skip[i] != NO_PRIM)
        .fold(0, |m, i| m | 1 << i)
}

fn lanes(bits: LaneBits) -> impl Iterator<Item = usize> {
    (0..crate::lanes::LANES).filter(move |&i| bits >> i & 1 != 0)
}

/// Spawned rays of a render's calls on which a backend and the native BVH disagree.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SelfHits {
    /// Spawned intersection rays, and those whose nearest hit was the primitive they
    /// left where the native BVH's was not.
    pub spawned: u64,
    pub own_hits: u64,
    /// Spawned shadow rays, and those occluded where the native BVH found them clear.
    pub spawned_shadow: u64,
    pub extra_occlusions: u64,
    /// Spawned rays (both kinds) with any other answer than the native BVH's: also
    /// rays that graze an edge both backends may legitimately decide either way.
    pub differ: u64,
}

impl SelfHits {
    fn add(self, o: SelfHits) -> SelfHits {
        SelfHits {
            spawned: self.spawned + o.spawned,
            own_hits: self.own_hits + o.own_hits,
            spawned_shadow: self.spawned_shadow + o.spawned_shadow,
            extra_occlusions: self.extra_occlusions + o.extra_occlusions,
            differ: self.differ + o.differ,
        }
    }
}
