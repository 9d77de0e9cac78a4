//! The path tracer of `path.rs` run on sixteen paths at once, one per SIMD lane,
//! for the scenes whose every part it covers: Lambertian surfaces lit by area
//! lights, light sampling or MIS (the defaults there). Each lane performs the
//! same floating-point operations as `PathIntegrator::li` on the same random
//! numbers (one stream per pixel sample, drawn in the same order), so a pixel is
//! the scalar engine's pixel whatever the lanes beside it hold; rays are traced
//! sixteen at a time (`Accel::intersect_packet`, `occluded_packet`).
//!
//! Lanes are refilled as paths end (a path that escapes at once frees its lane
//! for the next sample), taking the samples of a tile's pixels in order. A pixel's
//! samples are summed in sample order once all are done, as the scalar renderer
//! sums them.

use super::{DirectStrategy, Roulette};
use crate::accel::{Accel, HitPacket, RayPacket};
use crate::camera::Camera;
use crate::geometry::ray::gamma;
use crate::geometry::NO_PRIM;
use crate::lights::{AreaLight, Light};
use crate::materials::Material;
use crate::sampling::{concentric_disk, PixelStreams, Sampler};
use crate::scene::{Scene, NO_LIGHT};
use crate::simd::{dispatch, F32s, LaneBits, Mask, Simd, SimdTask, U32s, Vec3s, ALL_LANES, LANES};
use crate::Color;
use glam::{Vec2, Vec3};
use std::f32::consts::FRAC_1_PI;

use super::path::{PathSettings, SHADOW_EPSILON};

/// Why a scene or setting needs the scalar path tracer.
pub fn unsupported(scene: &Scene, s: &PathSettings) -> Option<&'static str> {
    if !matches!(s.strategy, DirectStrategy::Light | DirectStrategy::Mis) {
        return Some("hemisphere and BSDF-only sampling");
    }
    let lambertian = |m: &Material| matches!(m, Material::Lambertian { .. } | Material::Black);
    if !scene.materials.iter().all(lambertian) {
        return Some("materials other than Lambertian");
    }
    if scene.lights.is_empty() || !scene.lights.iter().all(|l| matches!(l, Light::Area(_))) {
        return Some("lights other than area lights");
    }
    if scene.has_unsampled_emitters() {
        return Some("emissive surfaces");
    }
    None
}

/// One pixel sample's result, as the scalar renderer records it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SampleValue {
    pub radiance: Color,
}

/// Renders pixel samples of a scene that [`unsupported`] accepts.
pub struct PacketPathIntegrator<'a> {
    scene: &'a Scene,
    accel: &'a dyn Accel,
    camera: &'a Camera,
    max_depth: u32,
    accumulate: bool,
    light_samples: u32,
    mis: bool,
    roulette: Roulette,
    lights: Vec<AreaLight>,
}

/// The pixels of a tile and where their results go: `value(i, sum, n)` is called
/// once per pixel `pixels[i]`, with the sum of its samples' radiance in sample
/// order and the count of non-finite samples (counted as black).
pub struct TileWork<'t> {
    pub pixels: &'t [(u32, u32)],
    pub spp: u32,
    pub spp_offset: u32,
    pub seed: u64,
    /// Checked before each pixel is started; a pixel not started is not reported.
    pub stop: &'t (dyn Fn() -> bool + Sync),
}

/// A finished pixel: the sum of its samples in order, and how many were not finite.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PixelSum {
    pub sum: Color,
    pub nonfinite: u32,
}

impl<'a> PacketPathIntegrator<'a> {
    /// `None` when the scene or settings need the scalar engine ([`unsupported`]).
    pub fn new(
        scene: &'a Scene,
        accel: &'a dyn Accel,
        camera: &'a Camera,
        s: PathSettings,
    ) -> Option<Self> {
        if unsupported(scene, &s).is_some() {
            return None;
        }
        let lights = scene.lights.iter().filter_map(|l| l.as_area().copied());
        Some(PacketPathIntegrator {
            scene,
            accel,
            camera,
            max_depth: s.max_depth,
            accumulate: s.accumulate,
            light_samples: s.light_samples.max(1),
            mis: s.strategy == DirectStrategy::Mis,
            roulette: s.roulette,
            lights: lights.collect(),
        })
    }

    /// Renders every sample of `work`'s pixels; `out[i]` receives pixel `i`'s sum
    /// (pixels left unstarted because `stop` said so keep `None`).
    pub fn render_tile(&self, work: &TileWork, out: &mut [Option<PixelSum>]) {
        dispatch(TileTask {
            integrator: self,
            work,
            out,
        })
    }
}

struct TileTask<'a, 'b, 't> {
    integrator: &'b PacketPathIntegrator<'a>,
    work: &'b TileWork<'t>,
    out: &'b mut [Option<PixelSum>],
}

impl SimdTask for TileTask<'_, '_, '_> {
    type Output = ();
    #[inline(always)]
    fn run<S: Simd>(self, s: S) {
        Kernel::new(s, self.integrator, self.work).run(self.out);
    }
}

/// What each lane carries between bounces (structure of arrays).
struct Lanes {
    /// Lanes holding a live path.
    live: LaneBits,
    /// Index into the tile's pixels and sample index (relative to `spp_offset`).
    pixel: [u32; LANES],
    sample: [u32; LANES],
    samplers: [Sampler; LANES],
    rays: RayPacket,
    beta: [[f32; LANES]; 3],
    l: [[f32; LANES]; 3],
    bounces: [u32; LANES],
    /// Lanes whose ray left a surface vertex (else the camera), that vertex and the
    /// BSDF pdf of the ray's direction there.
    has_prev: LaneBits,
    prev_p: [[f32; LANES]; 3],
    prev_pdf: [f32; LANES],
}

/// Where a pixel's finished samples wait until they can be summed in order.
struct PixelSlots {
    spp: usize,
    /// Tile pixel of each slot (`u32::MAX`: free), its values and how many are done.
    pixel: Vec<u32>,
    values: Vec<Color>,
    done: Vec<u32>,
}

/// Pixels in flight at once: lanes may run ahead of a long path by this many pixels.
const SLOTS: usize = 8;

