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
//! Determinism: a render is `spp·W·H` light paths cut into chunks of `CHUNK_PATHS`,
//! each with its own random stream; each chunk records its splats, and the splats
//! are added to the film in chunk order, so the image depends on the seed only.

use super::{PathSettings, Roulette};
use crate::accel::Accel;
use crate::camera::Camera;
use crate::color::is_finite;
use crate::film::Image;
use crate::geometry::{Frame, Ray};
use crate::lights::Light;
use crate::materials::{specular, Material};
use crate::render::{PixelRect, RenderJob, RenderOutput, RenderSettings, Shading, StopToken};
use crate::sampling::Sampler;
use crate::scene::{Scene, SurfaceInteraction};
use crate::Color;
use glam::{Vec2, Vec3};
use rayon::prelude::*;

/// Light paths per chunk (one random stream each).
const CHUNK_PATHS: u64 = 4096;
/// Chunks traced in parallel before their splats are added (bounds memory).
const CHUNKS_PER_GROUP: u64 = 64;
/// Sampler pass ids, distinct from the path tracer's pixel streams.
const LIGHT_PASS: u64 = 0x4C54_0001;
const CAMERA_PASS: u64 = 0x4C54_0002;

pub struct LightTracer<'a> {
    scene: &'a Scene,
    accel: &'a dyn Accel,
    camera: &'a Camera,
    max_depth: u32,
    accumulate: bool,
    roulette: Roulette,
    /// Cumulative light-selection probabilities, proportional to emitted power.
    light_cdf: Vec<f32>,
}

/// One splat: pixel column, row and value (before division by paths per pixel).
type Splat = (u32, u32, Color);

impl<'a> LightTracer<'a> {
    pub fn new(
        scene: &'a Scene,
        accel: &'a dyn Accel,
        camera: &'a Camera,
        s: PathSettings,
    ) -> Self {
        let radius = 0.5 * scene.bounds.diagonal().length();
        let radius = if radius.is_finite() { radius } else { 1.0 };
        let power: Vec<f32> = scene.lights.iter().map(|l| l.power(radius)).collect();
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
        LightTracer {
            scene,
            accel,
            camera,
            max_depth: s.max_depth,
            accumulate: s.accumulate,
            roulette: s.roulette,
            light_cdf,
        }
    }

    #[inline]
    fn counts(&self, bounces: u32) -> bool {
        if self.accumulate {
            bounces <= self.max_depth
        } else {
            bounces == self.max_depth
        }
    }

    /// A light index chosen in proportion to power, and its probability.
    fn pick_light(&self, u: f32) -> Option<(usize, f32)> {
        let i = self.light_cdf.iter().position(|&c| u < c)?;
        let prev = if i == 0 { 0.0 } else { self.light_cdf[i - 1] };
        let p = self.light_cdf[i] - prev;
        (p > 0.0).then_some((i, p))
    }

    /// Traces one light path, pushing its camera connections to `splats`. Returns the
    /// number of non-finite contributions dropped.
    pub fn trace(&self, sampler: &mut Sampler, splats: &mut Vec<Splat>) -> u32 {
        let u_light = sampler.next_f32();
        let (u_pos, u_dir) = (sampler.next_2d(), sampler.next_2d());
        let Some((li, p_light)) = self.pick_light(u_light) else {
            return 0;
        };
        let Some(es) = self.scene.lights[li].sample_le(&self.scene.bounds, u_pos, u_dir) else {
            return 0;
        };
        let mut beta = es.beta / p_light;
        let beta0 = beta.max_element();
        if beta0.is_nan() || beta0 <= 0.0 {
            return 0;
        }
        let mut ray = Ray::new(es.origin, es.dir);
        // Where the current ray's line starts, when its origin was moved off a surface.
        let mut from = es.on_surface;
        let mut bounces = 0u32;
        let mut nonfinite = 0;
        while let Some(hit) = self.accel.intersect(&ray) {
            let mut si = self.scene.interaction(&ray, &hit);
            if let Some(from) = from {
                si = self.scene.on_line(&si, from, ray.d.normalize());
            }
            let material = &self.scene.material_at(&si);
            if material.is_black() || bounces >= self.max_depth {
                break;
            }
            bounces += 1;
            let w_light = -ray.d.normalize();
            let frame = Frame::from_normal(si.ns);
            if !material.is_delta() && self.counts(bounces) {
                // A lens point only with a lens, so pinhole renders keep their random numbers.
                let u_lens = match self.camera.lens.is_pinhole() {
                    true => Vec2::ZERO,
                    false => sampler.next_2d(),
                };
                let vertex = (&si, &frame, material);
                nonfinite += self.connect_to_camera(vertex, u_lens, w_light, beta, splats);
            }
            if bounces >= self.max_depth {
                break;
            }
            let wl = frame.to_local(w_light);
            let Some(bs) = material.sample(wl, sampler.next_f32(), sampler.next_2d()) else {
                break;
            };
            let w_next = frame.to_world(bs.wi);
            let reflect = bs.wi.z * wl.z > 0.0;
            if !geometrically_consistent(&si, w_light, w_next, reflect) {
                break;
            }
            beta *= bs.weight * adjoint_factor(material, &si, wl, bs.wi, w_light, w_next);
            let Some(q) = self.roulette.play(bounces, beta / beta0, sampler) else {
                break;
            };
            beta /= q;
            if !is_finite(beta) || beta == Color::ZERO {
                break;
            }
            ray = si.spawn_ray(w_next);
            from = Some(si.p);
        }
        nonfinite
    }

