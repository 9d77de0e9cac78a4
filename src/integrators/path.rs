//! The unidirectional path tracer of spec §7, written once over the lane type: one
//! path at a time (`One`) or sixteen, one per SIMD lane, each lane performing exactly
//! the operations a path alone performs, on the same numbers, so an image does not
//! depend on which ran it.
//!
//! A path with `k` scattering events ("bounces") contributes when `k ≤ m`
//! (accumulation on) or `k = m` (off). Emission found by a ray leaving vertex `x_k`
//! and light sampled at `x_k` both belong to paths of `k` bounces.
//!
//! Lanes are refilled as paths end (a camera ray that escapes at once frees its lane
//! for the next sample), taking the samples of the blocks in order; a block's values
//! are handed back, in sample order, once all are done. Lanes whose materials differ
//! run each kind present (`BsdfLanes`), masked.

use super::vertex::{Depth, Scattering, Vertex};
use super::{
    power_heuristic, DirectStrategy, PathSettings, PixelSamples, SampleIntegrator, SampleValue,
    Tracing,
};
use super::{starts_caustic_paths, Engine};
use crate::accel::Accel;
use crate::geometry::NO_PRIM;
use crate::lanes::rays::{HitPacket, RayPacket};
use crate::lanes::{
    dispatch, each_lane, per_lane, per_lane_v3, LaneBits, LaneMask, Lanes, One, Real, Simd,
    SimdTask, UInt, LANES, V3,
};
use crate::lights::Light;
use crate::sampling::warps::{uniform_hemisphere_l, uniform_hemisphere_pdf};
use crate::sampling::{pixel_key, SampleStream, FIRST_PATH_PAIR, PIXEL_PAIR};
use crate::scene::{Hits, NO_LIGHT};
use crate::Color;
use glam::Vec3;

/// Shadow rays stop this fraction short of the sampled light point, so the light's own
/// surface does not occlude it; relative, so it works at every scene scale.
pub(super) const SHADOW_EPSILON: f32 = 1e-4;

/// The path tracer over one scene, camera and set of settings.
pub struct PathIntegrator<'a> {
    t: Tracing<'a>,
    /// Samples per vertex of each light (one for delta lights).
    light_samples: Vec<u32>,
    layout: DimLayout,
    unsampled_emitters: bool,
    /// The triangles of area lights' surfaces, and their light.
    light_prims: Vec<(u32, u32)>,
    scattering: Scattering,
}

/// Which dimension pair each number of a path comes from: the pixel position, the
/// lens, then per bounce its BSDF direction, its lobe choice with roulette, and its
/// light samples (or hemisphere directions), so every number a path draws has a
/// pair of its own, whatever the path does. (A bounce's first light sample is drawn
/// jointly with the pair that chose the arriving direction: `light_2d`.)
#[derive(Clone, Copy, Debug)]
struct DimLayout {
    per_bounce: u32,
}

/// Offsets within a bounce's pairs.
const BSDF_PAIR: u32 = 0;
const LOBE_PAIR: u32 = 1;
const LIGHT_PAIRS: u32 = 2;

impl<'a> PathIntegrator<'a> {
    pub fn new(t: Tracing<'a>) -> Self {
        let (scene, s) = (t.scene, t.s);
        let n = s.light_samples.max(1);
        let light_samples: Vec<u32> = scene
            .lights
            .iter()
            .map(|l| if l.is_delta() { 1 } else { n })
            .collect();
        let direct_pairs = match s.strategy {
            DirectStrategy::Hemisphere => n,
            DirectStrategy::Light | DirectStrategy::Mis | DirectStrategy::MisGlossy => {
                light_samples.iter().sum()
            }
            DirectStrategy::Bsdf => 0,
        };
        PathIntegrator {
            t: Tracing {
                s: PathSettings {
                    light_samples: n,
                    ..s
                },
                ..t
            },
            light_samples,
            layout: DimLayout {
                per_bounce: LIGHT_PAIRS + direct_pairs,
            },
            unsampled_emitters: scene.has_unsampled_emitters(),
            scattering: Scattering::of(scene),
            light_prims: (0..scene.triangles.len() as u32)
                .map(|i| (i, scene.triangles[i as usize].light))
                .filter(|&(_, light)| light != NO_LIGHT)
                .collect(),
        }
    }
}

impl PathIntegrator<'_> {
    /// The radiance arriving at `o` from direction `−d` (unit `d`), estimated by the
    /// one path of sample `index` of the stream keyed `key`: the pixel sample's path
    /// with the camera ray replaced by `(o, d)`.
    pub fn radiance_along(&self, o: Vec3, d: Vec3, key: u32, index: u32) -> Color {
        let mut out = Color::ZERO;
        let block = [PixelSamples {
            x: 0,
            y: 0,
            first: index,
            count: 1,
            min_bounces: 0,
        }];
        let mut kernel = Kernel::new(One, self, &block, &|| false);
        kernel.first_ray = Some((o, d, key));
        kernel.run(&mut |_, v| out = v[0].radiance);
        out
    }
}