impl PixelSlots {
    fn new(spp: usize) -> Self {
        PixelSlots {
            spp,
            pixel: vec![u32::MAX; SLOTS],
            values: vec![Color::ZERO; SLOTS * spp],
            done: vec![0; SLOTS],
        }
    }

    fn slot_of(pixel: u32) -> usize {
        pixel as usize % SLOTS
    }
}

struct Kernel<'a, 'b, 't, S: Simd> {
    s: S,
    it: &'b PacketPathIntegrator<'a>,
    work: &'b TileWork<'t>,
    lanes: Lanes,
    slots: PixelSlots,
    /// Next sample to start, as (tile pixel, sample).
    next: (u32, u32),
    stopped: bool,
}

/// A surface point in lanes, as `SurfaceInteraction`.
#[derive(Clone, Copy)]
struct Hits<S: Simd> {
    p: Vec3s<S>,
    p_error: Vec3s<S>,
    ng: Vec3s<S>,
    ns: Vec3s<S>,
}

impl<'a, 'b, 't, S: Simd> Kernel<'a, 'b, 't, S> {
    fn new(s: S, it: &'b PacketPathIntegrator<'a>, work: &'b TileWork<'t>) -> Self {
        Kernel {
            s,
            it,
            work,
            lanes: Lanes {
                live: 0,
                pixel: [0; LANES],
                sample: [0; LANES],
                samplers: std::array::from_fn(|_| Sampler::from_seed(0)),
                rays: RayPacket::default(),
                beta: [[0.0; LANES]; 3],
                l: [[0.0; LANES]; 3],
                bounces: [0; LANES],
                has_prev: 0,
                prev_p: [[0.0; LANES]; 3],
                prev_pdf: [0.0; LANES],
            },
            slots: PixelSlots::new(work.spp.max(1) as usize),
            next: (0, 0),
            stopped: false,
        }
    }

    #[inline(always)]
    fn run(mut self, out: &mut [Option<PixelSum>]) {
        let mut hits = HitPacket::default();
        loop {
            self.refill();
            if self.lanes.live == 0 {
                break;
            }
            let live = self.lanes.live;
            self.it
                .accel
                .intersect_packet(&self.lanes.rays, live, &mut hits);
            let ended = self.bounce(&hits);
            self.finish(ended, out);
        }
    }

    /// Starts the next samples in free lanes (camera rays, drawn as the scalar
    /// renderer draws them).
    fn refill(&mut self) {
        let spp = self.work.spp.max(1);
        let npix = self.work.pixels.len() as u32;
        let cam = self.it.camera;
        while self.lanes.live != ALL_LANES && !self.stopped {
            let (px, sample) = self.next;
            if px >= npix {
                return;
            }
            let slot = PixelSlots::slot_of(px);
            if sample == 0 {
                // A new pixel needs a free slot, and leave to start.
                if self.slots.pixel[slot] != u32::MAX {
                    return;
                }
                if (self.work.stop)() {
                    self.stopped = true;
                    return;
                }
                self.slots.pixel[slot] = px;
                self.slots.done[slot] = 0;
            }
            let i = (!self.lanes.live).trailing_zeros() as usize;
            let (x, y) = self.work.pixels[px as usize];
            let pixel = y as u64 * cam.width as u64 + x as u64;
            let index = self.work.spp_offset as u64 + sample as u64;
            let mut sampler = PixelStreams::new(self.work.seed, pixel).sample(index);
            let ray = cam.sample_ray(x, y, &mut sampler);
            let l = &mut self.lanes;
            l.samplers[i] = sampler;
            l.rays.set(i, &ray);
            l.pixel[i] = px;
            l.sample[i] = sample;
            for c in 0..3 {
                l.beta[c][i] = 1.0;
                l.l[c][i] = 0.0;
            }
            l.bounces[i] = 0;
            l.has_prev &= !(1 << i);
            l.live |= 1 << i;
            self.next = if sample + 1 < spp {
                (px, sample + 1)
            } else {
                (px + 1, 0)
            };
        }
    }

    /// Records the radiance of the lanes in `ended` and frees them; pixels whose
    /// samples are all done are summed into `out`.
    fn finish(&mut self, ended: LaneBits, out: &mut [Option<PixelSum>]) {
        let mut rest = ended;
        while rest != 0 {
            let i = rest.trailing_zeros() as usize;
            rest &= rest - 1;
            let l = &self.lanes;
            let radiance = Vec3::new(l.l[0][i], l.l[1][i], l.l[2][i]);
            let (px, sample) = (l.pixel[i], l.sample[i] as usize);
            let slot = PixelSlots::slot_of(px);
            let spp = self.slots.spp;
            self.slots.values[slot * spp + sample] = radiance;
            self.slots.done[slot] += 1;
            if self.slots.done[slot] as usize == spp {
                let mut sum = Color::ZERO;
                let mut nonfinite = 0;
                for &v in &self.slots.values[slot * spp..(slot + 1) * spp] {
                    if crate::color::is_finite(v) {
                        sum += v;
                    } else {
                        nonfinite += 1;
                    }
                }
                out[px as usize] = Some(PixelSum { sum, nonfinite });
                self.slots.pixel[slot] = u32::MAX;
            }
        }
        self.lanes.live &= !ended;
    }

    // ---- lane helpers ----

    #[inline(always)]
    fn f(&self, x: f32) -> F32s<S> {
        F32s::splat(self.s, x)
    }

    #[inline(always)]
    fn load3(&self, a: &[[f32; LANES]; 3]) -> Vec3s<S> {
        Vec3s::new(
            F32s::from_array(self.s, a[0]),
            F32s::from_array(self.s, a[1]),
            F32s::from_array(self.s, a[2]),
        )
    }

    #[inline(always)]
    fn mask(&self, bits: LaneBits) -> Mask<S> {
        Mask::from_bits(self.s, bits)
    }

    /// Uniform numbers for the lanes in `lanes` (0 elsewhere), one draw each.
    #[inline(always)]
    fn next_f32(&mut self, lanes: LaneBits) -> F32s<S> {
        let mut u = [0.0; LANES];
        let mut rest = lanes;
        while rest != 0 {
            let i = rest.trailing_zeros() as usize;
            rest &= rest - 1;
            u[i] = self.lanes.samplers[i].next_f32();
        }
        F32s::from_array(self.s, u)
    }

