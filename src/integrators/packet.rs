//! The path tracer of `path.rs` run on sixteen paths at once, one per SIMD lane,
//! for the scenes whose every part it covers ([`unsupported`] says which do not):
//! Lambertian surfaces lit by area lights, seen through a pinhole, by light
//! sampling or MIS (the defaults there). Each lane performs the same
//! floating-point operations as `PathIntegrator::li` on the same random numbers
//! (one stream per pixel sample, drawn in the same order), so a pixel is the
//! scalar engine's pixel bit for bit, whatever the lanes beside it hold; rays are
//! traced sixteen at a time (`Accel::intersect_packet`, `occluded_packet`).
//!
//! Lanes are refilled as paths end (a camera ray that escapes at once frees its
//! lane for the next sample), taking the samples of a tile's pixels in order. A
//! pixel's samples are summed in sample order once all are done, as the scalar
//! renderer sums them.

use super::path::{PathSettings, SHADOW_EPSILON};
use super::{DirectStrategy, Roulette};
use crate::accel::{Accel, HitPacket, RayPacket};
use crate::camera::Camera;
use crate::geometry::ray::gamma;
use crate::geometry::sphere::sphere_spawn_origin;
use crate::geometry::NO_PRIM;
use crate::lights::{AreaLight, Light};
use crate::materials::Material;
use crate::sampling::{PixelStreams, StreamLanes, COS_POLY, SIN_POLY};
use crate::scene::{into_triangle, Scene, NO_LIGHT};
use crate::simd::{
    dispatch, prefetch, F32s, LaneBits, Mask, Simd, SimdTask, U32s, U64s, Vec3s, ALL_LANES, LANES,
};
use crate::Color;
use glam::Vec3;
use std::f32::consts::FRAC_1_PI;

/// Why the scene or settings need the scalar path tracer, if they do.
pub fn unsupported(scene: &Scene, camera: &Camera, s: &PathSettings) -> Option<&'static str> {
    if !matches!(s.strategy, DirectStrategy::Light | DirectStrategy::Mis) {
        return Some("hemisphere and BSDF-only sampling");
    }
    if scene.lights.iter().any(|l| matches!(l, Light::Spot(_))) {
        return Some("spot lights");
    }
    if scene.has_textures() {
        return Some("textures");
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
    if !camera.lens.is_pinhole() {
        return Some("a thin lens");
    }
    None
}

/// Renders the pixel samples of a scene that [`unsupported`] accepts.
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
    /// The triangles of area lights' surfaces, and their light.
    light_prims: Vec<(u32, u32)>,
    /// Per material: albedo, and whether it scatters nothing (light surfaces).
    albedo: Vec<Color>,
    black: Vec<bool>,
}

/// The pixels of a tile and how to sample them.
pub struct TileWork<'t> {
    pub pixels: &'t [(u32, u32)],
    pub spp: u32,
    pub spp_offset: u32,
    pub seed: u64,
    /// Checked before each pixel is started; a pixel not started is not reported.
    pub stop: &'t (dyn Fn() -> bool + Sync),
}

/// A finished pixel: the sum of its samples' radiance in sample order (non-finite
/// samples counted as black), and how many were not finite.
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
        if unsupported(scene, camera, &s).is_some() {
            return None;
        }
        let lights = scene.lights.iter().filter_map(|l| l.as_area().copied());
        let albedo = scene.materials.iter().map(|m| match m {
            Material::Lambertian { albedo } => *albedo,
            _ => Color::ZERO,
        });
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
            light_prims: (0..scene.triangles.len() as u32)
                .map(|i| (i, scene.triangles[i as usize].light))
                .filter(|&(_, light)| light != NO_LIGHT)
                .collect(),
            albedo: albedo.collect(),
            black: scene.materials.iter().map(Material::is_black).collect(),
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

/// Where a pixel's finished samples wait until they can be summed in order.
struct PixelSlots {
    spp: usize,
    /// Tile pixel of each slot (`u32::MAX`: free), its values and how many are done.
    pixel: [u32; SLOTS],
    /// Each slot's pixel's `PixelStreams::key`, hashed once per pixel.
    key: [u64; SLOTS],
    values: Vec<Color>,
    done: [u32; SLOTS],
}

/// Pixels in flight at once: lanes may run ahead of a long path by this many pixels.
const SLOTS: usize = 8;

impl PixelSlots {
    fn slot_of(pixel: u32) -> usize {
        pixel as usize % SLOTS
    }
}