impl SampleIntegrator for PathIntegrator<'_> {
    fn render_blocks(
        &self,
        blocks: &[PixelSamples],
        stop: &(dyn Fn() -> bool + Sync),
        done: &mut dyn FnMut(usize, &[SampleValue]),
    ) {
        let task = BlocksTask {
            it: self,
            blocks,
            stop,
            done,
        };
        match self.t.engine {
            Engine::Scalar => task.run_lanes(One),
            Engine::Auto | Engine::Packet => dispatch(task),
        }
    }
}

struct BlocksTask<'t, 'a> {
    it: &'t PathIntegrator<'a>,
    blocks: &'t [PixelSamples],
    stop: &'t (dyn Fn() -> bool + Sync),
    done: &'t mut dyn FnMut(usize, &[SampleValue]),
}

impl BlocksTask<'_, '_> {
    #[inline(always)]
    fn run_lanes<L: Lanes>(self, l: L) {
        Kernel::new(l, self.it, self.blocks, self.stop).run(self.done);
    }
}

impl SimdTask for BlocksTask<'_, '_> {
    type Output = ();
    #[inline(always)]
    fn run<S: Simd>(self, s: S) {
        self.run_lanes(s)
    }
}

/// Where blocks' finished samples wait until a block is complete.
struct Slots {
    /// Block of each slot (`usize::MAX`: free), its pixel's key, how many samples are
    /// done, its values.
    block: [usize; SLOTS],
    key: [u32; SLOTS],
    done: [u32; SLOTS],
    values: Vec<SampleValue>,
    stride: usize,
}

/// Blocks in flight at once: lanes may run ahead of a long path by this many blocks.
const SLOTS: usize = 8;

/// Per lane: a path's state between bounces.
struct Kernel<'k, 'a, L: Lanes> {
    l: L,
    it: &'k PathIntegrator<'a>,
    blocks: &'k [PixelSamples],
    stop: &'k (dyn Fn() -> bool + Sync),
    /// Lanes holding a live path.
    live: LaneBits,
    /// Slot and sample (within its block) of each lane.
    slot: [u32; LANES],
    sample: [u32; LANES],
    stream: SampleStream<L>,
    rays: RayPacket,
    beta: V3<L::F>,
    /// The product of `1 / radiance_scale` over the path's refractions: roulette
    /// reads `beta · eta_scale`, so a path inside glass (whose radiance is compressed
    /// by `(ηi/ηt)²` until it leaves again) is not ended for a factor that cancels.
    eta_scale: L::F,
    radiance: V3<L::F>,
    depth: Depth<L>,
    /// Lanes whose ray left a surface vertex (else the camera), that vertex, the BSDF
    /// pdf of the ray's direction there, and whether it was a delta lobe.
    has_prev: LaneBits,
    prev_p: V3<L::F>,
    prev_pdf: L::F,
    prev_delta: LaneBits,
    /// Lanes whose previous vertex was glossy (`DirectStrategy::MisGlossy` weights
    /// the emission their ray finds; from a diffuse vertex it is light sampling's).
    prev_glossy: LaneBits,
    /// Lanes whose first vertex from the camera does not focus light
    /// (`BsdfLanes::focus`): `Estimator::Caustics` light-traces their caustics.
    first_unfocused: LaneBits,
    /// Lanes whose previous vertex is a caustic vertex (`caustic_vertices`): the
    /// light their ray finds is light tracing's.
    prev_caustic: LaneBits,
    /// Lanes whose camera ray met a surface.
    met_surface: LaneBits,
    /// Light found after fewer bounces than this does not count (`PixelSamples::min_bounces`).
    min_bounces: L::F,
    slots: Slots,
    /// Next sample to start, as (block, sample).
    next: (usize, u32),
    stopped: bool,
    /// A ray (and stream key) to start paths with instead of the camera's.
    first_ray: Option<(Vec3, Vec3, u32)>,
}

impl<'k, 'a, L: Lanes> Kernel<'k, 'a, L> {
    #[inline(always)]
    fn new(
        l: L,
        it: &'k PathIntegrator<'a>,
        blocks: &'k [PixelSamples],
        stop: &'k (dyn Fn() -> bool + Sync),
    ) -> Self {
        let zero = V3::splat(l, Vec3::ZERO);
        let stride = blocks.iter().map(|b| b.count).max().unwrap_or(0) as usize;
        Kernel {
            l,
            it,
            blocks,
            stop,
            live: 0,
            slot: [0; LANES],
            sample: [0; LANES],
            stream: SampleStream {
                kind: it.t.s.sampler,
                key: l.u(0),
                index: l.u(0),
            },
            rays: RayPacket::default(),
            beta: zero,
            eta_scale: l.f(1.0),
            radiance: zero,
            depth: Depth::new(l),
            has_prev: 0,
            prev_p: zero,
            prev_pdf: l.f(0.0),
            prev_delta: 0,
            prev_glossy: 0,
            first_unfocused: 0,
            prev_caustic: 0,
            met_surface: 0,
            min_bounces: l.f(0.0),
            slots: Slots {
                block: [usize::MAX; SLOTS],
                key: [0; SLOTS],
                done: [0; SLOTS],
                values: vec![SampleValue::default(); SLOTS * stride],
                stride,
            },
            next: (0, 0),
            stopped: false,
            first_ray: None,
        }
    }