    #[inline(always)]
    fn next_2d(&mut self, lanes: LaneBits) -> (F32s<S>, F32s<S>) {
        let mut u = [[0.0; LANES]; 2];
        let mut rest = lanes;
        while rest != 0 {
            let i = rest.trailing_zeros() as usize;
            rest &= rest - 1;
            let v = self.lanes.samplers[i].next_2d();
            (u[0][i], u[1][i]) = (v.x, v.y);
        }
        (F32s::from_array(self.s, u[0]), F32s::from_array(self.s, u[1]))
    }

    /// Lanes of `lanes` where the path's emission and light at `bounces` count
    /// (`PathIntegrator::counts`).
    #[inline(always)]
    fn counts(&self, lanes: LaneBits, extra: u32) -> LaneBits {
        let (max, acc) = (self.it.max_depth, self.it.accumulate);
        let mut m = 0;
        let mut rest = lanes;
        while rest != 0 {
            let i = rest.trailing_zeros() as usize;
            rest &= rest - 1;
            let b = self.lanes.bounces[i] + extra;
            if (acc && b <= max) || (!acc && b == max) {
                m |= 1 << i;
            }
        }
        m
    }

    /// `L += beta · c` in lanes `m`.
    #[inline(always)]
    fn add_radiance(&mut self, m: LaneBits, c: Vec3s<S>) {
        if m == 0 {
            return;
        }
        let mk = self.mask(m);
        let beta = self.load3(&self.lanes.beta);
        let l = self.load3(&self.lanes.l);
        let sum = l + beta * c;
        let new = Vec3s::select(mk, sum, l);
        self.lanes.l = [new.x.to_array(), new.y.to_array(), new.z.to_array()];
    }

    /// One bounce of every live lane, from its traced ray's `hits`: the lanes whose
    /// path ended.
    #[inline(always)]
    fn bounce(&mut self, hits: &HitPacket) -> LaneBits {
        let s = self.s;
        let live = self.lanes.live;
        let o = self.load3(&self.lanes.rays.o);
        let d = self.load3(&self.lanes.rays.d);
        // The unit direction, once, as the scalar `li`.
        let w = d.normalize(s);
        let mut hit_lanes = 0;
        for i in 0..LANES {
            if live >> i & 1 != 0 && hits.prim[i] != NO_PRIM {
                hit_lanes |= 1 << i;
            }
        }
        let mut ended = 0;
        // Area lights the sampled line meets before the hit end the path there.
        let with_prev = live & self.lanes.has_prev;
        if with_prev != 0 {
            ended |= self.area_light_on_line(with_prev, hits, hit_lanes, o, d, w);
        }
        // Escaped paths end: nothing here lights them.
        ended |= live & !hit_lanes & !ended;
        let lanes = live & !ended;
        if lanes == 0 {
            return ended;
        }
        let (mut si, material, light) = self.interaction(lanes, hits, o, d);
        let from_prev = lanes & self.lanes.has_prev;
        if from_prev != 0 {
            si = self.on_line(from_prev, hits, si, w);
        }
        // Emission seen by camera rays (other vertices' light was found above).
        let camera = lanes & !self.lanes.has_prev;
        let counts_now = self.counts(camera, 0);
        if counts_now != 0 {
            self.emitted(counts_now, &light, si, w);
        }
        // Paths end at the depth cap and on lights' surfaces.
        let mut stop = 0;
        for i in 0..LANES {
            if lanes >> i & 1 != 0
                && (self.lanes.bounces[i] >= self.it.max_depth
                    || self.it.scene.materials[material[i] as usize].is_black())
            {
                stop |= 1 << i;
            }
        }
        ended |= stop;
        let lanes = lanes & !stop;
        if lanes == 0 {
            return ended;
        }
        for i in 0..LANES {
            if lanes >> i & 1 != 0 {
                self.lanes.bounces[i] += 1;
            }
        }
        let albedo = self.albedo(lanes, &material);
        let frame = Frame::from_normal(s, si.ns);
        let wo_world = -w;
        let wo = frame.to_local(wo_world);
        let direct = self.counts(lanes, 0);
        if direct != 0 {
            self.direct(direct, &hits.prim, si, &frame, wo, albedo);
        }
        ended |= self.scatter(lanes, &hits.prim, si, &frame, wo, wo_world, albedo);
        ended
    }

    /// `PathIntegrator::area_light_on_line` for the lanes in `lanes` (all with a
    /// previous vertex): the lanes whose line meets an area light first, which end.
    #[inline(always)]
    fn area_light_on_line(
        &mut self,
        lanes: LaneBits,
        hits: &HitPacket,
        hit_lanes: LaneBits,
        o: Vec3s<S>,
        d: Vec3s<S>,
        w: Vec3s<S>,
    ) -> LaneBits {
        let s = self.s;
        let prev = self.load3(&self.lanes.prev_p);
        let t = F32s::from_array(s, hits.t);
        let hit_m = self.mask(hit_lanes);
        let at = o + d * t;
        let t_hit = F32s::select(hit_m, (at - prev).dot(w), self.f(f32::INFINITY));
        let mut hit_light = [NO_LIGHT; LANES];
        let ntri = self.it.scene.triangles.len();
        for (i, light) in hit_light.iter_mut().enumerate() {
            let p = hits.prim[i] as usize;
            if hit_lanes >> i & 1 != 0 && p < ntri {
                *light = self.it.scene.triangles[p].light;
            }
        }
        let hit_light = U32s::from_array(s, hit_light);
        let mut best_t = self.f(f32::INFINITY);
        let mut best: LaneBits = 0;
        let mut best_light = U32s::splat(s, 0);
        for (k, light) in self.it.lights.iter().enumerate() {
            let (met, t_light) = intersect_area(s, light, prev, w);
            let own = hit_light.eq(U32s::splat(s, k as u32));
            let nearer = t_light.lt(t_hit) | own;
            let better = self.mask(!best) | t_light.lt(best_t);
            let take = (met & nearer & better).bits() & lanes;
            let m = self.mask(take);
            best_t = F32s::select(m, t_light, best_t);
            best_light = U32s::select(m, U32s::splat(s, k as u32), best_light);
            best |= take;
        }
        if best == 0 {
            return 0;
        }
        let counted = self.counts(best, 0);
        if counted != 0 && self.it.mis {
            // Light sampling also finds these lights: weight by the power heuristic.
            let ids = best_light.to_array();
            let mut le = [[0.0; LANES]; 3];
            let mut light_pdf = [0.0; LANES];
            let prev_a = [
                prev.x.to_array(),
                prev.y.to_array(),
                prev.z.to_array(),
            ];
            let wa = [w.x.to_array(), w.y.to_array(), w.z.to_array()];
            for i in (0..LANES).filter(|&i| counted >> i & 1 != 0) {
                let light = &self.it.lights[ids[i] as usize];
                let p = Vec3::new(prev_a[0][i], prev_a[1][i], prev_a[2][i]);
                let dir = Vec3::new(wa[0][i], wa[1][i], wa[2][i]);
                light_pdf[i] = light.pdf_li(p, dir);
                (le[0][i], le[1][i], le[2][i]) = light.radiance.into();
            }
            let weight = power_heuristic(
                s,
                self.f(1.0),
                F32s::from_array(s, self.lanes.prev_pdf),
                self.f(self.it.light_samples as f32),
                F32s::from_array(s, light_pdf),
            );
            let le = self.load3(&le) * weight;
            self.add_radiance(counted, le);
        }
        // With light sampling alone the weight is 0: nothing to add.
        best
    }