/// Per lane: a path's state between bounces.
struct Kernel<'a, 'b, 't, S: Simd> {
    s: S,
    it: &'b PacketPathIntegrator<'a>,
    work: &'b TileWork<'t>,
    /// Lanes holding a live path.
    live: LaneBits,
    /// Tile pixel and sample index (relative to `spp_offset`) of each lane.
    pixel: [u32; LANES],
    sample: [u32; LANES],
    rng: StreamLanes<S>,
    rays: RayPacket,
    beta: Vec3s<S>,
    l: Vec3s<S>,
    /// Scattering events so far (small integers, exact as floats).
    bounces: F32s<S>,
    /// Lanes whose ray left a surface vertex (else the camera), that vertex and the
    /// BSDF pdf of the ray's direction there.
    has_prev: LaneBits,
    prev_p: Vec3s<S>,
    prev_pdf: F32s<S>,
    slots: PixelSlots,
    /// Next sample to start, as (tile pixel, sample).
    next: (u32, u32),
    stopped: bool,
}

/// What the scene says about each lane's hit.
struct HitData<S: Simd> {
    si: Hits<S>,
    /// Triangle lanes (the others hit spheres), their corners, sphere centres and radii.
    triangles: LaneBits,
    corners: [Vec3s<S>; 3],
    centre: Vec3s<S>,
    radius: [f32; LANES],
    albedo: Vec3s<S>,
    /// Lanes on a surface that scatters nothing (an area light's).
    black: LaneBits,
    /// The area light whose surface each lane hit (`NO_LIGHT` if none).
    light: [u32; LANES],
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
    #[inline(always)]
    fn new(s: S, it: &'b PacketPathIntegrator<'a>, work: &'b TileWork<'t>) -> Self {
        let zero = F32s::splat(s, 0.0);
        let spp = work.spp.max(1) as usize;
        let none = U64s::splat(s, 0);
        Kernel {
            s,
            it,
            work,
            live: 0,
            pixel: [0; LANES],
            sample: [0; LANES],
            rng: StreamLanes::new(s, work.seed, none, none),
            rays: RayPacket::default(),
            beta: Vec3s::new(zero, zero, zero),
            l: Vec3s::new(zero, zero, zero),
            bounces: zero,
            has_prev: 0,
            prev_p: Vec3s::new(zero, zero, zero),
            prev_pdf: zero,
            slots: PixelSlots {
                spp,
                pixel: [u32::MAX; SLOTS],
                key: [0; SLOTS],
                values: vec![Color::ZERO; SLOTS * spp],
                done: [0; SLOTS],
            },
            next: (0, 0),
            stopped: false,
        }
    }

    #[inline(always)]
    fn run(mut self, out: &mut [Option<PixelSum>]) {
        let mut hits = HitPacket::default();
        loop {
            self.refill();
            if self.live == 0 {
                break;
            }
            self.it
                .accel
                .intersect_packet(&self.rays, self.live, &mut hits);
            let ended = self.bounce(&hits);
            self.finish(ended, out);
        }
    }

    // ---- lane helpers ----

    #[inline(always)]
    fn f(&self, x: f32) -> F32s<S> {
        F32s::splat(self.s, x)
    }

    #[inline(always)]
    fn mask(&self, bits: LaneBits) -> Mask<S> {
        Mask::from_bits(self.s, bits)
    }

    /// One uniform number per lane of `lanes` (`Sampler::next_f32`).
    #[inline(always)]
    fn next_f32(&mut self, lanes: LaneBits) -> F32s<S> {
        let m = self.mask(lanes);
        self.rng.next_f32(self.s, m)
    }

    /// Two uniform numbers per lane of `lanes` (`Sampler::next_2d`).
    #[inline(always)]
    fn next_2d(&mut self, lanes: LaneBits) -> (F32s<S>, F32s<S>) {
        let m = self.mask(lanes);
        self.rng.next_2d(self.s, m)
    }

    /// Lanes of `lanes` where light found after `bounces` scattering events counts
    /// (`PathIntegrator::counts`).
    #[inline(always)]
    fn counts(&self, lanes: LaneBits) -> LaneBits {
        let max = self.f(self.it.max_depth as f32);
        let ok = if self.it.accumulate {
            self.bounces.le(max)
        } else {
            self.bounces.eq(max)
        };
        ok.bits() & lanes
    }

    /// Lanes of `lanes` at the depth cap.
    #[inline(always)]
    fn at_depth_cap(&self, lanes: LaneBits) -> LaneBits {
        self.bounces.ge(self.f(self.it.max_depth as f32)).bits() & lanes
    }

    /// `L += beta · c` in lanes `m`.
    #[inline(always)]
    fn add_radiance(&mut self, m: LaneBits, c: Vec3s<S>) {
        if m != 0 {
            let sum = self.l + self.beta * c;
            self.l = Vec3s::select(self.mask(m), sum, self.l);
        }
    }