    #[inline(always)]
    fn run(mut self, done: &mut dyn FnMut(usize, &[SampleValue])) {
        let mut hits = HitPacket::default();
        loop {
            self.refill();
            if self.live == 0 {
                break;
            }
            trace(self.l, self.it.t.accel, &self.rays, self.live, &mut hits);
            let ended = self.bounce(&hits);
            self.finish(ended, done);
        }
    }

    // ---- lane helpers ----

    #[inline(always)]
    fn f(&self, x: f32) -> L::F {
        self.l.f(x)
    }

    #[inline(always)]
    fn mask(&self, bits: LaneBits) -> L::M {
        self.l.mask(bits)
    }

    /// The 2D point of pair `offset` of the current bounce.
    #[inline(always)]
    fn bounce_2d(&self, offset: u32) -> (L::F, L::F) {
        self.stream.get_2d(
            self.depth
                .pair_base
                .wrapping_add(self.l.u(offset + FIRST_PATH_PAIR)),
        )
    }

    /// The point of the bounce's light (or hemisphere) sample `k`. The first is
    /// stratified jointly with the pair that chose the direction arriving here (the
    /// position in the pixel at the first vertex, the previous vertex's BSDF pair
    /// after it): light reaching the pixel by one bounce is an integral over both.
    #[inline(always)]
    fn light_2d(&self, k: u32) -> (L::F, L::F) {
        if k > 0 {
            return self.bounce_2d(LIGHT_PAIRS + k);
        }
        let l = self.l;
        let base = self.depth.pair_base;
        let own = base.wrapping_add(l.u(FIRST_PATH_PAIR + LIGHT_PAIRS));
        let back = (FIRST_PATH_PAIR + BSDF_PAIR).wrapping_sub(self.it.layout.per_bounce);
        let first = self.depth.bounces.le(self.f(1.0));
        let partner = L::U::select(first, l.u(PIXEL_PAIR), base.wrapping_add(l.u(back)));
        self.stream.get_2d_coupled(partner, own)
    }

    /// Lanes of `lanes` where light found after `bounces` scattering events counts:
    /// within the settings' depths, and not below the lane's block's `min_bounces`.
    #[inline(always)]
    fn counts(&self, lanes: LaneBits) -> LaneBits {
        let deep_enough = self.depth.bounces.ge(self.min_bounces).bits();
        self.depth.counts(self.l, &self.it.t.s, lanes) & deep_enough
    }

    /// Lanes of `lanes` at the depth cap.
    #[inline(always)]
    fn at_depth_cap(&self, lanes: LaneBits) -> LaneBits {
        self.depth.at_cap(self.l, &self.it.t.s, lanes)
    }

    /// `L += beta · c` in lanes `m`.
    #[inline(always)]
    fn add_radiance(&mut self, m: LaneBits, c: V3<L::F>) {
        if m != 0 {
            let sum = self.radiance + self.beta * c;
            self.radiance = V3::select(self.mask(m), sum, self.radiance);
        }
    }

    /// Starts the next samples in the free lanes: their streams and camera rays.
    #[inline(always)]
    fn refill(&mut self) {
        let l = self.l;
        let (fresh, key, index, xy, min_bounces) = self.assign_samples();
        if fresh == 0 {
            return;
        }
        let m = self.mask(fresh);
        let stream = SampleStream {
            kind: self.it.t.s.sampler,
            key: l.u_from(key),
            index: l.u_from(index),
        };
        self.stream = SampleStream::select(m, stream, self.stream);
        let pixel = (l.f_from(xy[0]), l.f_from(xy[1]));
        let (o, d) = match self.first_ray {
            Some((o, d, _)) => (V3::splat(l, o), V3::splat(l, d)),
            None => self.it.t.camera.sample_rays(l, pixel, &self.stream),
        };
        self.rays
            .set_lanes(l, fresh, o, d, self.f(f32::INFINITY), l.u(NO_PRIM));
        let zero = V3::splat(l, Vec3::ZERO);
        self.beta = V3::select(m, V3::splat(l, Vec3::ONE), self.beta);
        self.eta_scale = L::F::select(m, self.f(1.0), self.eta_scale);
        self.min_bounces = L::F::select(m, l.f_from(min_bounces), self.min_bounces);
        self.radiance = V3::select(m, zero, self.radiance);
        self.depth.start(l, m, 0);
        self.has_prev &= !fresh;
        self.prev_delta &= !fresh;
        self.prev_glossy &= !fresh;
        self.prev_caustic &= !fresh;
        self.met_surface &= !fresh;
        self.live |= fresh;
    }

