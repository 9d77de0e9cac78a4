//! Light tracing (particle tracing; pbrt-v4 `LightPathIntegrator`, Mitsuba 3
//! `ptracer`): paths start on the lights, and every non-specular vertex is connected
//! to the camera (the eye, or a point drawn on the thin lens) and splatted into the
//! pixel that sees it.
//!
//! What it estimates: every path of `1…m` bounces (spec §7) that starts on a `Light`
//! (area, point, directional, ambient). Paths of 0 bounces (area lights, emissive
//! surfaces and the ambient sky seen directly) are estimated from the camera, exactly
//! as `-m 0` does, because a light path cannot hit a pinhole. Two kinds of path are
//! out of its reach, and `warnings` says so: specular surfaces seen by the camera
//! (a mirror or glass vertex cannot be connected to a pinhole), and emissive
//! surfaces that are not lights (nothing starts a path there).
//!
//! Written once over the lane type, as the path tracer is: one path at a time
//! (`--engine scalar`) or sixteen, one per SIMD lane, with the same BSDF, light and
//! hit code.
//!
//! Determinism: a render is `spp·W·H` light paths, numbered; each chunk of
//! `CHUNK_PATHS` draws its numbers as one stratified set; a chunk's splats are put in
//! path order whichever lanes traced them, and the render driver adds them chunk by
//! chunk in order, so the image depends on the seed only.

use super::path::{geometrically_consistent, occluded, trace};
use super::vertex::{Depth, Scattering, Vertex};
use super::Engine;
use super::{
    starts_caustic_paths, PathIntegrator, PathSettings, SampleIntegrator, Splat, SplatIntegrator,
    Tracing,
};
use crate::geometry::NO_PRIM;
use crate::lanes::rays::{HitPacket, RayPacket};
use crate::lanes::{
    dispatch, each_lane, LaneBits, LaneMask, Lanes, One, Real, Simd, SimdTask, UInt, LANES, V3,
};
use crate::lights::emit::{EmissionAim, EmissionSample};
use crate::lights::Light;
use crate::materials::Material;
use crate::sampling::{pixel_key, SampleStream};
use crate::scene::{Hits, Scene};
use crate::Color;
use glam::{Vec2, Vec3};
use std::cell::RefCell;

/// Light paths per chunk: each chunk's paths are one stratified set (the chunk plays
/// the part of a pixel), and a render's splats are added chunk by chunk, in order.
pub const CHUNK_PATHS: u64 = 4096;

/// The dimension pairs of a light path: the light's choice, the point on it and the
/// direction leaving it, then per bounce the lens point, the BSDF direction and the
/// lobe choice with roulette.
const CHOICE_PAIR: u32 = 0;
const POSITION_PAIR: u32 = 1;
const DIRECTION_PAIR: u32 = 2;
const PAIRS_PER_BOUNCE: u32 = 3;

pub struct LightTracer<'a> {
    t: Tracing<'a>,
    scattering: Scattering,
    /// Cumulative light-selection probabilities, proportional to emitted power.
    light_cdf: Vec<f32>,
    /// For caustics: the sphere around the focusing surfaces, which point and
    /// directional lights aim their paths at (every other path ends at its first hit).
    aim: Option<EmissionAim>,
    /// Emitters seen directly (0-bounce paths), which only camera rays can find.
    direct: Option<PathIntegrator<'a>>,
    draws: StartDraws,
}

/// Which numbers a path's start reads: the light's choice (when more than one light
/// emits) and the point on it (unless every light that emits is a point).
#[derive(Clone, Copy)]
struct StartDraws {
    choice: bool,
    position: bool,
}

impl<'a> LightTracer<'a> {
    pub fn new(t: Tracing<'a>) -> Self {
        let (scene, s) = (t.scene, t.s);
        let radius = 0.5 * scene.bounds.diagonal().length();
        let radius = if radius.is_finite() { radius } else { 1.0 };
        let starts = |l: &Light| !s.caustics_by_light || starts_caustic_paths(l);
        let power: Vec<f32> = (scene.lights.iter())
            .map(|l| if starts(l) { l.power(radius) } else { 0.0 })
            .collect();
        let emitting = || (scene.lights.iter().zip(&power)).filter(|&(_, &p)| p > 0.0);
        let draws = StartDraws {
            choice: emitting().count() > 1,
            position: emitting().any(|(l, _)| l.samples_position()),
        };
        let total: f32 = power.iter().sum();
        let mut acc = 0.0;
        let light_cdf = power
            .iter()
            .map(|p| {
                acc += p;
                if total > 0.0 {
                    acc / total
                } else {
                    0.0
                }
            })
            .collect();
        let zero_bounces = PathSettings {
            max_depth: 0,
            accumulate: true,
            ..s
        };
        let counts_zero = s.accumulate || s.max_depth == 0;
        let camera_pass = counts_zero && has_visible_emitters(scene) && !s.caustics_by_light;
        let direct = camera_pass.then(|| {
            PathIntegrator::new(Tracing {
                s: zero_bounces,
                ..t
            })
        });
        LightTracer {
            t,
            scattering: Scattering::of(scene),
            light_cdf,
            aim: s
                .caustics_by_light
                .then(|| specular_bounds(scene))
                .flatten(),
            direct,
            draws,
        }
    }