    /// Connects a non-specular vertex, lit along `w_light` with power `beta`, to the eye.
    fn connect_to_camera(
        &self,
        (si, frame, m): (&SurfaceInteraction, &Frame, &Material),
        u_lens: Vec2,
        w_light: Vec3,
        beta: Color,
        splats: &mut Vec<Splat>,
    ) -> u32 {
        let Some(c) = self.camera.connect(si.p, u_lens) else {
            return 0;
        };
        let (wl, wc) = (frame.to_local(w_light), frame.to_local(c.to_eye));
        if !geometrically_consistent(si, c.to_eye, w_light, wl.z * wc.z > 0.0) {
            return 0;
        }
        let f = m.eval(wc, wl);
        if f == Color::ZERO {
            return 0;
        }
        // The path tracer's |cos| is taken with the shading normal on the light side;
        // Veach's adjoint correction (thesis §5.3) turns the geometric cosine toward the
        // camera into that.
        let cos = shading_correction(si, wl, w_light) * c.to_eye.dot(si.ng).abs();
        let value = beta * f * (cos * c.importance);
        if !is_finite(value) {
            return 1;
        }
        if value == Color::ZERO {
            return 0;
        }
        if self.accel.occluded(&si.spawn_segment(c.origin, 1.0)) {
            return 0;
        }
        splats.push((c.x, c.y, value));
        0
    }

    /// Mean emitted radiance seen directly through pixel `(x, y)` (0-bounce paths).
    fn seen_directly(&self, x: u32, y: u32, spp: u32, sampler: &mut Sampler) -> Color {
        let mut sum = Color::ZERO;
        for _ in 0..spp {
            let ray = self.camera.sample_ray(x, y, sampler);
            sum += match self.accel.intersect(&ray) {
                Some(h) => {
                    let si = self.scene.interaction(&ray, &h);
                    self.scene.emission(&si, -ray.d.normalize())
                }
                None => self.scene.lights.iter().map(|l| l.le_escaped(ray.d)).sum(),
            };
        }
        sum / spp as f32
    }
}

/// `|wl·ns|/|wl·ng|`: the shading-normal factor of the adjoint BSDF (0 when grazing).
fn shading_correction(si: &SurfaceInteraction, wl_local: Vec3, w_light: Vec3) -> f32 {
    let g = w_light.dot(si.ng).abs();
    if g > 0.0 {
        wl_local.z.abs() / g
    } else {
        0.0
    }
}

/// What turns a BSDF sample drawn from the light side (`wl`, its weight
/// `f·|cos θ_next|/pdf` in the shading frame) into the adjoint transport of power:
/// Veach's shading-normal correction `|wl·ns|·|w_next·ng| / (|wl·ng|·|w_next·ns|)`, and,
/// for refraction, no `(ηi/ηt)²` radiance scaling (power is not compressed by refraction).
fn adjoint_factor(
    m: &Material,
    si: &SurfaceInteraction,
    wl: Vec3,
    w_next_local: Vec3,
    w_light: Vec3,
    w_next: Vec3,
) -> f32 {
    let ns_next = w_next_local.z.abs();
    if ns_next.is_nan() || ns_next <= 0.0 {
        return 0.0;
    }
    let mut k = shading_correction(si, wl, w_light) * w_next.dot(si.ng).abs() / ns_next;
    let transmitted = wl.z * w_next_local.z < 0.0;
    if let (true, Material::Glass { ior, .. } | Material::Refraction { ior, .. }) = (transmitted, m)
    {
        let (eta_i, eta_t) = specular::indices(wl, *ior);
        k *= (eta_t / eta_i) * (eta_t / eta_i);
    }
    k
}

/// The side of the geometric surface must agree with the shading frame's choice of
/// reflection or transmission (as in the path tracer), so shading normals cannot leak.
#[inline]
fn geometrically_consistent(si: &SurfaceInteraction, a: Vec3, b: Vec3, reflect: bool) -> bool {
    let (x, y) = (a.dot(si.ng), b.dot(si.ng));
    if reflect {
        x * y > 0.0
    } else {
        x * y < 0.0
    }
}