    /// The surface points of the hits in `lanes` (`Scene::interaction`), and each
    /// lane's material and light.
    #[inline(always)]
    fn interaction(
        &self,
        lanes: LaneBits,
        hits: &HitPacket,
        o: Vec3s<S>,
        d: Vec3s<S>,
    ) -> (Hits<S>, [u32; LANES], [u32; LANES]) {
        let s = self.s;
        let scene = self.it.scene;
        let ntri = scene.triangles.len();
        let mut corner = [[[0.0f32; LANES]; 3]; 3];
        let mut normal = [[[0.0f32; LANES]; 3]; 3];
        let mut has_normals: LaneBits = 0;
        let mut sphere: LaneBits = 0;
        let mut centre = [[0.0f32; LANES]; 3];
        let mut radius = [0.0f32; LANES];
        let mut material = [0u32; LANES];
        let mut light = [NO_LIGHT; LANES];
        for i in (0..LANES).filter(|&i| lanes >> i & 1 != 0) {
            let p = hits.prim[i] as usize;
            if p < ntri {
                let tri = &scene.triangles[p];
                for (k, &v) in tri.v.iter().enumerate() {
                    let q = scene.positions[v as usize];
                    (corner[k][0][i], corner[k][1][i], corner[k][2][i]) = q.into();
                }
                if let Some(n) = tri.n {
                    has_normals |= 1 << i;
                    for (k, &v) in n.iter().enumerate() {
                        let q = scene.normals[v as usize];
                        (normal[k][0][i], normal[k][1][i], normal[k][2][i]) = q.into();
                    }
                }
                material[i] = tri.material;
                light[i] = tri.light;
            } else {
                let sp = &scene.spheres[p - ntri];
                sphere |= 1 << i;
                (centre[0][i], centre[1][i], centre[2][i]) = sp.centre.into();
                radius[i] = sp.radius;
                material[i] = sp.material;
            }
        }
        let b1 = F32s::from_array(s, hits.b1);
        let b2 = F32s::from_array(s, hits.b2);
        let [p0, p1, p2] = corner.map(|c| self.load3(&c));
        let mut out = triangle_points(s, p0, p1, p2, b1, b2);
        if has_normals != 0 {
            let [n0, n1, n2] = normal.map(|c| self.load3(&c));
            let (ng, ns) = shading_normals(s, out.ng, n0, n1, n2, b1, b2);
            let m = self.mask(has_normals);
            out.ng = Vec3s::select(m, ng, out.ng);
            out.ns = Vec3s::select(m, ns, out.ns);
        }
        if sphere != 0 {
            let t = F32s::from_array(s, hits.t);
            let c = self.load3(&centre);
            let r = F32s::from_array(s, radius);
            let sp = sphere_points(s, o, d, t, c, r);
            let m = self.mask(sphere);
            out = Hits {
                p: Vec3s::select(m, sp.p, out.p),
                p_error: Vec3s::select(m, sp.p_error, out.p_error),
                ng: Vec3s::select(m, sp.ng, out.ng),
                ns: Vec3s::select(m, sp.ns, out.ns),
            };
        }
        (out, material, light)
    }

    /// `Scene::on_line` for the lanes in `lanes`.
    #[inline(always)]
    fn on_line(&self, lanes: LaneBits, hits: &HitPacket, si: Hits<S>, w: Vec3s<S>) -> Hits<S> {
        let s = self.s;
        let scene = self.it.scene;
        let ntri = scene.triangles.len();
        let from = self.load3(&self.lanes.prev_p);
        let cos = w.dot(si.ng);
        let steep = cos.abs().ge(self.f(0.05));
        let dist = (si.p - from).dot(si.ng) / cos;
        let ahead = dist.gt(self.f(0.0)) & dist.is_finite();
        let p = from + w * dist;
        let p_error =
            si.p_error + p.abs() * self.f(gamma(1)) + (w * dist).abs() * self.f(gamma(5));
        // Triangles: the point must lie in the hit triangle; exact axes stay.
        let mut corner = [[[0.0f32; LANES]; 3]; 3];
        let mut tri: LaneBits = 0;
        let mut centre = [[0.0f32; LANES]; 3];
        for i in (0..LANES).filter(|&i| lanes >> i & 1 != 0) {
            let prim = hits.prim[i] as usize;
            if prim < ntri {
                tri |= 1 << i;
                for k in 0..3 {
                    let q = scene.positions[scene.triangles[prim].v[k] as usize];
                    (corner[k][0][i], corner[k][1][i], corner[k][2][i]) = q.into();
                }
            } else {
                let c = scene.spheres[prim - ntri].centre;
                (centre[0][i], centre[1][i], centre[2][i]) = c.into();
            }
        }
        let [p0, p1, p2] = corner.map(|c| self.load3(&c));
        let inside = triangle_contains(s, p0, p1, p2, p);
        let exact = exact_axes(p0, p1, p2);
        let tri_p = Vec3s::new(
            F32s::select(exact[0], si.p.x, p.x),
            F32s::select(exact[1], si.p.y, p.y),
            F32s::select(exact[2], si.p.z, p.z),
        );
        let zero = self.f(0.0);
        let tri_err = Vec3s::new(
            F32s::select(exact[0], zero, p_error.x),
            F32s::select(exact[1], zero, p_error.y),
            F32s::select(exact[2], zero, p_error.z),
        );
        // Spheres: the normal again at the moved point.
        let c = self.load3(&centre);
        let n = normalize_or_zero(s, (from - c) + w * dist);
        let facing = n.dot(si.ng).gt(zero);
        let tri_m = self.mask(tri);
        let lands = (tri_m & inside) | (!tri_m & facing);
        let moved = self.mask(lanes) & steep & ahead & lands;
        let is_tri = moved & tri_m;
        let is_sph = moved & !tri_m;
        Hits {
            p: Vec3s::select(is_tri, tri_p, Vec3s::select(is_sph, p, si.p)),
            p_error: Vec3s::select(is_tri, tri_err, Vec3s::select(is_sph, p_error, si.p_error)),
            ng: Vec3s::select(is_sph, n, si.ng),
            ns: Vec3s::select(is_sph, n, si.ns),
        }
    }