    /// A path's start: the point and direction drawn on the light chosen by `u_choice`,
    /// and its throughput (divided by the light's selection probability); `None` when
    /// it carries nothing.
    fn emit(&self, u_choice: f32, u_pos: Vec2, u_dir: Vec2) -> Option<(EmissionSample, Color)> {
        let (li, p_light) = self.pick_light(u_choice)?;
        let light = &self.t.scene.lights[li];
        let es = light.sample_le(&self.t.scene.bounds, self.aim, u_pos, u_dir)?;
        let beta = es.beta / p_light;
        let beta0 = beta.max_element();
        (!beta0.is_nan() && beta0 > 0.0).then_some((es, beta))
    }

    /// A light index chosen in proportion to power, and its probability.
    fn pick_light(&self, u: f32) -> Option<(usize, f32)> {
        let i = self.light_cdf.iter().position(|&c| u < c)?;
        let prev = if i == 0 { 0.0 } else { self.light_cdf[i - 1] };
        let p = self.light_cdf[i] - prev;
        (p > 0.0).then_some((i, p))
    }
}

/// Whether `Estimator::Caustics` differs from path tracing on `scene` at `max_depth`:
/// a focusing surface (`Material::focuses`), a light that starts caustic paths and
/// emits, a scattering surface that does not focus to receive them, and at least two
/// bounces (light → focusing → unfocused surface seen by the camera).
pub fn caustics_possible(scene: &Scene, max_depth: u32) -> bool {
    let receives = |m: &Material| m.scatters() && !m.focuses();
    max_depth >= 2
        && scene.materials.iter().any(|m| m.focuses())
        && scene.materials.iter().any(receives)
        && scene.lights.iter().any(starts_emitting_caustic_paths)
}

/// A light that starts caustic paths and emits something.
fn starts_emitting_caustic_paths(light: &Light) -> bool {
    starts_caustic_paths(light) && light.power(1.0) > 0.0
}

/// The bounding sphere of the scene's focusing surfaces, if it has any.
fn specular_bounds(scene: &Scene) -> Option<EmissionAim> {
    // Primitive ids number the triangles first, then the spheres.
    let materials = (scene.triangles.iter().map(|t| t.material))
        .chain(scene.spheres.iter().map(|s| s.material));
    let b = (0..)
        .zip(materials)
        .filter(|&(_, m)| scene.materials[m as usize].focuses())
        .map(|(prim, _)| scene.prim_bounds(prim))
        .reduce(|a, b| a.union(&b))?;
    EmissionAim::around(&b)
}

/// Whether path tracing alone misses light on `scene` at `max_depth`: caustics are
/// possible and a point, spot or directional light can start one, which no camera
/// path can find.
pub fn path_misses_caustics(scene: &Scene, max_depth: u32) -> bool {
    caustics_possible(scene, max_depth)
        && (scene.lights.iter()).any(|l| l.is_delta() && starts_emitting_caustic_paths(l))
}

/// Per lane: a light path's state between bounces. Lanes are refilled with the next
/// paths as paths end; each lane does exactly what the path alone would, so the
/// splats (put back in path order) do not depend on the lane type.
struct LightKernel<'k, 'a, L: Lanes> {
    l: L,
    it: &'k LightTracer<'a>,
    live: LaneBits,
    /// The path number of each lane.
    path: [u64; LANES],
    stream: SampleStream<L>,
    rays: RayPacket,
    beta: V3<L::F>,
    /// Each path's starting throughput, which roulette divides by.
    beta0: L::F,
    depth: Depth<L>,
    /// Where each ray's line starts (lanes of `has_from`): the point it left.
    from: V3<L::F>,
    has_from: LaneBits,
    /// Lanes whose ray leaves the light (their next hit is the path's first vertex).
    from_light: LaneBits,
    /// The range's first path, the next to start, and the end of the range.
    first: u64,
    next: u64,
    end: u64,
    /// Splats with their path number (the worker's buffer, `TAGGED`), and
    /// non-finite contributions dropped.
    splats: Vec<(u64, Splat)>,
    nonfinite: u32,
}

