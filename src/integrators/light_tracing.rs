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
//! Determinism: a render is `spp·W·H` light paths, numbered; each chunk of
//! `CHUNK_PATHS` draws its numbers as one stratified set, and the render driver adds
//! the splats chunk by chunk in order, so the image depends on the seed only.

use super::Engine;
use super::{PathIntegrator, PathSettings, SampleIntegrator, Splat, SplatIntegrator};
use crate::accel::Accel;
use crate::camera::Camera;
use crate::color::is_finite;
use crate::geometry::{Frame, Ray};
use crate::lanes::One;
use crate::lights::Light;
use crate::materials::Material;
use crate::sampling::{pixel_key, SampleStream};
use crate::scene::{Scene, SurfaceInteraction};
use crate::Color;
use glam::{Vec2, Vec3};

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
    scene: &'a Scene,
    accel: &'a dyn Accel,
    camera: &'a Camera,
    s: PathSettings,
    seed: u64,
    /// Cumulative light-selection probabilities, proportional to emitted power.
    light_cdf: Vec<f32>,
    /// Emitters seen directly (0-bounce paths), which only camera rays can find.
    direct: Option<PathIntegrator<'a>>,
}

impl<'a> LightTracer<'a> {
    pub fn new(
        scene: &'a Scene,
        accel: &'a dyn Accel,
        camera: &'a Camera,
        s: PathSettings,
        engine: Engine,
        seed: u64,
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
        let zero_bounces = PathSettings {
            max_depth: 0,
            accumulate: true,
            ..s
        };
        let counts_zero = s.accumulate || s.max_depth == 0;
        let direct = (counts_zero && has_visible_emitters(scene))
            .then(|| PathIntegrator::new(scene, accel, camera, zero_bounces, engine, seed));
        LightTracer {
            scene,
            accel,
            camera,
            s,
            seed,
            light_cdf,
            direct,
        }
    }

    #[inline]
    fn counts(&self, bounces: u32) -> bool {
        if self.s.accumulate {
            bounces <= self.s.max_depth
        } else {
            bounces == self.s.max_depth
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
    fn trace(&self, stream: &SampleStream<One>, splats: &mut Vec<Splat>) -> u32 {
        let get = |pair: u32| {
            let (x, y) = stream.get_2d(pair);
            Vec2::new(x, y)
        };
        let Some((li, p_light)) = self.pick_light(get(CHOICE_PAIR).x) else {
            return 0;
        };
        let (u_pos, u_dir) = (get(POSITION_PAIR), get(DIRECTION_PAIR));
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
            if !material.scatters() || bounces >= self.s.max_depth {
                break;
            }
            bounces += 1;
            let base = DIRECTION_PAIR + 1 + (bounces - 1) * PAIRS_PER_BOUNCE;
            let w_light = -ray.d.normalize();
            let frame = Frame::from_normal(si.ns);
            if !material.is_delta() && self.counts(bounces) {
                let u_lens = get(base);
                let vertex = (&si, &frame, material);
                nonfinite += self.connect_to_camera(vertex, u_lens, w_light, beta, splats);
            }
            if bounces >= self.s.max_depth {
                break;
            }
            let wl = frame.to_local(w_light);
            let u_lobe = get(base + 2);
            let Some(bs) = material.sample(wl, u_lobe.x, get(base + 1)) else {
                break;
            };
            let w_next = frame.to_world(bs.wi);
            let reflect = bs.wi.z * wl.z > 0.0;
            if !geometrically_consistent(&si, w_light, w_next, reflect) {
                break;
            }
            beta *= bs.weight * adjoint_factor(material, &si, wl, bs.wi, w_light, w_next);
            let q = self.s.roulette.continue_prob(bounces, beta / beta0);
            if q < 1.0 && u_lobe.y >= q {
                break;
            }
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
}

impl SplatIntegrator for LightTracer<'_> {
    fn trace_paths(&self, first: u64, count: u64, splats: &mut Vec<Splat>) -> u32 {
        let mut nonfinite = 0;
        for path in first..first + count {
            let chunk = path / CHUNK_PATHS;
            let stream = SampleStream::<One> {
                kind: self.s.sampler,
                key: pixel_key(self.seed ^ LIGHT_PATHS, chunk),
                index: (path % CHUNK_PATHS) as u32,
            };
            nonfinite += self.trace(&stream, splats);
        }
        nonfinite
    }

    fn camera_part(&self) -> Option<&dyn SampleIntegrator> {
        self.direct.as_ref().map(|p| p as &dyn SampleIntegrator)
    }
}

/// Mixed into the seed of light paths, so they do not share the pixels' streams.
const LIGHT_PATHS: u64 = 0x4C54_0001;

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
    let k = shading_correction(si, wl, w_light) * w_next.dot(si.ng).abs() / ns_next;
    k / m.radiance_scale(wl, w_next_local)
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