    /// Starts the next samples in the free lanes: their streams and camera rays, as
    /// the scalar renderer makes them (`Camera::sample_ray`, pinhole).
    #[inline(always)]
    fn refill(&mut self) {
        let s = self.s;
        let (fresh, pixel_key, index, xy) = self.assign_samples();
        if fresh == 0 {
            return;
        }
        let m = self.mask(fresh);
        let streams = StreamLanes::of_pixels(
            s,
            U64s::from_array(s, pixel_key),
            U64s::from_array(s, index),
        );
        self.rng = self.rng.replace(m, streams);
        let (xi_x, xi_y) = self.next_2d(fresh);
        let cam = self.it.camera;
        let (one, two) = (self.f(1.0), self.f(2.0));
        let u = (U32s::from_array(s, xy[0]).to_f32() + xi_x) / self.f(cam.width as f32);
        let v = (U32s::from_array(s, xy[1]).to_f32() + xi_y) / self.f(cam.height as f32);
        let a = (two * u - one) * self.f(cam.tan_half_x);
        let b = (one - two * v) * self.f(cam.tan_half_y);
        let d = (Vec3s::splat(s, cam.right) * a + Vec3s::splat(s, cam.up) * b)
            + Vec3s::splat(s, cam.forward);
        let d = d.normalize(s);
        let o = Vec3s::splat(s, cam.eye);
        let rays = &mut self.rays;
        rays.o = Vec3s::select(m, o, Vec3s::from_arrays(s, &rays.o)).to_arrays();
        rays.d = Vec3s::select(m, d, Vec3s::from_arrays(s, &rays.d)).to_arrays();
        let t_max = F32s::from_array(s, rays.t_max);
        rays.t_max = F32s::select(m, F32s::splat(s, f32::INFINITY), t_max).to_array();
        let skip = U32s::from_array(s, rays.skip);
        rays.skip = U32s::select(m, U32s::splat(s, NO_PRIM), skip).to_array();
        self.beta = Vec3s::select(m, Vec3s::splat(s, Vec3::ONE), self.beta);
        self.l = Vec3s::select(m, Vec3s::splat(s, Vec3::ZERO), self.l);
        self.bounces = F32s::select(m, self.f(0.0), self.bounces);
        self.has_prev &= !fresh;
        self.live |= fresh;
    }

    /// Gives the free lanes the next samples of the tile, in order: the lanes
    /// started, and per lane its pixel's `PixelStreams::key`, the sample's index
    /// and the pixel's `(x, y)`.
    #[allow(clippy::type_complexity)]
    #[inline(always)]
    fn assign_samples(&mut self) -> (LaneBits, [u64; LANES], [u64; LANES], [[u32; LANES]; 2]) {
        let spp = self.work.spp.max(1);
        let npix = self.work.pixels.len() as u32;
        let width = self.it.camera.width as u64;
        let mut fresh: LaneBits = 0;
        let mut pixel_key = [0u64; LANES];
        let mut index = [0u64; LANES];
        let mut xy = [[0u32; LANES]; 2];
        while (self.live | fresh) != ALL_LANES && !self.stopped {
            let (px, sample) = self.next;
            if px >= npix {
                break;
            }
            let slot = PixelSlots::slot_of(px);
            let (x, y) = self.work.pixels[px as usize];
            if sample == 0 {
                // A new pixel needs a free slot, and leave to start.
                if self.slots.pixel[slot] != u32::MAX {
                    break;
                }
                if (self.work.stop)() {
                    self.stopped = true;
                    break;
                }
                let image_pixel = y as u64 * width + x as u64;
                self.slots.pixel[slot] = px;
                self.slots.key[slot] = PixelStreams::new(self.work.seed, image_pixel).key();
                self.slots.done[slot] = 0;
            }
            let i = (!(self.live | fresh)).trailing_zeros() as usize;
            pixel_key[i] = self.slots.key[slot];
            index[i] = self.work.spp_offset as u64 + sample as u64;
            (xy[0][i], xy[1][i]) = (x, y);
            self.pixel[i] = px;
            self.sample[i] = sample;
            fresh |= 1 << i;
            self.next = if sample + 1 < spp {
                (px, sample + 1)
            } else {
                (px + 1, 0)
            };
        }
        (fresh, pixel_key, index, xy)
    }