impl<'k, 'a, L: Lanes> LightKernel<'k, 'a, L> {
    #[inline(always)]
    fn new(
        l: L,
        it: &'k LightTracer<'a>,
        first: u64,
        count: u64,
        splats: Vec<(u64, Splat)>,
    ) -> Self {
        let zero = V3::splat(l, Vec3::ZERO);
        LightKernel {
            l,
            it,
            live: 0,
            path: [0; LANES],
            stream: SampleStream {
                kind: it.t.s.sampler,
                key: l.u(0),
                index: l.u(0),
            },
            rays: RayPacket::default(),
            beta: zero,
            beta0: l.f(1.0),
            depth: Depth::new(l),
            from: zero,
            has_from: 0,
            from_light: 0,
            first,
            next: first,
            end: first + count,
            splats,
            nonfinite: 0,
        }
    }

    /// Traces every path of the range; its splats in path order. Returns the count of
    /// non-finite contributions, and the (emptied) tagged buffer for the next range.
    #[inline(always)]
    fn run(mut self, out: &mut Vec<Splat>) -> (u32, Vec<(u64, Splat)>) {
        let mut hits = HitPacket::default();
        loop {
            self.refill();
            if self.live == 0 {
                break;
            }
            trace(self.l, self.it.t.accel, &self.rays, self.live, &mut hits);
            let ended = self.bounce(&hits);
            self.live &= !ended;
        }
        if L::WIDTH == 1 {
            out.extend(self.splats.iter().map(|&(_, splat)| splat));
        } else {
            in_path_order(&self.splats, self.first, self.end, out);
        }
        self.splats.clear();
        (self.nonfinite, self.splats)
    }

    /// Starts the next paths in the free lanes: a light, a point and a direction.
    #[inline(always)]
    fn refill(&mut self) {
        while self.live != self.l.all() && self.next < self.end {
            let fresh = self.assign_paths();
            self.start(fresh);
        }
    }

    /// Gives the free lanes the next paths of the range and their streams: the lanes.
    #[inline(always)]
    fn assign_paths(&mut self) -> LaneBits {
        let l = self.l;
        let (mut fresh, mut key, mut index) = (0 as LaneBits, [0u32; LANES], [0u32; LANES]);
        for i in each_lane(l.all() & !self.live) {
            if self.next == self.end {
                break;
            }
            let path = self.next;
            self.next += 1;
            self.path[i] = path;
            key[i] = pixel_key(self.it.t.seed ^ LIGHT_PATHS, path / CHUNK_PATHS);
            index[i] = (path % CHUNK_PATHS) as u32;
            fresh |= 1 << i;
        }
        let stream = SampleStream {
            kind: self.it.t.s.sampler,
            key: l.u_from(key),
            index: l.u_from(index),
        };
        self.stream = SampleStream::select(l.mask(fresh), stream, self.stream);
        fresh
    }

    /// Starts the paths of lanes `fresh` on the lights; a path that carries nothing
    /// leaves its lane free.
    #[inline(always)]
    fn start(&mut self, fresh: LaneBits) {
        let l = self.l;
        // Numbers no light reads are not drawn (each pair is drawn by its number, so
        // the others do not change).
        let unread = ([0.0f32; LANES], [0.0f32; LANES]);
        let choice = match self.it.draws.choice {
            true => self.pair_arrays(CHOICE_PAIR),
            false => unread,
        };
        let pos = match self.it.draws.position {
            true => self.pair_arrays(POSITION_PAIR),
            false => unread,
        };
        let dir = self.pair_arrays(DIRECTION_PAIR);
        let [mut o, mut d, mut from, mut beta] = [[[0.0f32; LANES]; 3]; 4];
        let mut beta0 = [1.0f32; LANES];
        let (mut started, mut has_from) = (0 as LaneBits, 0 as LaneBits);
        for i in each_lane(fresh) {
            let u = |p: &([f32; LANES], [f32; LANES])| Vec2::new(p.0[i], p.1[i]);
            let Some((es, b)) = self.it.emit(u(&choice).x, u(&pos), u(&dir)) else {
                continue;
            };
            (o[0][i], o[1][i], o[2][i]) = es.origin.into();
            (d[0][i], d[1][i], d[2][i]) = es.dir.into();
            (beta[0][i], beta[1][i], beta[2][i]) = b.into();
            beta0[i] = b.max_element();
            if let Some(p) = es.on_surface {
                (from[0][i], from[1][i], from[2][i]) = p.into();
                has_from |= 1 << i;
            }
            started |= 1 << i;
        }
        let m = l.mask(started);
        let (o, d) = (V3::from_arrays(l, &o), V3::from_arrays(l, &d));
        self.rays
            .set_lanes(l, started, o, d, l.f(f32::INFINITY), l.u(NO_PRIM));
        self.beta = V3::select(m, V3::from_arrays(l, &beta), self.beta);
        self.beta0 = L::F::select(m, l.f_from(beta0), self.beta0);
        self.depth.start(l, m, DIRECTION_PAIR + 1);
        self.from = V3::select(m, V3::from_arrays(l, &from), self.from);
        self.has_from = (self.has_from & !started) | has_from;
        self.from_light |= started;
        self.live |= started;
    }