    /// Gives the free lanes the next samples, in order: the lanes started, and per
    /// lane its pixel's key, the sample's index, the pixel's `(x, y)` and its block's
    /// `min_bounces`.
    #[allow(clippy::type_complexity)]
    #[inline(always)]
    fn assign_samples(
        &mut self,
    ) -> (
        LaneBits,
        [u32; LANES],
        [u32; LANES],
        [[f32; LANES]; 2],
        [f32; LANES],
    ) {
        let width = self.it.t.camera.width as u64;
        let all = self.l.all();
        let mut fresh: LaneBits = 0;
        let mut key = [0u32; LANES];
        let mut index = [0u32; LANES];
        let mut xy = [[0.0f32; LANES]; 2];
        let mut min_bounces = [0.0f32; LANES];
        while (self.live | fresh) != all && !self.stopped {
            let (b, sample) = self.next;
            let Some(block) = self.blocks.get(b) else {
                break;
            };
            let slot = b % SLOTS;
            if sample == 0 {
                // A new block needs a free slot, and leave to start.
                if self.slots.block[slot] != usize::MAX {
                    break;
                }
                if (self.stop)() {
                    self.stopped = true;
                    break;
                }
                self.slots.block[slot] = b;
                self.slots.key[slot] = match self.first_ray {
                    Some((_, _, k)) => k,
                    None => pixel_key(self.it.t.seed, block.y as u64 * width + block.x as u64),
                };
                self.slots.done[slot] = 0;
            }
            let i = (!(self.live | fresh)).trailing_zeros() as usize;
            key[i] = self.slots.key[slot];
            index[i] = block.first + sample;
            (xy[0][i], xy[1][i]) = (block.x as f32, block.y as f32);
            self.slot[i] = slot as u32;
            self.sample[i] = sample;
            min_bounces[i] = block.min_bounces as f32;
            fresh |= 1 << i;
            self.next = if sample + 1 < block.count {
                (b, sample + 1)
            } else {
                (b + 1, 0)
            };
        }
        (fresh, key, index, xy, min_bounces)
    }

    /// Records the values of the lanes in `ended` and frees them; blocks whose
    /// samples are all done are handed to `done`.
    #[inline(always)]
    fn finish(&mut self, ended: LaneBits, done: &mut dyn FnMut(usize, &[SampleValue])) {
        if ended == 0 {
            return;
        }
        let l = self.radiance.to_arrays();
        let stride = self.slots.stride;
        for i in each_lane(ended) {
            let (slot, sample) = (self.slot[i] as usize, self.sample[i] as usize);
            self.slots.values[slot * stride + sample] = SampleValue {
                radiance: Color::new(l[0][i], l[1][i], l[2][i]),
                met_surface: self.met_surface >> i & 1 != 0,
            };
            self.slots.done[slot] += 1;
            let b = self.slots.block[slot];
            let count = self.blocks[b].count as usize;
            if self.slots.done[slot] as usize == count {
                done(b, &self.slots.values[slot * stride..slot * stride + count]);
                self.slots.block[slot] = usize::MAX;
            }
        }
        self.live &= !ended;
    }

    /// One bounce of every live lane, from its traced ray's `hits` (the body of the
    /// path loop): the lanes whose path ended.
    #[inline(always)]
    fn bounce(&mut self, hits: &HitPacket) -> LaneBits {
        let l = self.l;
        let live = self.live;
        let o = V3::from_arrays(l, &self.rays.o);
        let d = V3::from_arrays(l, &self.rays.d);
        // The unit direction, once: emission, the line test and `wo` all use it.
        let w = d.normalize();
        let hit_lanes = !l.u_from(hits.prim).eq(l.u(NO_PRIM)).bits() & live;
        self.met_surface |= hit_lanes & !self.has_prev;
        let mut ended = 0;
        // Area lights the sampled line meets before the hit end the path there.
        let with_prev = live & self.has_prev;
        if with_prev != 0 {
            ended |= self.area_light_on_line(with_prev, hits, hit_lanes, o, d, w);
        }
        let escaped = live & !hit_lanes & !ended;
        if escaped != 0 {
            self.escaped(escaped, w);
            ended |= escaped;
        }
        let lanes = live & !ended;
        if lanes == 0 {
            return ended;
        }
        let scene = self.it.t.scene;
        let mut hit = scene.hits(l, lanes, o, d, hits);
        let from_prev = lanes & self.has_prev;
        if from_prev != 0 {
            hit = hit.on_line(l, from_prev, self.prev_p, w);
        }
        let seen = self.counts(lanes);
        if seen != 0 {
            self.emitted(seen, &hit, w);
        }
        // Paths end at the depth cap and on surfaces that scatter nothing.
        let stop = self.at_depth_cap(lanes) | self.it.scattering.dark(&hit.material, lanes);
        ended |= stop;
        let lanes = lanes & !stop;
        if lanes == 0 {
            return ended;
        }
        let v = Vertex::new(l, scene, lanes, hit, w);
        let first = lanes & !self.has_prev;
        self.first_unfocused = (self.first_unfocused & !first) | (first & !v.bsdf.focus);
        self.depth
            .advance(l, self.mask(lanes), self.it.layout.per_bounce);
        let direct = self.counts(lanes) & !v.bsdf.delta;
        if direct != 0 {
            self.direct(direct, &v);
        }
        ended |= self.scatter(lanes, &v);
        ended
    }