    /// Emission of area lights seen directly by camera rays, in lanes `lanes`.
    #[inline(always)]
    fn emitted(&mut self, lanes: LaneBits, light: &[u32; LANES], si: Hits<S>, w: Vec3s<S>) {
        let mut le = [[0.0; LANES]; 3];
        let mut any = 0;
        let cos_out = (-w).dot(si.ng).to_array();
        for i in (0..LANES).filter(|&i| lanes >> i & 1 != 0) {
            let Some(Light::Area(a)) = self.it.scene.lights.get(light[i] as usize) else {
                continue;
            };
            let e = a.emitted(cos_out[i]);
            if e != Color::ZERO {
                any |= 1 << i;
                (le[0][i], le[1][i], le[2][i]) = e.into();
            }
        }
        let le = self.load3(&le);
        self.add_radiance(any, le);
    }

    #[inline(always)]
    fn albedo(&self, lanes: LaneBits, material: &[u32; LANES]) -> Vec3s<S> {
        let mut a = [[0.0; LANES]; 3];
        for i in (0..LANES).filter(|&i| lanes >> i & 1 != 0) {
            if let Material::Lambertian { albedo } = self.it.scene.materials[material[i] as usize] {
                (a[0][i], a[1][i], a[2][i]) = albedo.into();
            }
        }
        self.load3(&a)
    }

    /// `PathIntegrator::direct` by light sampling (with MIS weights when asked):
    /// one shadow packet per light sample, contributions summed in the scalar order.
    #[inline(always)]
    fn direct(
        &mut self,
        lanes: LaneBits,
        prims: &[u32; LANES],
        si: Hits<S>,
        frame: &Frame<S>,
        wo: Vec3s<S>,
        albedo: Vec3s<S>,
    ) {
        let s = self.s;
        let zero = self.f(0.0);
        let n = self.it.light_samples;
        let nf = self.f(n as f32);
        let f = albedo * self.f(FRAC_1_PI);
        let f_black = f.x.eq(zero) & f.y.eq(zero) & f.z.eq(zero);
        let wo_world = frame.to_world(wo);
        let mut acc = Vec3s::splat(s, Vec3::ZERO);
        let skip = *prims;
        let mut shadow = RayPacket::default();
        for k in 0..self.it.lights.len() {
            let light = self.it.lights[k];
            for _ in 0..n {
                let (u1, u2) = self.next_2d(lanes);
                let ls = sample_area(s, &light, si.p, u1, u2);
                let wi = frame.to_local(ls.wi);
                let reflect = (wi.z * wo.z).gt(zero);
                let consistent = geometrically_consistent(s, si.ng, wo_world, ls.wi, reflect);
                let ok = (ls.valid & consistent & reflect & !f_black).bits() & lanes;
                if ok == 0 {
                    continue;
                }
                // The shadow segment, stopped short of the light.
                let target = ls.p_light;
                let origin = offset_ray_origin(s, si.p, si.p_error, si.ng, target - si.p);
                let dir = target - origin;
                store3(&mut shadow.o, origin);
                store3(&mut shadow.d, dir);
                shadow.t_max = [1.0 - SHADOW_EPSILON; LANES];
                shadow.skip = skip;
                let blocked = self.it.accel.occluded_packet(&shadow, ok);
                let lit = ok & !blocked;
                if lit == 0 {
                    continue;
                }
                let weight = if self.it.mis {
                    let bsdf_pdf = wi.z.abs().max(zero) * self.f(FRAC_1_PI);
                    power_heuristic(s, nf, ls.pdf, self.f(1.0), bsdf_pdf)
                } else {
                    self.f(1.0)
                };
                let li = Vec3s::splat(s, light.radiance);
                let contrib = f * li * (wi.z.abs() * weight / ls.pdf);
                let m = self.mask(lit);
                acc = Vec3s::select(m, acc + contrib / nf, acc);
            }
        }
        self.add_radiance(lanes, acc);
    }