    /// Pair `pair` of every lane, as arrays. (A method, not a closure: a closure the
    /// compiler does not inline loses the instruction set it was written for.)
    #[inline(always)]
    fn pair_arrays(&self, pair: u32) -> ([f32; LANES], [f32; LANES]) {
        let (x, y) = self.stream.get_2d(self.l.u(pair));
        (x.to_array(), y.to_array())
    }

    /// One vertex of every live lane: its connection to the camera, then the next
    /// direction. The lanes whose path ended.
    #[inline(always)]
    fn bounce(&mut self, hits: &HitPacket) -> LaneBits {
        let l = self.l;
        let it = self.it;
        let live = self.live;
        let o = V3::from_arrays(l, &self.rays.o);
        let d = V3::from_arrays(l, &self.rays.d);
        let hit_lanes = !l.u_from(hits.prim).eq(l.u(NO_PRIM)).bits() & live;
        let mut ended = live & !hit_lanes;
        if hit_lanes == 0 {
            return ended;
        }
        let w = d.normalize();
        let mut hit = it.t.scene.hits(l, hit_lanes, o, d, hits);
        let on_line = hit_lanes & self.has_from;
        if on_line != 0 {
            hit = hit.on_line(l, on_line, self.from, w);
        }
        let dark = it.scattering.dark(&hit.material, hit_lanes);
        let stop = dark | self.depth.at_cap(l, &it.t.s, hit_lanes);
        ended |= stop;
        let lanes = hit_lanes & !stop;
        if lanes == 0 {
            return ended;
        }
        // Its `wo` points back toward the light.
        let v = Vertex::new(l, it.t.scene, lanes, hit, w);
        let first = self.from_light & lanes;
        self.from_light &= !live;
        // Caustics only: a path whose first vertex does not focus light is the path
        // tracer's.
        let lanes = if it.t.s.caustics_by_light {
            let not_caustic = first & !v.bsdf.focus;
            ended |= not_caustic;
            lanes & !not_caustic
        } else {
            lanes
        };
        if lanes == 0 {
            return ended;
        }
        // The pairs of this bounce: the lens point, the BSDF direction, lobe and roulette.
        self.depth.advance(l, l.mask(lanes), PAIRS_PER_BOUNCE);
        // Caustics only: the path tracer takes the paths whose vertex seen by the
        // camera focuses light.
        let unconnected = match it.t.s.caustics_by_light {
            true => v.bsdf.focus,
            false => v.bsdf.delta,
        };
        let connect = self.depth.counts(l, &it.t.s, lanes) & !unconnected;
        if connect != 0 {
            self.connect_to_camera(connect, &v);
        }
        ended |= self.depth.at_cap(l, &it.t.s, lanes);
        let lanes = lanes & !ended;
        if lanes == 0 {
            return ended;
        }
        ended | self.scatter(lanes, &v)
    }