    /// The MIS weight of emission found by a BSDF-sampled ray in lanes `lanes`, from
    /// their previous vertex, of a light whose pdf there is `light_pdf` (`None`: an
    /// emissive surface that light sampling cannot pick).
    #[inline(always)]
    fn hit_weight(&self, lanes: LaneBits, light_pdf: Option<L::F>) -> L::F {
        let (zero, one) = (self.f(0.0), self.f(1.0));
        let w = match (self.it.t.s.strategy, light_pdf) {
            // The hemisphere estimator already counted every emitter the direction finds.
            (DirectStrategy::Hemisphere, _) => zero,
            // Nothing else estimates direct light: the BSDF-sampled ray counts in full.
            (DirectStrategy::Bsdf, _) | (_, None) => one,
            (DirectStrategy::Light, Some(_)) => zero,
            (DirectStrategy::Mis | DirectStrategy::MisGlossy, Some(pdf)) => {
                let n = self.f(self.it.t.s.light_samples as f32);
                let w = power_heuristic(one, self.prev_pdf, n, pdf);
                L::F::select(self.mask(self.hits_weighted()), w, zero)
            }
        };
        L::F::select(self.mask(self.found_in_full() & lanes), one, w)
    }

    /// Lanes whose ray left the camera or a delta vertex: nothing else could have found
    /// the emission it finds, which counts in full.
    #[inline(always)]
    fn found_in_full(&self) -> LaneBits {
        !self.has_prev | self.prev_delta
    }

    /// Of vertices whose glossy lanes are `glossy`, the lanes where emission from a
    /// light that light sampling picks, found by the BSDF-sampled ray leaving them,
    /// gets a weight above zero (MIS, or BSDF sampling alone); elsewhere light sampling
    /// takes it all.
    #[inline(always)]
    fn bsdf_rays_weighted(&self, glossy: LaneBits) -> LaneBits {
        match self.it.t.s.strategy {
            DirectStrategy::Hemisphere | DirectStrategy::Light => 0,
            DirectStrategy::Mis | DirectStrategy::Bsdf => self.l.all(),
            DirectStrategy::MisGlossy => glossy,
        }
    }

    /// The lanes whose ray's emission from a light that light sampling picks gets a
    /// weight above zero (`hit_weight`): the rest leave it to light sampling.
    #[inline(always)]
    fn hits_weighted(&self) -> LaneBits {
        self.found_in_full() | self.bsdf_rays_weighted(self.prev_glossy)
    }

    /// For the lanes in `lanes` (all with a previous vertex): the area light that the
    /// line from the previous vertex along `w` meets before what the ray hit, and its
    /// MIS-weighted emission; those lanes end there (lights do not reflect).
    ///
    /// The traced ray starts off the surface by the point's rounding error
    /// (`offset_ray_origin`), on a line parallel to the sampled one and that much
    /// closer to what it finds: seen from there an area light covers more directions
    /// (a floor 2 below a light gains 2·δ/2: 0.4 % for δ = 4e-3; stability case 5),
    /// and with MIS those extra directions would get the full BSDF weight, because the
    /// light's pdf from the vertex is 0 there. So which light the sampled line reaches
    /// is decided analytically from the vertex, relative to each light
    /// (`AreaLight::intersect`); the traced ray only says what lies in front of it.
    #[inline(always)]
    fn area_light_on_line(
        &mut self,
        lanes: LaneBits,
        hits: &HitPacket,
        hit_lanes: LaneBits,
        o: V3<L::F>,
        d: V3<L::F>,
        w: V3<L::F>,
    ) -> LaneBits {
        let l = self.l;
        let prev = self.prev_p;
        let at = o + d * l.f_from(hits.t);
        let t_hit = L::F::select(
            self.mask(hit_lanes),
            (at - prev).dot(w),
            self.f(f32::INFINITY),
        );
        // The light whose surface each lane hit, from the lights' primitive ids (no
        // scene lookup: the triangle records are not in cache yet).
        let prims = l.u_from(hits.prim);
        let mut hit_light = l.u(NO_LIGHT);
        for &(prim, light) in &self.it.light_prims {
            let on = prims.eq(l.u(prim)) & self.mask(hit_lanes);
            hit_light = L::U::select(on, l.u(light), hit_light);
        }
        let mut best_t = self.f(f32::INFINITY);
        let mut best: LaneBits = 0;
        let mut best_light = l.u(0);
        for (k, light) in self.it.t.scene.lights.iter().enumerate() {
            let Light::Area(area) = light else {
                continue;
            };
            let (met, t_light) = area.intersect_l(l, prev, w);
            // The light the ray hit counts wherever the line meets it (they differ by
            // the offset).
            let own = hit_light.eq(l.u(k as u32));
            let nearer = t_light.lt(t_hit) | own;
            let better = self.mask(!best) | t_light.lt(best_t);
            let take = (met & nearer & better).bits() & lanes;
            let m = self.mask(take);
            best_t = L::F::select(m, t_light, best_t);
            best_light = L::U::select(m, l.u(k as u32), best_light);
            best |= take;
        }
        let counted = self.counts(best) & self.hits_weighted();
        if counted != 0 {
            let lights = &self.it.t.scene.lights;
            let ids = best_light.to_array();
            let area = |i: usize| lights[ids[i] as usize].as_area().expect("an area light");
            let le = per_lane_v3(w.x, |i| area(i).radiance);
            let (p, d) = (prev.to_arrays(), w.to_arrays());
            let at = |v: &[[f32; LANES]; 3], i: usize| Vec3::new(v[0][i], v[1][i], v[2][i]);
            let pdf = per_lane(w.x, |i| area(i).pdf_li(at(&p, i), at(&d, i)));
            let weight = self.hit_weight(counted, Some(pdf));
            // Light tracing's paths (`Estimator::Caustics`).
            let caustic = self.mask(self.prev_caustic & counted);
            let weight = L::F::select(caustic, self.f(0.0), weight);
            self.add_radiance(counted, le * weight);
        }
        best
    }