    /// `Material::sample` (Lambertian), the depth and consistency checks, the
    /// throughput update and roulette of `li`, and the next rays: the lanes whose
    /// path ended.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn scatter(
        &mut self,
        lanes: LaneBits,
        prims: &[u32; LANES],
        si: Hits<S>,
        frame: &Frame<S>,
        wo: Vec3s<S>,
        wo_world: Vec3s<S>,
        albedo: Vec3s<S>,
    ) -> LaneBits {
        let s = self.s;
        let zero = self.f(0.0);
        let _u_lobe = self.next_f32(lanes);
        let (u1, u2) = self.next_2d(lanes);
        // Cosine-weighted direction on the side of `wo` (`lambertian::sample`).
        let finite = wo.x.is_finite() & wo.y.is_finite() & wo.z.is_finite();
        let (dx, dy) = concentric_disk_lanes(s, u1, u2, lanes);
        let z = (self.f(1.0) - (dx * dx + dy * dy)).max(zero).sqrt();
        let sampled = finite & !wo.z.eq(zero) & z.gt(zero);
        let wi = Vec3s::new(dx, dy, z.copysign(wo.z));
        let pdf = wi.z.abs().max(zero) * self.f(FRAC_1_PI);
        let mut ended = lanes & !sampled.bits();
        // At the depth cap only MIS still traces the ray, to weight the light it finds.
        if !self.it.mis {
            ended |= lanes & self.at_depth_cap(lanes);
        }
        let wi_world = frame.to_world(wi);
        let reflect = (wi.z * wo.z).gt(zero);
        let consistent = geometrically_consistent(s, si.ng, wo_world, wi_world, reflect);
        ended |= lanes & !consistent.bits();
        let go = lanes & !ended;
        let beta = self.load3(&self.lanes.beta) * albedo;
        let q = self.continue_prob(go, beta);
        let play = go & q.lt(self.f(1.0)).bits();
        let mut survive = go;
        if play != 0 {
            let u = self.next_f32(play);
            survive &= !(play & u.ge(q).bits());
        }
        let beta = beta / q;
        let finite = beta.x.is_finite() & beta.y.is_finite() & beta.z.is_finite();
        let black = beta.x.eq(zero) & beta.y.eq(zero) & beta.z.eq(zero);
        survive &= (finite & !black).bits();
        ended |= lanes & !survive;
        if survive != 0 {
            let m = self.mask(survive);
            let old = self.load3(&self.lanes.beta);
            store3(&mut self.lanes.beta, Vec3s::select(m, beta, old));
            let prev = self.load3(&self.lanes.prev_p);
            store3(&mut self.lanes.prev_p, Vec3s::select(m, si.p, prev));
            let old_pdf = F32s::from_array(s, self.lanes.prev_pdf);
            self.lanes.prev_pdf = F32s::select(m, pdf, old_pdf).to_array();
            self.lanes.has_prev |= survive;
            let origin = offset_ray_origin(s, si.p, si.p_error, si.ng, wi_world);
            let rays = &mut self.lanes.rays;
            let (o, d) = (rays.o, rays.d);
            rays.o = select3(m, origin, self_load3(s, &o));
            rays.d = select3(m, wi_world, self_load3(s, &d));
            for i in (0..LANES).filter(|&i| survive >> i & 1 != 0) {
                rays.t_max[i] = f32::INFINITY;
                rays.skip[i] = prims[i];
            }
        }
        ended
    }

    /// Lanes of `lanes` at the depth cap (after this bounce's increment).
    #[inline(always)]
    fn at_depth_cap(&self, lanes: LaneBits) -> LaneBits {
        (0..LANES)
            .filter(|&i| lanes >> i & 1 != 0 && self.lanes.bounces[i] >= self.it.max_depth)
            .fold(0, |m, i| m | 1 << i)
    }

    /// `Roulette::continue_prob` per lane (1 where the lane is not in `lanes`).
    #[inline(always)]
    fn continue_prob(&self, lanes: LaneBits, beta: Vec3s<S>) -> F32s<S> {
        let one = self.f(1.0);
        let (start, q) = match self.it.roulette {
            Roulette::Off => return one,
            Roulette::Throughput { start, min_prob } => {
                // glam's max_element, then f32::clamp.
                let m = max_nonnan(beta.x, max_nonnan(beta.y, beta.z));
                (start, clamp(m, self.f(min_prob), one))
            }
            Roulette::Fixed { start, prob } => (start, self.f(prob.clamp(1e-6, 1.0))),
        };
        let playing = (0..LANES)
            .filter(|&i| lanes >> i & 1 != 0 && self.lanes.bounces[i] >= start)
            .fold(0, |m, i| m | 1 << i);
        F32s::select(self.mask(playing), q, one)
    }
}

/// A local shading frame in lanes (`Frame`, operation for operation).
struct Frame<S: Simd> {
    s: Vec3s<S>,
    t: Vec3s<S>,
    n: Vec3s<S>,
}

impl<S: Simd> Frame<S> {
    #[inline(always)]
    fn from_normal(k: S, n: Vec3s<S>) -> Self {
        let one = F32s::splat(k, 1.0);
        let sign = one.copysign(n.z);
        let a = F32s::splat(k, -1.0) / (sign + n.z);
        let b = n.x * n.y * a;
        let s = Vec3s::new(one + sign * n.x * n.x * a, sign * b, -sign * n.x);
        let t = Vec3s::new(b, sign + n.y * n.y * a, -n.y);
        Frame { s, t, n }
    }

    #[inline(always)]
    fn to_local(&self, v: Vec3s<S>) -> Vec3s<S> {
        Vec3s::new(v.dot(self.s), v.dot(self.t), v.dot(self.n))
    }

    #[inline(always)]
    fn to_world(&self, v: Vec3s<S>) -> Vec3s<S> {
        self.s * v.x + self.t * v.y + self.n * v.z
    }
}

#[inline(always)]
fn store3<S: Simd>(a: &mut [[f32; LANES]; 3], v: Vec3s<S>) {
    *a = [v.x.to_array(), v.y.to_array(), v.z.to_array()];
}

#[inline(always)]
fn self_load3<S: Simd>(s: S, a: &[[f32; LANES]; 3]) -> Vec3s<S> {
    Vec3s::new(
        F32s::from_array(s, a[0]),
        F32s::from_array(s, a[1]),
        F32s::from_array(s, a[2]),
    )
}

#[inline(always)]
fn select3<S: Simd>(m: Mask<S>, a: Vec3s<S>, b: Vec3s<S>) -> [[f32; LANES]; 3] {
    let v = Vec3s::select(m, a, b);
    [v.x.to_array(), v.y.to_array(), v.z.to_array()]
}

/// `f32::max`: the other operand where one is NaN.
#[inline(always)]
fn max_nonnan<S: Simd>(a: F32s<S>, b: F32s<S>) -> F32s<S> {
    F32s::select(b.eq(b), a.max(b), a)
}

/// `f32::clamp`.
#[inline(always)]
fn clamp<S: Simd>(x: F32s<S>, lo: F32s<S>, hi: F32s<S>) -> F32s<S> {
    let x = F32s::select(x.lt(lo), lo, x);
    F32s::select(x.gt(hi), hi, x)
}