    /// Samples each lane's BSDF from the light side, updates the power the path
    /// carries, plays roulette and spawns the next rays: the lanes whose path ended.
    #[inline(always)]
    fn scatter(&mut self, lanes: LaneBits, v: &Vertex<L>) -> LaneBits {
        let l = self.l;
        let base = self.depth.pair_base;
        let u = self.stream.get_2d(base.wrapping_add(l.u(1)));
        // The lobe and roulette pair only where a BSDF chooses a lobe or roulette plays.
        let draw_lobe_pair = || self.stream.get_2d(base.wrapping_add(l.u(2)));
        let lobe_pair = (lanes & v.bsdf.chooses_lobe != 0).then(draw_lobe_pair);
        let u_lobe = lobe_pair.map_or(l.f(0.0), |p| p.0);
        let (bs, w_next, go) = v.sample_next(l, lanes, u_lobe, u);
        let adjoint = adjoint_factor(l, v, bs.wi, w_next);
        let beta = self.beta * (bs.weight * adjoint);
        let roulette = &self.it.t.s.roulette;
        let read = beta / self.beta0;
        let bounces = self.depth.bounces;
        let u_roulette = || lobe_pair.unwrap_or_else(draw_lobe_pair).1;
        let (survive, beta) = roulette.play_l(l, bounces, (go, 0), (beta, read), u_roulette);
        if survive != 0 {
            let m = l.mask(survive);
            self.beta = V3::select(m, beta, self.beta);
            self.from = V3::select(m, v.hit.p, self.from);
            self.has_from |= survive;
            let origin = v.hit.spawn_origins(l, survive, w_next);
            let (t_max, skip) = (l.f(f32::INFINITY), l.u_from(v.hit.prim));
            self.rays.set_lanes(l, survive, origin, w_next, t_max, skip);
        }
        lanes & !survive
    }

    /// Connects the non-specular vertices of `lanes`, lit along `w_light` (`wl` in
    /// the shading frame) with power `beta`, to the eye, splatting what it sees.
    #[inline(always)]
    fn connect_to_camera(&mut self, lanes: LaneBits, v: &Vertex<L>) {
        let l = self.l;
        let (hit, bsdf, frame) = (&v.hit, &v.bsdf, &v.frame);
        let (wl, w_light) = (v.wo, v.wo_world);
        let camera = self.it.t.camera;
        // The lens point's pair is this bounce's first (drawn only with a lens).
        let u_lens = || self.stream.get_2d(self.depth.pair_base);
        let c = camera.connect_l(l, lanes, hit.p, u_lens);
        let seen = c.seen;
        if seen == 0 {
            return;
        }
        let zero = l.f(0.0);
        let to_eye = c.to_eye;
        let wc = frame.local(to_eye);
        let consistent = geometrically_consistent(hit.ng, to_eye, w_light, (wl.z * wc.z).gt(zero));
        let f = bsdf.eval(l, wc, wl);
        // The path tracer's |cos| is taken with the shading normal on the light side;
        // Veach's adjoint correction (thesis §5.3) turns the geometric cosine toward the
        // camera into that.
        let cos = shading_correction(hit, wl, w_light) * to_eye.dot(hit.ng).abs();
        let value = self.beta * f * (cos * c.importance);
        let ok = seen & (consistent & !f.is_zero()).bits();
        let finite = value.is_finite().bits();
        self.nonfinite += (ok & !finite).count_ones();
        let ok = ok & finite & !value.is_zero().bits();
        if ok == 0 {
            return;
        }
        let eye = c.origin;
        let origin = hit.spawn_origins(l, ok, eye - hit.p);
        let shadow = RayPacket {
            o: origin.to_arrays(),
            d: (eye - origin).to_arrays(),
            t_max: [1.0; LANES],
            skip: hit.prim,
        };
        let lit = ok & !occluded(l, self.it.t.accel, &shadow, ok);
        let value = value.to_arrays();
        let (u, v) = (c.u.to_array(), c.v.to_array());
        for i in each_lane(lit) {
            let (x, y) = camera.pixel_at(u[i], v[i]);
            let value = Color::new(value[0][i], value[1][i], value[2][i]);
            self.splats.push((self.path[i], (x, y, value)));
        }
    }
}

/// Appends `splats` (of paths `first..end`, lanes' paths interleaved) to `out` in the
/// order one path at a time gives: by path, each path's in the order it made them (a
/// counting sort, stable).
fn in_path_order(splats: &[(u64, Splat)], first: u64, end: u64, out: &mut Vec<Splat>) {
    let mut start = vec![0usize; (end - first) as usize + 1];
    for &(path, _) in splats {
        start[(path - first) as usize + 1] += 1;
    }
    for k in 1..start.len() {
        start[k] += start[k - 1];
    }
    let base = out.len();
    out.resize(base + splats.len(), (0, 0, Color::ZERO));
    for &(path, splat) in splats {
        let slot = &mut start[(path - first) as usize];
        out[base + *slot] = splat;
        *slot += 1;
    }
}