    /// Light from the lights at infinity reaching the escaped rays of `lanes`.
    #[inline(always)]
    fn escaped(&mut self, lanes: LaneBits, w: V3<L::F>) {
        let lanes = self.counts(lanes);
        if lanes == 0 {
            return;
        }
        let l = self.l;
        let mut sum = V3::splat(l, Vec3::ZERO);
        for light in &self.it.t.scene.lights {
            if !light.is_environment() {
                continue;
            }
            let le = light.le_escaped_l(l, w);
            let pdf = light.pdf_incident(l, self.prev_p, w);
            sum = sum + le * self.hit_weight(lanes, Some(pdf));
        }
        self.add_radiance(lanes, sum);
    }

    /// Emission at the hits of `lanes` (where it counts): area lights seen by camera
    /// rays (other vertices' were found on the line), and emissive materials.
    #[inline(always)]
    fn emitted(&mut self, lanes: LaneBits, hit: &Hits<L>, w: V3<L::F>) {
        let scene = self.it.t.scene;
        let cos_out = (-w).dot(hit.ng).to_array();
        let on_light = !self.l.u_from(hit.light).eq(self.l.u(NO_LIGHT)).bits();
        let camera_on_light = lanes & on_light & !self.has_prev;
        if camera_on_light != 0 {
            let le = per_lane_v3(w.x, |i| match scene.lights.get(hit.light[i] as usize) {
                Some(Light::Area(a)) if camera_on_light >> i & 1 != 0 => a.emitted(cos_out[i]),
                _ => Vec3::ZERO,
            });
            self.add_radiance(camera_on_light, le);
        }
        if !self.it.unsampled_emitters {
            return;
        }
        let emissive = each_lane(lanes & !on_light)
            .filter(|&i| scene.materials[hit.material[i] as usize].emits())
            .fold(0, |m, i| m | 1 << i);
        if emissive != 0 {
            let le = per_lane_v3(w.x, |i| {
                let m = &scene.materials[hit.material[i] as usize];
                m.emitted(Vec3::new(0.0, 0.0, cos_out[i]))
            });
            let weight = self.hit_weight(emissive, None);
            self.add_radiance(emissive, le * weight);
        }
    }

    /// Direct light at the (non-delta) hits of `lanes` by the chosen strategy.
    #[inline(always)]
    fn direct(&mut self, lanes: LaneBits, v: &Vertex<L>) {
        let acc = match self.it.t.s.strategy {
            DirectStrategy::Bsdf => return,
            DirectStrategy::Hemisphere => self.direct_hemisphere(lanes, v),
            DirectStrategy::Light | DirectStrategy::Mis | DirectStrategy::MisGlossy => {
                self.direct_lights(lanes, v)
            }
        };
        self.add_radiance(lanes, acc);
    }