/// `geometrically_consistent` of `path.rs`.
#[inline(always)]
fn geometrically_consistent<S: Simd>(
    s: S,
    ng: Vec3s<S>,
    wo: Vec3s<S>,
    wi: Vec3s<S>,
    reflect: Mask<S>,
) -> Mask<S> {
    let ab = wo.dot(ng) * wi.dot(ng);
    let zero = F32s::splat(s, 0.0);
    (reflect & ab.gt(zero)) | (!reflect & ab.lt(zero))
}

/// `sampling::power_heuristic`.
#[inline(always)]
fn power_heuristic<S: Simd>(
    s: S,
    nf: F32s<S>,
    f_pdf: F32s<S>,
    ng: F32s<S>,
    g_pdf: F32s<S>,
) -> F32s<S> {
    let (zero, one) = (F32s::splat(s, 0.0), F32s::splat(s, 1.0));
    let f = nf * f_pdf;
    let g = ng * g_pdf;
    let d = f * f + g * g;
    let w = F32s::select(d.gt(zero), f * f / d, zero);
    let infinite = f.abs().eq(F32s::splat(s, f32::INFINITY));
    F32s::select(infinite, one, w)
}

/// A light sample in lanes (`AreaLight::sample_li`): `valid` where it gives one.
struct AreaSample<S: Simd> {
    valid: Mask<S>,
    wi: Vec3s<S>,
    p_light: Vec3s<S>,
    pdf: F32s<S>,
}

/// `AreaLight::sample_li` from points `p` with numbers `(u1, u2)`.
#[inline(always)]
fn sample_area<S: Simd>(s: S, a: &AreaLight, p: Vec3s<S>, u1: F32s<S>, u2: F32s<S>) -> AreaSample<S> {
    let half = F32s::splat(s, 0.5);
    let zero = F32s::splat(s, 0.0);
    // `uniform_parallelogram(u, ZERO, ex, ey)`: ZERO + (u.x − ½)·ex + (u.y − ½)·ey.
    let local = (Vec3s::splat(s, Vec3::ZERO) + Vec3s::splat(s, a.ex) * (u1 - half))
        + Vec3s::splat(s, a.ey) * (u2 - half);
    let centre = Vec3s::splat(s, a.centre);
    let p_light = centre + local;
    let to_light = (centre - p) + local;
    let dist = to_light.length_squared().sqrt();
    let mut valid = dist.gt(zero) & dist.is_finite();
    let wi = to_light / dist;
    // `solid_angle_pdf`
    let cos_light = -wi.dot(Vec3s::splat(s, a.normal));
    let area = a.area();
    valid = valid & cos_light.gt(zero);
    if !(area > 0.0) || a.radiance == Color::ZERO {
        valid = valid & zero.lt(zero);
    }
    let pdf = dist * dist / (F32s::splat(s, area) * cos_light);
    valid = valid & pdf.is_finite() & pdf.gt(zero);
    AreaSample {
        valid,
        wi,
        p_light,
        pdf,
    }
}

/// `AreaLight::intersect` from points `p` along unit `wi`: where the front is met, and how far.
#[inline(always)]
fn intersect_area<S: Simd>(s: S, a: &AreaLight, p: Vec3s<S>, wi: Vec3s<S>) -> (Mask<S>, F32s<S>) {
    let zero = F32s::splat(s, 0.0);
    let half = F32s::splat(s, 0.5);
    let normal = Vec3s::splat(s, a.normal);
    let denom = wi.dot(normal);
    let to_centre = Vec3s::splat(s, a.centre) - p;
    let dist = to_centre.dot(normal) / denom;
    let mut met = denom.lt(zero) & dist.gt(zero) & dist.is_finite();
    let m = a.ex.cross(a.ey);
    let m2 = m.length_squared();
    if !(m2 > 0.0) {
        return (met & zero.lt(zero), dist);
    }
    let (ex, ey, mv, m2v) = (
        Vec3s::splat(s, a.ex),
        Vec3s::splat(s, a.ey),
        Vec3s::splat(s, m),
        F32s::splat(s, m2),
    );
    let d = wi * dist - to_centre;
    let u = d.cross(ey).dot(mv) / m2v;
    let v = ex.cross(d).dot(mv) / m2v;
    met = met & u.abs().le(half) & v.abs().le(half);
    (met, dist)
}

/// `Scene::triangle_interaction` without shading normals: point, error bound and
/// geometric normal of the hits at barycentrics `(b1, b2)`.
#[inline(always)]
fn triangle_points<S: Simd>(
    s: S,
    p0: Vec3s<S>,
    p1: Vec3s<S>,
    p2: Vec3s<S>,
    b1: F32s<S>,
    b2: F32s<S>,
) -> Hits<S> {
    let (e1, e2) = (p1 - p0, p2 - p0);
    let (t1, t2) = (e1 * b1, e2 * b2);
    let p = p0 + (t1 + t2);
    let p_error = p.abs() * F32s::splat(s, gamma(2))
        + (t1.abs() + t2.abs()) * F32s::splat(s, gamma(4));
    let exact = exact_axes(p0, p1, p2);
    let zero = F32s::splat(s, 0.0);
    let p_error = Vec3s::new(
        F32s::select(exact[0], zero, p_error.x),
        F32s::select(exact[1], zero, p_error.y),
        F32s::select(exact[2], zero, p_error.z),
    );
    let ng = normalize_or_zero(s, e1.cross(e2));
    Hits {
        p,
        p_error,
        ng,
        ns: ng,
    }
}

/// The interpolated shading normal and the geometric normal turned to its side,
/// as `Scene::triangle_interaction` does for meshes with normals.
#[inline(always)]
fn shading_normals<S: Simd>(
    s: S,
    ng: Vec3s<S>,
    n0: Vec3s<S>,
    n1: Vec3s<S>,
    n2: Vec3s<S>,
    b1: F32s<S>,
    b2: F32s<S>,
) -> (Vec3s<S>, Vec3s<S>) {
    let zero = F32s::splat(s, 0.0);
    let b0 = F32s::splat(s, 1.0) - b1 - b2;
    let interp = normalize_or_zero(s, n0 * b0 + n1 * b1 + n2 * b2);
    let ng = Vec3s::select((n0 + n1 + n2).dot(ng).lt(zero), -ng, ng);
    let is_zero = interp.x.eq(zero) & interp.y.eq(zero) & interp.z.eq(zero);
    let ns = Vec3s::select(is_zero, ng, interp);
    let ns = Vec3s::select(ns.dot(ng).lt(zero), -ns, ns);
    (ng, ns)
}