/// Emitters a camera ray can see directly (they need the camera pass).
fn has_visible_emitters(scene: &Scene) -> bool {
    scene.lights.iter().any(|l| !l.is_delta())
        || scene.has_unsampled_emitters()
        || scene
            .materials
            .iter()
            .any(|m| matches!(m, Material::Emission { .. }))
}

/// What light tracing cannot show in `scene`, said out loud (for settings that use it).
pub fn warnings(scene: &Scene, s: &RenderSettings) -> Vec<String> {
    let mut w = Vec::new();
    if s.shading != Shading::Radiance {
        return w;
    }
    if s.max_depth > 0 && scene.materials.iter().any(|m| m.is_delta()) {
        w.push(
            "light tracing cannot connect mirror or glass surfaces to the pinhole camera: \
             they look black except for light they transmit from behind; use path tracing"
                .into(),
        );
    }
    if s.max_depth > 0 && scene.has_unsampled_emitters() {
        w.push(
            "light tracing starts paths on lights only: light that emissive surfaces \
             (not lights) cast on the scene is missing; use path tracing"
                .into(),
        );
    }
    if s.max_depth > 0
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
    if s.adaptive.is_some() {
        w.push("adaptive sampling (-a) does not apply to light tracing: ignored".into());
    }
    w
}

/// Renders pixels `rect` of `job` with light tracing: `spp·W·H` light paths over the
/// whole image (a light path lands anywhere), of which the splats inside `rect` are
/// kept, plus the 0-bounce image from the camera when the scene has emitters a camera
/// can see. A rectangle is therefore exactly the crop of the full image, at the cost
/// of tracing every path (one full frame's work per rectangle).
pub fn render(
    job: &RenderJob,
    settings: &RenderSettings,
    rect: PixelRect,
    progress: &(dyn Fn(u64) + Sync),
    stop: &StopToken,
) -> RenderOutput {
    let (scene, camera) = (&job.scene, &job.camera);
    let npix = camera.width as u64 * camera.height as u64;
    let spp = settings.spp.max(1);
    let tracer = LightTracer::new(
        scene,
        job.accel.as_ref(),
        camera,
        settings.path_settings(scene),
    );
    let total = spp as u64 * npix;
    let chunks = total.div_ceil(CHUNK_PATHS);
    let (rw, rh) = (rect.width(), rect.height());
    let mut sum = vec![Color::ZERO; rect.area() as usize];
    let mut nonfinite = 0u64;
    let done = |c: u64| c * rect.area() / chunks.max(1);
    let mut group = 0;
    while group < chunks && !stop.should_stop() {
        let end = (group + CHUNKS_PER_GROUP).min(chunks);
        let results: Vec<(Vec<Splat>, u32)> = (group..end)
            .into_par_iter()
            .map(|c| {
                let mut sampler = Sampler::new(settings.seed, c, LIGHT_PASS);
                let mut splats = Vec::new();
                let mut bad = 0;
                for _ in 0..CHUNK_PATHS.min(total - c * CHUNK_PATHS) {
                    bad += tracer.trace(&mut sampler, &mut splats);
                }
                progress(done(c + 1) - done(c));
                (splats, bad)
            })
            .collect();
        for (splats, bad) in results {
            nonfinite += bad as u64;
            for (x, y, v) in splats {
                if (rect.x0..rect.x1).contains(&x) && (rect.y0..rect.y1).contains(&y) {
                    sum[((y - rect.y0) * rw + (x - rect.x0)) as usize] += v;
                }
            }
        }
        group = end;
    }
    // A stopped render divides by the paths it traced (`spp · pixels` when complete),
    // and sees emitters directly with as many camera samples.
    let traced = (group * CHUNK_PATHS).min(total);
    let per_pixel = traced as f64 / npix as f64;
    let spp = per_pixel.ceil() as u32;
    let mut image = Image::new(rw, rh);
    for (p, s) in image.pixels.iter_mut().zip(&sum) {
        *p = if traced == 0 {
            Color::ZERO
        } else {
            *s / per_pixel as f32
        };
    }
    if spp > 0 && tracer.counts(0) && has_visible_emitters(scene) {
        let direct: Vec<Color> = (0..rect.area())
            .into_par_iter()
            .map(|i| {
                let (x, y) = (
                    rect.x0 + (i % rw as u64) as u32,
                    rect.y0 + (i / rw as u64) as u32,
                );
                let pixel = y as u64 * camera.width as u64 + x as u64;
                let mut sampler = Sampler::new(settings.seed, pixel, CAMERA_PASS);
                tracer.seen_directly(x, y, spp, &mut sampler)
            })
            .collect();
        for (p, d) in image.pixels.iter_mut().zip(direct) {
            *p += d;
        }
    }
    RenderOutput {
        image,
        samples: vec![spp; rect.area() as usize],
        nonfinite_samples: nonfinite,
    }
}