    /// Light sampling (with MIS weights when asked): each light's samples, one shadow
    /// packet each, averaged per light and summed over the lights.
    #[inline(always)]
    fn direct_lights(&mut self, lanes: LaneBits, v: &Vertex<L>) -> V3<L::F> {
        let l = self.l;
        let zero = self.f(0.0);
        let (hit, bsdf, frame, wo) = (&v.hit, &v.bsdf, &v.frame, v.wo);
        // (From the local `wo`, as it always was: `-w` can differ in the last bit.)
        let wo_world = frame.world(wo);
        // MIS where the BSDF-sampled ray's emission also counts.
        let mis = lanes & self.bsdf_rays_weighted(v.bsdf.glossy);
        let mut acc = V3::splat(l, Vec3::ZERO);
        let mut shadow = RayPacket {
            skip: hit.prim,
            ..RayPacket::default()
        };
        let caustic = self.caustic_vertices(lanes, v);
        let mut k = 0;
        for (light, &n) in self.it.t.scene.lights.iter().zip(&self.it.light_samples) {
            let nf = self.f(n as f32);
            let lanes = match starts_caustic_paths(light) {
                true => lanes & !caustic,
                false => lanes,
            };
            for _ in 0..n {
                let u = self.light_2d(k);
                k += 1;
                let ls = light.sample_incident(l, hit.p, u);
                let wi = frame.local(ls.wi);
                let reflect = (wi.z * wo.z).gt(zero);
                let consistent = geometrically_consistent(hit.ng, wo_world, ls.wi, reflect);
                let f = bsdf.eval(l, wo, wi);
                let ok =
                    (ls.valid & ls.pdf.gt(zero) & consistent & !f.is_zero() & !ls.li.is_zero())
                        .bits()
                        & lanes;
                if ok == 0 {
                    continue;
                }
                let finite = ls.dist.is_finite().bits() & ok;
                // Finite lights: the segment to the point, stopped short of it.
                let to = V3::select(self.mask(finite), ls.p_light - hit.p, ls.wi);
                let origin = hit.spawn_origins(l, ok, to);
                let dir = V3::select(self.mask(finite), ls.p_light - origin, ls.wi);
                let t_max = L::F::select(
                    self.mask(finite),
                    self.f(1.0 - SHADOW_EPSILON),
                    self.f(f32::INFINITY),
                );
                shadow.o = origin.to_arrays();
                shadow.d = dir.to_arrays();
                shadow.t_max = t_max.to_array();
                let lit = ok & !occluded(l, self.it.t.accel, &shadow, ok);
                if lit == 0 {
                    continue;
                }
                let one = self.f(1.0);
                let weight = if mis & lit != 0 && !light.is_delta() {
                    let w = power_heuristic(nf, ls.pdf, one, bsdf.pdf(l, wo, wi));
                    L::F::select(self.mask(mis), w, one)
                } else {
                    one
                };
                let contrib = f * ls.li * (wi.z.abs() * weight / ls.pdf);
                acc = V3::select(self.mask(lit), acc + contrib / nf, acc);
            }
        }
        acc
    }

    /// Of `lanes`, the focusing vertices after an unfocused first one: light tracing
    /// takes the light that reaches them straight from the lights it starts from
    /// (`Estimator::Caustics`).
    #[inline(always)]
    fn caustic_vertices(&self, lanes: LaneBits, v: &Vertex<L>) -> LaneBits {
        match self.it.t.s.caustics_by_light {
            true => lanes & v.bsdf.focus & self.first_unfocused,
            false => 0,
        }
    }

    /// `-H`: `-l` uniform directions on the hemisphere of `wo`, counting whatever
    /// emission they find (but the area lights' at caustic vertices).
    #[inline(always)]
    fn direct_hemisphere(&mut self, lanes: LaneBits, v: &Vertex<L>) -> V3<L::F> {
        let l = self.l;
        let scene = self.it.t.scene;
        let n = self.it.t.s.light_samples;
        let (hit, bsdf, frame, wo) = (&v.hit, &v.bsdf, &v.frame, v.wo);
        let wo_world = frame.world(wo);
        let caustic = self.caustic_vertices(lanes, v);
        let mut acc = V3::splat(l, Vec3::ZERO);
        let mut rays = RayPacket::default();
        let mut found = HitPacket::default();
        for k in 0..n {
            let (u1, u2) = self.light_2d(k);
            let mut wi = uniform_hemisphere_l(u1, u2);
            wi.z = L::F::select(wo.z.lt(self.f(0.0)), -wi.z, wi.z);
            let wi_world = frame.world(wi);
            let f = bsdf.eval(l, wo, wi);
            let consistent =
                geometrically_consistent(hit.ng, wo_world, wi_world, self.mask(l.all()));
            let ok = (consistent & !f.is_zero()).bits() & lanes;
            if ok == 0 {
                continue;
            }
            let origin = hit.spawn_origins(l, ok, wi_world);
            rays.o = origin.to_arrays();
            rays.d = wi_world.to_arrays();
            rays.t_max = [f32::INFINITY; LANES];
            rays.skip = hit.prim;
            trace(l, self.it.t.accel, &rays, ok, &mut found);
            let met = !l.u_from(found.prim).eq(l.u(NO_PRIM)).bits() & ok;
            let mut le = V3::splat(l, Vec3::ZERO);
            for light in &scene.lights {
                le = le + light.le_escaped_l(l, wi_world);
            }
            le = V3::select(self.mask(met), V3::splat(l, Vec3::ZERO), le);
            if met != 0 {
                let there = scene.hits(l, met, origin, wi_world, &found);
                let cos_out = (-wi_world).dot(there.ng);
                let emitted = per_lane_v3(wi_world.x, |i| {
                    if met >> i & 1 == 0 {
                        return Vec3::ZERO;
                    }
                    match scene.lights.get(there.light[i] as usize) {
                        Some(Light::Area(a))
                            if caustic >> i & 1 == 0
                                && a.intersect(hit.p.lane(i), wi_world.lane(i)).is_some() =>
                        {
                            a.emitted(cos_out.lane(i))
                        }
                        Some(_) => Vec3::ZERO,
                        None => scene.materials[there.material[i] as usize].emitted(Vec3::new(
                            0.0,
                            0.0,
                            cos_out.lane(i),
                        )),
                    }
                });
                le = V3::select(self.mask(met), emitted, le);
            }
            let contrib = f * le * (wi.z.abs() / self.f(uniform_hemisphere_pdf()));
            acc = V3::select(self.mask(ok), acc + contrib, acc);
        }
        acc / self.f(n as f32)
    }