/// `Scene::sphere_interaction` of rays `o + t·d` on spheres `(c, r)`.
#[inline(always)]
fn sphere_points<S: Simd>(
    s: S,
    o: Vec3s<S>,
    d: Vec3s<S>,
    t: F32s<S>,
    c: Vec3s<S>,
    r: F32s<S>,
) -> Hits<S> {
    let zero = F32s::splat(s, 0.0);
    let raw = (o - c) + d * t;
    let n = normalize_or_zero(s, raw);
    let is_zero = n.x.eq(zero) & n.y.eq(zero) & n.z.eq(zero);
    let n = Vec3s::select(is_zero, Vec3s::splat(s, Vec3::Y), n);
    let p = c + n * r;
    let err = F32s::splat(s, gamma(4)) * r;
    let p_error = p.abs() * F32s::splat(s, gamma(2)) + Vec3s::new(err, err, err);
    Hits {
        p,
        p_error,
        ng: n,
        ns: n,
    }
}

/// `Scene::triangle_contains`: whether `q`, in the plane of `(p0, p1, p2)`, lies in it.
#[inline(always)]
fn triangle_contains<S: Simd>(
    s: S,
    p0: Vec3s<S>,
    p1: Vec3s<S>,
    p2: Vec3s<S>,
    q: Vec3s<S>,
) -> Mask<S> {
    let (e1, e2, d) = (p1 - p0, p2 - p0, q - p0);
    let m = e1.cross(e2);
    let m2 = m.length_squared();
    let b1 = d.cross(e2).dot(m) / m2;
    let b2 = e1.cross(d).dot(m) / m2;
    let zero = F32s::splat(s, 0.0);
    b1.ge(zero) & b2.ge(zero) & (b1 + b2).le(F32s::splat(s, 1.0))
}

/// `Scene::exact_axes`: per axis, the lanes whose three corners agree there.
#[inline(always)]
fn exact_axes<S: Simd>(p0: Vec3s<S>, p1: Vec3s<S>, p2: Vec3s<S>) -> [Mask<S>; 3] {
    [
        p0.x.eq(p1.x) & p0.x.eq(p2.x),
        p0.y.eq(p1.y) & p0.y.eq(p2.y),
        p0.z.eq(p1.z) & p0.z.eq(p2.z),
    ]
}

/// glam's `normalize_or_zero`.
#[inline(always)]
fn normalize_or_zero<S: Simd>(s: S, v: Vec3s<S>) -> Vec3s<S> {
    let rcp = F32s::splat(s, 1.0) / v.length_squared().sqrt();
    let ok = rcp.is_finite() & rcp.gt(F32s::splat(s, 0.0));
    Vec3s::select(ok, v * rcp, Vec3s::splat(s, Vec3::ZERO))
}

/// `geometry::offset_ray_origin` in lanes.
#[inline(always)]
fn offset_ray_origin<S: Simd>(
    s: S,
    p: Vec3s<S>,
    p_error: Vec3s<S>,
    ng: Vec3s<S>,
    w: Vec3s<S>,
) -> Vec3s<S> {
    let zero = F32s::splat(s, 0.0);
    let d = ng.abs().dot(p_error);
    let offset = ng * d;
    let offset = Vec3s::select(w.dot(ng).lt(zero), -offset, offset);
    let po = p + offset;
    Vec3s::new(
        round_away(s, po.x, offset.x),
        round_away(s, po.y, offset.y),
        round_away(s, po.z, offset.z),
    )
}

/// `v` moved one float in the direction of `offset`'s sign (unchanged where it is 0).
#[inline(always)]
fn round_away<S: Simd>(s: S, v: F32s<S>, offset: F32s<S>) -> F32s<S> {
    let zero = F32s::splat(s, 0.0);
    let up = next_float_up(s, v);
    let down = next_float_down(s, v);
    F32s::select(offset.gt(zero), up, F32s::select(offset.lt(zero), down, v))
}

/// `ray::next_float_up` in lanes.
#[inline(always)]
fn next_float_up<S: Simd>(s: S, v: F32s<S>) -> F32s<S> {
    let zero = F32s::splat(s, 0.0);
    let v0 = F32s::select(v.eq(zero), zero, v);
    let bits = v0.bits();
    let up = (bits + U32s::splat(s, 1)).as_f32_bits();
    let down = (bits + U32s::splat(s, u32::MAX)).as_f32_bits();
    let r = F32s::select(v0.ge(zero), up, down);
    F32s::select(v.eq(F32s::splat(s, f32::INFINITY)), v, r)
}

/// `ray::next_float_down` in lanes.
#[inline(always)]
fn next_float_down<S: Simd>(s: S, v: F32s<S>) -> F32s<S> {
    let zero = F32s::splat(s, 0.0);
    let v0 = F32s::select(v.eq(zero), F32s::splat(s, -0.0), v);
    let bits = v0.bits();
    let up = (bits + U32s::splat(s, 1)).as_f32_bits();
    let down = (bits + U32s::splat(s, u32::MAX)).as_f32_bits();
    let r = F32s::select(v0.gt(zero), down, up);
    F32s::select(v.eq(F32s::splat(s, f32::NEG_INFINITY)), v, r)
}

/// `sampling::concentric_disk` of the lanes in `lanes` (0 elsewhere).
#[inline(always)]
fn concentric_disk_lanes<S: Simd>(
    s: S,
    u1: F32s<S>,
    u2: F32s<S>,
    lanes: LaneBits,
) -> (F32s<S>, F32s<S>) {
    let (a, b) = (u1.to_array(), u2.to_array());
    let mut x = [0.0; LANES];
    let mut y = [0.0; LANES];
    for i in (0..LANES).filter(|&i| lanes >> i & 1 != 0) {
        let d = concentric_disk(Vec2::new(a[i], b[i]));
        (x[i], y[i]) = (d.x, d.y);
    }
    (F32s::from_array(s, x), F32s::from_array(s, y))
}