    /// Records the radiance of the lanes in `ended` and frees them; pixels whose
    /// samples are all done are summed into `out`.
    #[inline(always)]
    fn finish(&mut self, ended: LaneBits, out: &mut [Option<PixelSum>]) {
        if ended == 0 {
            return;
        }
        let l = self.l.to_arrays();
        let spp = self.slots.spp;
        let mut rest = ended;
        while rest != 0 {
            let i = rest.trailing_zeros() as usize;
            rest &= rest - 1;
            let (px, sample) = (self.pixel[i], self.sample[i] as usize);
            let slot = PixelSlots::slot_of(px);
            self.slots.values[slot * spp + sample] = Vec3::new(l[0][i], l[1][i], l[2][i]);
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
        self.live &= !ended;
    }

    /// One bounce of every live lane, from its traced ray's `hits` (the body of the
    /// loop in `li`): the lanes whose path ended.
    #[inline(always)]
    fn bounce(&mut self, hits: &HitPacket) -> LaneBits {
        let s = self.s;
        let live = self.live;
        let o = Vec3s::from_arrays(s, &self.rays.o);
        let d = Vec3s::from_arrays(s, &self.rays.d);
        // The unit direction, once, as the scalar `li`.
        let w = d.normalize(s);
        let prims = U32s::from_array(s, hits.prim);
        let hit_lanes = !prims.eq(U32s::splat(s, NO_PRIM)).bits() & live;
        let triangles = self.it.scene.triangles.as_ptr();
        let mut rest = hit_lanes;
        while rest != 0 {
            let i = rest.trailing_zeros() as usize;
            rest &= rest - 1;
            prefetch(triangles.wrapping_add(hits.prim[i] as usize));
        }
        let mut ended = 0;
        // Area lights the sampled line meets before the hit end the path there.
        let with_prev = live & self.has_prev;
        if with_prev != 0 {
            ended |= self.area_light_on_line(with_prev, hits, hit_lanes, o, d, w);
        }
        // Escaped paths end: nothing here lights them.
        ended |= live & !hit_lanes;
        let lanes = live & !ended;
        if lanes == 0 {
            return ended;
        }
        let mut hit = self.hit_data(lanes, hits, o, d);
        let from_prev = lanes & self.has_prev;
        if from_prev != 0 {
            hit.si = self.on_line(from_prev, &hit, w);
        }
        let si = hit.si;
        // Emission seen by camera rays (other vertices' light was found above).
        let seen = self.counts(lanes & !self.has_prev);
        if seen != 0 {
            self.emitted(seen, &hit.light, si, w);
        }
        // Paths end at the depth cap and on lights' surfaces.
        let stop = (self.at_depth_cap(lanes) | hit.black) & lanes;
        ended |= stop;
        let lanes = lanes & !stop;
        if lanes == 0 {
            return ended;
        }
        let one_more = self.bounces + self.f(1.0);
        self.bounces = F32s::select(self.mask(lanes), one_more, self.bounces);
        let frame = Frame::from_normal(s, si.ns);
        let wo_world = -w;
        let wo = frame.to_local(wo_world);
        let direct = self.counts(lanes);
        if direct != 0 {
            self.direct(direct, &hits.prim, &hit, &frame, wo);
        }
        ended |= self.scatter(lanes, &hits.prim, &hit, &frame, wo, wo_world);
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
        let prev = self.prev_p;
        let t = F32s::from_array(s, hits.t);
        let at = o + d * t;
        let t_hit = F32s::select(
            self.mask(hit_lanes),
            (at - prev).dot(w),
            self.f(f32::INFINITY),
        );
        // The light whose surface each lane hit, from the lights' primitive ids (no
        // scene lookup: the triangle records are not in cache yet).
        let prims = U32s::from_array(s, hits.prim);
        let mut hit_light = U32s::splat(s, NO_LIGHT);
        for &(prim, light) in &self.it.light_prims {
            let on = prims.eq(U32s::splat(s, prim)) & self.mask(hit_lanes);
            hit_light = U32s::select(on, U32s::splat(s, light), hit_light);
        }
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
        let counted = self.counts(best);
        if counted != 0 && self.it.mis {
            self.add_light_found(counted, best_light, prev, w);
        }
        // With light sampling alone the weight is 0: nothing to add.
        best
    }

    /// MIS-weighted emission of the area lights `light` found from `prev` along `w`
    /// in lanes `lanes` (`bsdf_hit_weight`).
    #[cold]
    fn add_light_found(&mut self, lanes: LaneBits, light: U32s<S>, prev: Vec3s<S>, w: Vec3s<S>) {
        let s = self.s;
        let ids = light.to_array();
        let (prev_a, wa) = (prev.to_arrays(), w.to_arrays());
        let mut le = [[0.0; LANES]; 3];
        let mut light_pdf = [0.0; LANES];
        for i in (0..LANES).filter(|&i| lanes >> i & 1 != 0) {
            let light = &self.it.lights[ids[i] as usize];
            let p = Vec3::new(prev_a[0][i], prev_a[1][i], prev_a[2][i]);
            let dir = Vec3::new(wa[0][i], wa[1][i], wa[2][i]);
            light_pdf[i] = light.pdf_li(p, dir);
            (le[0][i], le[1][i], le[2][i]) = light.radiance.into();
        }
        let weight = power_heuristic(
            s,
            self.f(1.0),
            self.prev_pdf,
            self.f(self.it.light_samples as f32),
            F32s::from_array(s, light_pdf),
        );
        let le = Vec3s::from_arrays(s, &le) * weight;
        self.add_radiance(lanes, le);
    }

    /// The scene's data for the hits in `lanes` (`Scene::interaction`).
    #[inline(always)]
    fn hit_data(&self, lanes: LaneBits, hits: &HitPacket, o: Vec3s<S>, d: Vec3s<S>) -> HitData<S> {
        let s = self.s;
        let scene = self.it.scene;
        let ntri = scene.triangles.len();
        let mut corner = [[[0.0f32; LANES]; 3]; 3];
        let mut normal = [[[0.0f32; LANES]; 3]; 3];
        let mut has_normals: LaneBits = 0;
        let mut triangles: LaneBits = 0;
        let mut centre = [[0.0f32; LANES]; 3];
        let mut radius = [0.0f32; LANES];
        let mut albedo = [[0.0f32; LANES]; 3];
        let mut black: LaneBits = 0;
        let mut light = [NO_LIGHT; LANES];
        // First the triangles' records, asking for their corners' and normals'
        // memory as the indices arrive, so the misses of all lanes overlap.
        let mut vertex = [[0u32; LANES]; 3];
        let mut normal_index = [[0u32; LANES]; 3];
        let mut material = [0usize; LANES];
        let mut rest = lanes;
        while rest != 0 {
            let i = rest.trailing_zeros() as usize;
            rest &= rest - 1;
            let p = hits.prim[i] as usize;
            material[i] = if p < ntri {
                let tri = &scene.triangles[p];
                triangles |= 1 << i;
                for (k, &v) in tri.v.iter().enumerate() {
                    vertex[k][i] = v;
                    prefetch(scene.positions.as_ptr().wrapping_add(v as usize));
                }
                if let Some(n) = tri.n {
                    has_normals |= 1 << i;
                    for (k, &v) in n.iter().enumerate() {
                        normal_index[k][i] = v;
                        prefetch(scene.normals.as_ptr().wrapping_add(v as usize));
                    }
                }
                light[i] = tri.light;
                tri.material as usize
            } else {
                let sp = &scene.spheres[p - ntri];
                (centre[0][i], centre[1][i], centre[2][i]) = sp.centre.into();
                radius[i] = sp.radius;
                sp.material as usize
            };
        }
        let mut rest = lanes;
        while rest != 0 {
            let i = rest.trailing_zeros() as usize;
            rest &= rest - 1;
            if triangles >> i & 1 != 0 {
                for (k, v) in vertex.iter().enumerate() {
                    let q = scene.positions[v[i] as usize];
                    (corner[k][0][i], corner[k][1][i], corner[k][2][i]) = q.into();
                }
            }
            if has_normals >> i & 1 != 0 {
                for (k, v) in normal_index.iter().enumerate() {
                    let q = scene.normals[v[i] as usize];
                    (normal[k][0][i], normal[k][1][i], normal[k][2][i]) = q.into();
                }
            }
            (albedo[0][i], albedo[1][i], albedo[2][i]) = self.it.albedo[material[i]].into();
            black |= (self.it.black[material[i]] as LaneBits) << i;
        }
        let b1 = F32s::from_array(s, hits.b1);
        let b2 = F32s::from_array(s, hits.b2);
        let corners = corner.map(|c| Vec3s::from_arrays(s, &c));
        let [p0, p1, p2] = corners;
        let mut si = triangle_points(s, triangles, p0, p1, p2, b1, b2);
        if has_normals != 0 {
            let [n0, n1, n2] = normal.map(|c| Vec3s::from_arrays(s, &c));
            let (ng, ns) = shading_normals(s, si.ng, n0, n1, n2, b1, b2);
            let m = self.mask(has_normals);
            si.ng = Vec3s::select(m, ng, si.ng);
            si.ns = Vec3s::select(m, ns, si.ns);
        }
        let centre = Vec3s::from_arrays(s, &centre);
        let spheres = lanes & !triangles;
        if spheres != 0 {
            let t = F32s::from_array(s, hits.t);
            let r = F32s::from_array(s, radius);
            let sp = sphere_points(s, o, d, t, centre, r);
            let m = self.mask(spheres);
            si = Hits {
                p: Vec3s::select(m, sp.p, si.p),
                p_error: Vec3s::select(m, sp.p_error, si.p_error),
                ng: Vec3s::select(m, sp.ng, si.ng),
                ns: Vec3s::select(m, sp.ns, si.ns),
            };
        }
        HitData {
            si,
            triangles,
            corners,
            centre,
            radius,
            albedo: Vec3s::from_arrays(s, &albedo),
            black,
            light,
        }
    }

    /// `Scene::on_line` for the lanes in `lanes`: the hit moved onto the sampled
    /// line from the previous vertex.
    #[inline(always)]
    fn on_line(&self, lanes: LaneBits, hit: &HitData<S>, w: Vec3s<S>) -> Hits<S> {
        let s = self.s;
        let si = hit.si;
        let from = self.prev_p;
        let zero = self.f(0.0);
        let cos = w.dot(si.ng);
        let steep = cos.abs().ge(self.f(0.05));
        let dist = (si.p - from).dot(si.ng) / cos;
        let ahead = dist.gt(zero) & dist.is_finite();
        let p = from + w * dist;
        let p_error = si.p_error + p.abs() * self.f(gamma(1)) + (w * dist).abs() * self.f(gamma(5));
        // Triangles: the point must lie in the hit triangle; exact axes stay.
        let [p0, p1, p2] = hit.corners;
        let (inside, b1, b2) = barycentrics(s, p0, p1, p2, p);
        let on_tri = self.mask(lanes & hit.triangles) & steep & ahead & inside;
        let p_tri = into_triangles(s, on_tri.bits(), p, from, w * dist, hit.corners, b1, b2);
        let exact = exact_axes(p0, p1, p2);
        let tri_p = Vec3s::new(
            F32s::select(exact[0], si.p.x, p_tri.x),
            F32s::select(exact[1], si.p.y, p_tri.y),
            F32s::select(exact[2], si.p.z, p_tri.z),
        );
        let tri_err = Vec3s::new(
            F32s::select(exact[0], zero, p_error.x),
            F32s::select(exact[1], zero, p_error.y),
            F32s::select(exact[2], zero, p_error.z),
        );
        // Spheres: the normal again at the moved point.
        let n = normalize_or_zero(s, (from - hit.centre) + w * dist);
        let facing = n.dot(si.ng).gt(zero);
        let tri_m = self.mask(hit.triangles);
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
        let on_light = !U32s::from_array(self.s, *light)
            .eq(U32s::splat(self.s, NO_LIGHT))
            .bits();
        let mut rest = lanes & on_light;
        if rest == 0 {
            return;
        }
        let cos_out = (-w).dot(si.ng).to_array();
        while rest != 0 {
            let i = rest.trailing_zeros() as usize;
            rest &= rest - 1;
            let Some(Light::Area(a)) = self.it.scene.lights.get(light[i] as usize) else {
                continue;
            };
            let e = a.emitted(cos_out[i]);
            if e != Color::ZERO {
                any |= 1 << i;
                (le[0][i], le[1][i], le[2][i]) = e.into();
            }
        }
        let le = Vec3s::from_arrays(self.s, &le);
        self.add_radiance(any, le);
    }

    /// `PathIntegrator::direct` by light sampling (with MIS weights when asked):
    /// one shadow packet per light sample, contributions summed in the scalar order.
    #[inline(always)]
    fn direct(
        &mut self,
        lanes: LaneBits,
        prims: &[u32; LANES],
        hit: &HitData<S>,
        frame: &Frame<S>,
        wo: Vec3s<S>,
    ) {
        let s = self.s;
        let (si, albedo) = (hit.si, hit.albedo);
        let zero = self.f(0.0);
        let n = self.it.light_samples;
        let nf = self.f(n as f32);
        let f = albedo * self.f(FRAC_1_PI);
        let f_black = f.x.eq(zero) & f.y.eq(zero) & f.z.eq(zero);
        let wo_world = frame.to_world(wo);
        let mut acc = Vec3s::splat(s, Vec3::ZERO);
        let mut shadow = RayPacket {
            t_max: [1.0 - SHADOW_EPSILON; LANES],
            skip: *prims,
            ..RayPacket::default()
        };
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
                let origin = spawn_origins(s, ok, hit, target - si.p);
                shadow.o = origin.to_arrays();
                shadow.d = (target - origin).to_arrays();
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
                acc = Vec3s::select(self.mask(lit), acc + contrib / nf, acc);
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
        hit: &HitData<S>,
        frame: &Frame<S>,
        wo: Vec3s<S>,
        wo_world: Vec3s<S>,
    ) -> LaneBits {
        let s = self.s;
        let (si, albedo) = (hit.si, hit.albedo);
        let zero = self.f(0.0);
        // `material.sample(wo, next_f32(), next_2d())`: the lobe number is drawn too.
        self.rng.skip(s, self.mask(lanes));
        let (u1, u2) = self.next_2d(lanes);
        // Cosine-weighted direction on the side of `wo` (`lambertian::sample`).
        let finite = wo.x.is_finite() & wo.y.is_finite() & wo.z.is_finite();
        let (dx, dy) = concentric_disk_lanes(s, u1, u2);
        let z = (self.f(1.0) - (dx * dx + dy * dy)).max(zero).sqrt();
        let sampled = finite & !wo.z.eq(zero) & z.gt(zero);
        let wi = Vec3s::new(dx, dy, z.copysign(wo.z));
        let pdf = wi.z.abs().max(zero) * self.f(FRAC_1_PI);
        let mut ended = lanes & !sampled.bits();
        // At the depth cap only MIS still traces the ray, to weight the light it finds.
        if !self.it.mis {
            ended |= self.at_depth_cap(lanes);
        }
        let wi_world = frame.to_world(wi);
        let reflect = (wi.z * wo.z).gt(zero);
        let consistent = geometrically_consistent(s, si.ng, wo_world, wi_world, reflect);
        ended |= lanes & !consistent.bits();
        let go = lanes & !ended;
        let beta = self.beta * albedo;
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
            self.beta = Vec3s::select(m, beta, self.beta);
            self.prev_p = Vec3s::select(m, si.p, self.prev_p);
            self.prev_pdf = F32s::select(m, pdf, self.prev_pdf);
            self.has_prev |= survive;
            let origin = spawn_origins(s, survive, hit, wi_world);
            let rays = &mut self.rays;
            rays.o = Vec3s::select(m, origin, Vec3s::from_arrays(s, &rays.o)).to_arrays();
            rays.d = Vec3s::select(m, wi_world, Vec3s::from_arrays(s, &rays.d)).to_arrays();
            let t_max = F32s::from_array(s, rays.t_max);
            rays.t_max = F32s::select(m, F32s::splat(s, f32::INFINITY), t_max).to_array();
            let skip = U32s::from_array(s, rays.skip);
            rays.skip = U32s::select(m, U32s::from_array(s, *prims), skip).to_array();
        }
        ended
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
        let playing = self.bounces.ge(self.f(start as f32)).bits() & lanes;
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
fn sample_area<S: Simd>(
    s: S,
    a: &AreaLight,
    p: Vec3s<S>,
    u1: F32s<S>,
    u2: F32s<S>,
) -> AreaSample<S> {
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
    if area.is_nan() || area <= 0.0 || a.radiance == Color::ZERO {
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
    if m2.is_nan() || m2 <= 0.0 {
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
    lanes: LaneBits,
    p0: Vec3s<S>,
    p1: Vec3s<S>,
    p2: Vec3s<S>,
    b1: F32s<S>,
    b2: F32s<S>,
) -> Hits<S> {
    let (e1, e2) = (p1 - p0, p2 - p0);
    let (t1, t2) = (e1 * b1, e2 * b2);
    let local = t1 + t2;
    let p = p0 + local;
    let p_error =
        p.abs() * F32s::splat(s, gamma(2)) + (t1.abs() + t2.abs()) * F32s::splat(s, gamma(4));
    let p = into_triangles(s, lanes, p, p0, local, [p0, p1, p2], b1, b2);
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

/// `Scene::barycentrics`: whether `q`, in the plane of `(p0, p1, p2)`, lies in it,
/// and its `b1, b2`.
#[inline(always)]
fn barycentrics<S: Simd>(
    s: S,
    p0: Vec3s<S>,
    p1: Vec3s<S>,
    p2: Vec3s<S>,
    q: Vec3s<S>,
) -> (Mask<S>, F32s<S>, F32s<S>) {
    let (e1, e2, d) = (p1 - p0, p2 - p0, q - p0);
    let m = e1.cross(e2);
    let m2 = m.length_squared();
    let b1 = d.cross(e2).dot(m) / m2;
    let b2 = e1.cross(d).dot(m) / m2;
    let zero = F32s::splat(s, 0.0);
    let inside = b1.ge(zero) & b2.ge(zero) & (b1 + b2).le(F32s::splat(s, 1.0));
    (inside, b1, b2)
}

/// `scene::into_triangle` of `p = a ⊕ b` in the lanes in `lanes`, triangle corners
/// `t`, barycentrics `b1, b2`. Its edge test is run here with four times its margin,
/// so that whatever the lanes' rounding, every lane it would move is handed to it
/// (they are rare: within half an ulp of an edge); it decides and rounds each.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn into_triangles<S: Simd>(
    s: S,
    lanes: LaneBits,
    p: Vec3s<S>,
    a: Vec3s<S>,
    b: Vec3s<S>,
    t: [Vec3s<S>; 3],
    b1: F32s<S>,
    b2: F32s<S>,
) -> Vec3s<S> {
    let [p0, p1, p2] = t;
    let area2 = (p1 - p0).cross(p2 - p0).length_squared().sqrt();
    let margin = (p.abs() * F32s::splat(s, 4.0 * gamma(1)))
        .length_squared()
        .sqrt();
    let b0 = F32s::splat(s, 1.0) - b1 - b2;
    let near = near_edge(b0, p2 - p1, area2, margin)
        | near_edge(b1, p2 - p0, area2, margin)
        | near_edge(b2, p1 - p0, area2, margin);
    let mut moved = near.bits() & lanes;
    if moved == 0 {
        return p;
    }
    let mut out = p.to_arrays();
    let (b1, b2) = (b1.to_array(), b2.to_array());
    while moved != 0 {
        let i = moved.trailing_zeros() as usize;
        moved &= moved - 1;
        let bary = [1.0 - b1[i] - b2[i], b1[i], b2[i]];
        let corners = [p0.lane(i), p1.lane(i), p2.lane(i)];
        let q = into_triangle(p.lane(i), a.lane(i), b.lane(i), corners, bary);
        (out[0][i], out[1][i], out[2][i]) = q.into();
    }
    Vec3s::from_arrays(s, &out)
}

/// Whether the point at barycentric `bk` is within `margin` of the edge `edge`
/// opposite corner k (`area2`: twice the triangle's area).
#[inline(always)]
fn near_edge<S: Simd>(bk: F32s<S>, edge: Vec3s<S>, area2: F32s<S>, margin: F32s<S>) -> Mask<S> {
    (bk * area2).le(margin * edge.length_squared().sqrt())
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

/// `SurfaceInteraction::spawn_origin` for the lanes in `lanes` of `hit`, towards
/// `w`: off the surface by the error bound, or (one sphere lane at a time) just on
/// `w`'s side of the sphere.
#[inline(always)]
fn spawn_origins<S: Simd>(s: S, lanes: LaneBits, hit: &HitData<S>, w: Vec3s<S>) -> Vec3s<S> {
    let si = &hit.si;
    let offset = offset_ray_origin(s, si.p, si.p_error, si.ng, w);
    let mut spheres = lanes & !hit.triangles;
    if spheres == 0 {
        return offset;
    }
    let mut out = offset.to_arrays();
    while spheres != 0 {
        let i = spheres.trailing_zeros() as usize;
        spheres &= spheres - 1;
        let (p, ng) = (si.p.lane(i), si.ng.lane(i));
        let outward = w.lane(i).dot(ng) > 0.0;
        if let Some(o) = sphere_spawn_origin(p, ng, outward, hit.centre.lane(i), hit.radius[i]) {
            (out[0][i], out[1][i], out[2][i]) = o.into();
        }
    }
    Vec3s::from_arrays(s, &out)
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

/// `sampling::concentric_disk` in lanes, operation for operation.
#[inline(always)]
fn concentric_disk_lanes<S: Simd>(s: S, u1: F32s<S>, u2: F32s<S>) -> (F32s<S>, F32s<S>) {
    let (zero, one, two) = (
        F32s::splat(s, 0.0),
        F32s::splat(s, 1.0),
        F32s::splat(s, 2.0),
    );
    let (ox, oy) = (two * u1 - one, two * u2 - one);
    let centre = ox.eq(zero) & oy.eq(zero);
    let x_major = ox.abs().gt(oy.abs());
    let r = F32s::select(x_major, ox, oy);
    let ratio = F32s::select(x_major, oy / ox, ox / oy);
    let (sin, cos) = sin_cos_quarter_lanes(s, F32s::splat(s, std::f32::consts::FRAC_PI_4) * ratio);
    let x = F32s::select(x_major, r * cos, r * sin);
    let y = F32s::select(x_major, r * sin, r * cos);
    (F32s::select(centre, zero, x), F32s::select(centre, zero, y))
}

/// `sampling::sin_cos_quarter` in lanes.
#[inline(always)]
fn sin_cos_quarter_lanes<S: Simd>(s: S, x: F32s<S>) -> (F32s<S>, F32s<S>) {
    let [s0, s1, s2] = SIN_POLY.map(|c| F32s::splat(s, c));
    let [c0, c1, c2] = COS_POLY.map(|c| F32s::splat(s, c));
    let z = x * x;
    let sin = ((s0 * z + s1) * z + s2) * z * x + x;
    let cos = ((c0 * z + c1) * z + c2) * z * z - F32s::splat(s, 0.5) * z + F32s::splat(s, 1.0);
    (sin, cos)
}