    /// Samples each lane's BSDF, checks the depth cap and the geometry, updates the
    /// throughput, plays roulette and spawns the next rays: the lanes whose path ended.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn scatter(&mut self, lanes: LaneBits, v: &Vertex<L>) -> LaneBits {
        let l = self.l;
        let u = self.bounce_2d(BSDF_PAIR);
        // The lobe and roulette pair only where a BSDF chooses a lobe or roulette plays
        // (each pair is drawn by its number: leaving one undrawn changes no other).
        let lobe_pair = (lanes & v.bsdf.chooses_lobe != 0).then(|| self.bounce_2d(LOBE_PAIR));
        let u_lobe = lobe_pair.map_or(self.f(0.0), |p| p.0);
        let (bs, wi_world, go) = v.sample_next(l, lanes, u_lobe, u);
        let mut ended = lanes & !go;
        let cap = self.at_depth_cap(lanes);
        // At the depth cap the BSDF-sampled ray is traced only where the light it finds
        // counts: weighted against light sampling, from emitters light sampling cannot
        // pick (every strategy but hemisphere sampling, which finds them itself), or
        // through a delta lobe (whose light nothing else finds).
        let unsampled =
            self.it.unsampled_emitters && self.it.t.s.strategy != DirectStrategy::Hemisphere;
        let finds_light = match unsampled {
            true => l.all(),
            false => self.bsdf_rays_weighted(v.bsdf.glossy),
        };
        ended |= cap & !v.bsdf.delta & !finds_light;
        let go = lanes & !ended;
        let beta = self.beta * bs.weight;
        let eta_scale = self.eta_scale / v.bsdf.radiance_scale(l, v.wo, bs.wi);
        let roulette = &self.it.t.s.roulette;
        let read = beta * eta_scale;
        let bounces = self.depth.bounces;
        // At the depth cap the next ray only looks for emission (MIS, emitters light
        // sampling cannot pick, delta lobes): ending it would save that one ray and
        // nothing after it, at the cost of the variance roulette adds. It is spared.
        let played = (go, cap & go);
        let u_roulette = || lobe_pair.unwrap_or_else(|| self.bounce_2d(LOBE_PAIR)).1;
        let (survive, beta) = roulette.play_l(l, bounces, played, (beta, read), u_roulette);
        ended |= lanes & !survive;
        if survive != 0 {
            let m = self.mask(survive);
            self.beta = V3::select(m, beta, self.beta);
            self.eta_scale = L::F::select(m, eta_scale, self.eta_scale);
            self.prev_p = V3::select(m, v.hit.p, self.prev_p);
            self.prev_pdf = L::F::select(m, bs.pdf, self.prev_pdf);
            self.has_prev |= survive;
            self.prev_delta = (self.prev_delta & !survive) | (v.bsdf.delta & survive);
            self.prev_glossy = (self.prev_glossy & !survive) | (v.bsdf.glossy & survive);
            let caustic = self.caustic_vertices(survive, v);
            self.prev_caustic = (self.prev_caustic & !survive) | caustic;
            let origin = v.hit.spawn_origins(l, survive, wi_world);
            let (t_max, skip) = (self.f(f32::INFINITY), l.u_from(v.hit.prim));
            self.rays
                .set_lanes(l, survive, origin, wi_world, t_max, skip);
        }
        ended
    }
}

/// Rejects directions whose side of the geometric surface contradicts the BSDF's
/// (shading-frame) reflection/transmission choice, so shading normals cannot leak light.
#[inline(always)]
pub(super) fn geometrically_consistent<F: Real>(
    ng: V3<F>,
    wo: V3<F>,
    wi: V3<F>,
    reflect: F::M,
) -> F::M {
    let ab = wo.dot(ng) * wi.dot(ng);
    let zero = ab.splat_as(0.0);
    (reflect & ab.gt(zero)) | (!reflect & ab.lt(zero))
}

/// The nearest hits of the rays in `lanes` (one ray, or a packet).
#[inline(always)]
pub(super) fn trace<L: Lanes>(
    _: L,
    accel: &dyn Accel,
    rays: &RayPacket,
    lanes: LaneBits,
    hits: &mut HitPacket,
) {
    if L::WIDTH == 1 {
        hits.set(0, accel.intersect(&rays.ray(0)));
    } else {
        accel.intersect_packet(rays, lanes, hits);
    }
}

/// The lanes of `lanes` whose ray is blocked.
#[inline(always)]
pub(super) fn occluded<L: Lanes>(
    _: L,
    accel: &dyn Accel,
    rays: &RayPacket,
    lanes: LaneBits,
) -> LaneBits {
    if L::WIDTH == 1 {
        accel.occluded(&rays.ray(0)) as LaneBits & lanes
    } else {
        accel.occluded_packet(rays, lanes)
    }
}