/// The light path task, run with the best instruction set.
struct PathsTask<'t, 'a> {
    it: &'t LightTracer<'a>,
    first: u64,
    count: u64,
    tagged: Vec<(u64, Splat)>,
    splats: &'t mut Vec<Splat>,
}

impl SimdTask for PathsTask<'_, '_> {
    type Output = (u32, Vec<(u64, Splat)>);
    #[inline(always)]
    fn run<S: Simd>(self, s: S) -> Self::Output {
        LightKernel::new(s, self.it, self.first, self.count, self.tagged).run(self.splats)
    }
}

thread_local! {
    /// Each worker's buffer of tagged splats, kept from chunk to chunk: a chunk's
    /// fill a few hundred kB, which a new vector would grow and fault in page by page.
    static TAGGED: RefCell<Vec<(u64, Splat)>> = const { RefCell::new(Vec::new()) };
}

impl SplatIntegrator for LightTracer<'_> {
    fn trace_paths(&self, first: u64, count: u64, splats: &mut Vec<Splat>) -> u32 {
        let tagged = TAGGED.take();
        let (nonfinite, tagged) = match self.t.engine {
            Engine::Scalar => LightKernel::new(One, self, first, count, tagged).run(splats),
            Engine::Auto | Engine::Packet => dispatch(PathsTask {
                it: self,
                first,
                count,
                tagged,
                splats,
            }),
        };
        TAGGED.set(tagged);
        nonfinite
    }

    fn camera_part(&self) -> Option<&dyn SampleIntegrator> {
        self.direct.as_ref().map(|p| p as &dyn SampleIntegrator)
    }
}

/// Mixed into the seed of light paths, so they do not share the pixels' streams.
const LIGHT_PATHS: u64 = 0x4C54_0001;

/// `|wl·ns|/|wl·ng|`: the shading-normal factor of the adjoint BSDF (0 when grazing).
#[inline(always)]
fn shading_correction<L: Lanes>(hit: &Hits<L>, wl_local: V3<L::F>, w_light: V3<L::F>) -> L::F {
    let g = w_light.dot(hit.ng).abs();
    let zero = g.splat_as(0.0);
    L::F::select(g.gt(zero), wl_local.z.abs() / g, zero)
}

/// What turns a BSDF sample drawn from the light side (`wl`, its weight
/// `f·|cos θ_next|/pdf` in the shading frame) into the adjoint transport of power:
/// Veach's shading-normal correction `|wl·ns|·|w_next·ng| / (|wl·ng|·|w_next·ns|)`, and,
/// for refraction, no `(ηi/ηt)²` radiance scaling (power is not compressed by refraction).
#[inline(always)]
fn adjoint_factor<L: Lanes>(l: L, v: &Vertex<L>, w_next_local: V3<L::F>, w_next: V3<L::F>) -> L::F {
    let (hit, wl) = (&v.hit, v.wo);
    let ns_next = w_next_local.z.abs();
    let k = shading_correction(hit, wl, v.wo_world) * w_next.dot(hit.ng).abs() / ns_next;
    let k = k / v.bsdf.radiance_scale(l, wl, w_next_local);
    L::F::select(ns_next.gt(l.f(0.0)), k, l.f(0.0))
}

/// Emitters a camera ray can see directly (they need the camera pass).
fn has_visible_emitters(scene: &Scene) -> bool {
    scene.lights.iter().any(|l| !l.is_delta()) || scene.materials.iter().any(|m| m.emits())
}

/// What light tracing to depth `max_depth` cannot show in `scene`, said out loud.
pub fn warnings(scene: &Scene, max_depth: u32) -> Vec<String> {
    let mut w = Vec::new();
    if max_depth > 0 && scene.materials.iter().any(|m| m.is_delta()) {
        w.push(
            "light tracing cannot connect mirror or glass surfaces to the pinhole camera: \
             they look black except for light they transmit from behind; use path tracing"
                .into(),
        );
    }
    if max_depth > 0 && scene.has_unsampled_emitters() {
        w.push(
            "light tracing starts paths on lights only: light that emissive surfaces \
             (not lights) cast on the scene is missing; use path tracing"
                .into(),
        );
    }
    if max_depth > 0
        && scene
            .lights
            .iter()
            .any(|l| matches!(l, Light::Environment(_)))
    {
        w.push(
            "light tracing starts no paths on environment maps: the light they cast \
             on the scene is missing; use path tracing"
                .into(),
        );
    }
    w
}
