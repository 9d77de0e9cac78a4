//! The unidirectional path tracer of spec §7.
//!
//! A path with `k` scattering events ("bounces") contributes when `k ≤ m`
//! (accumulation on) or `k = m` (off). Emission found by a ray leaving vertex
//! `x_k` and light sampled at `x_k` both belong to paths of `k` bounces.

use super::{DirectStrategy, Roulette};
use crate::accel::Accel;
use crate::color::is_finite;
use crate::geometry::{Frame, Ray};
use crate::lights::Light;
use crate::materials::Material;
use crate::sampling::{power_heuristic, uniform_hemisphere, uniform_hemisphere_pdf, Sampler};
use crate::scene::{PrimHit, Scene, SurfaceInteraction, NO_LIGHT};
use crate::Color;
use glam::Vec3;

/// Shadow rays stop this fraction short of the sampled light point, so the light's own
/// surface does not occlude it; relative, so it works at every scene scale.
pub(super) const SHADOW_EPSILON: f32 = 1e-4;

/// The parameters of spec §7 that shape the estimator.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PathSettings {
    pub max_depth: u32,
    pub accumulate: bool,
    pub light_samples: u32,
    pub strategy: DirectStrategy,
    pub roulette: Roulette,
}

pub struct PathIntegrator<'a> {
    scene: &'a Scene,
    accel: &'a dyn Accel,
    max_depth: u32,
    accumulate: bool,
    light_samples: u32,
    strategy: DirectStrategy,
    roulette: Roulette,
    unsampled_emitters: bool,
}

/// State of the vertex a ray just left, needed to weight emission it finds.
#[derive(Clone, Copy)]
struct PrevVertex {
    p: Vec3,
    bsdf_pdf: f32,
    delta: bool,
}

impl<'a> PathIntegrator<'a> {
    pub fn new(scene: &'a Scene, accel: &'a dyn Accel, s: PathSettings) -> Self {
        PathIntegrator {
            scene,
            accel,
            max_depth: s.max_depth,
            accumulate: s.accumulate,
            light_samples: s.light_samples.max(1),
            strategy: s.strategy,
            roulette: s.roulette,
            unsampled_emitters: scene.has_unsampled_emitters(),
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

    /// Radiance arriving along the camera ray `ray`.
    pub fn li(&self, mut ray: Ray, sampler: &mut Sampler) -> Color {
        let mut l = Color::ZERO;
        let mut beta = Color::ONE;
        let mut prev: Option<PrevVertex> = None; // None: the camera
        let mut bounces = 0u32;
        loop {
            let hit = self.accel.intersect(&ray);
            // The unit direction, once: emission, the line test and `wo` all use it.
            let w = ray.d.normalize();
            if let Some(v) = prev {
                if let Some(le) = self.area_light_on_line(v, &ray, w, hit.as_ref()) {
                    if self.counts(bounces) {
                        l += beta * le;
                    }
                    break;
                }
            }
            let Some(hit) = hit else {
                if self.counts(bounces) {
                    l += beta * self.escaped(w, prev);
                }
                break;
            };
            let mut si = self.scene.interaction(&ray, &hit);
            if let Some(v) = prev {
                si = self.scene.on_line(&si, v.p, w);
            }
            let wo_world = -w;
            let material = &self.scene.material_at(&si);
            if self.counts(bounces) {
                l += beta * self.emitted(&si, wo_world, prev);
            }
            if bounces >= self.max_depth || material.is_black() {
                break;
            }
            bounces += 1;
            let frame = Frame::from_normal(si.ns);
            let wo = frame.to_local(wo_world);
            if !material.is_delta() && self.counts(bounces) {
                l += beta * self.direct(&si, &frame, material, wo, sampler);
            }
            let Some(bs) = material.sample(wo, sampler.next_f32(), sampler.next_2d()) else {
                break;
            };
            if bounces >= self.max_depth && !bs.delta && !self.bsdf_rays_find_light() {
                // The ray could only find emission that this strategy gives weight 0.
                break;
            }
            let wi_world = frame.to_world(bs.wi);
            if !geometrically_consistent(&si, wo_world, wi_world, bs.wi.z * wo.z > 0.0) {
                break;
            }
            beta *= bs.weight;
            let Some(q) = self.roulette.play(bounces, beta, sampler) else {
                break;
            };
            beta /= q;
            if !is_finite(beta) || beta == Color::ZERO {
                break;
            }
            prev = Some(PrevVertex {
                p: si.p,
                bsdf_pdf: bs.pdf,
                delta: bs.delta,
            });
            ray = si.spawn_ray(wi_world);
        }
        l
    }

    /// Whether a BSDF-sampled ray leaving a non-delta vertex can add light: with MIS,
    /// or when the scene has emitters that light sampling cannot pick.
    fn bsdf_rays_find_light(&self) -> bool {
        match self.strategy {
            DirectStrategy::Mis | DirectStrategy::Bsdf => true,
            DirectStrategy::Hemisphere => false,
            DirectStrategy::Light => self.unsampled_emitters,
        }
    }

    /// MIS weight of emission found by a BSDF-sampled ray leaving `prev`. `light` is
    /// the light it belongs to (None for emissive surfaces that light sampling cannot pick).
    fn bsdf_hit_weight(&self, prev: Option<PrevVertex>, light: Option<&Light>, dir: Vec3) -> f32 {
        match prev {
            None => 1.0,
            Some(v) if v.delta => 1.0,
            Some(v) => match (self.strategy, light) {
                // The hemisphere estimator already counted every emitter the direction finds.
                (DirectStrategy::Hemisphere, _) => 0.0,
                // Nothing else estimates direct light: the BSDF-sampled ray counts in full.
                (DirectStrategy::Bsdf, _) => 1.0,
                (_, None) => 1.0,
                (DirectStrategy::Light, Some(_)) => 0.0,
                (DirectStrategy::Mis, Some(l)) => power_heuristic(
                    1.0,
                    v.bsdf_pdf,
                    self.light_samples as f32,
                    l.pdf_li(v.p, dir),
                ),
            },
        }
    }

    /// The area light that the line from `v`'s surface point along `ray`'s direction
    /// meets before what `ray` hit, and its MIS-weighted emission.
    ///
    /// `ray` starts off the surface by the point's rounding error (`offset_ray_origin`:
    /// a few ulps of the coordinates, 1e-3…4e-3 at 1e4), on a line parallel to the
    /// sampled one and that much closer to what it finds: seen from there an area light
    /// covers more directions (a floor 2 below a light gains 2·δ/2: 0.4 % for δ = 4e-3;
    /// stability case 5), and with MIS those extra directions get the full BSDF weight,
    /// because the light's pdf from `v.p` is 0 there. So which light the sampled line
    /// reaches is decided analytically from `v.p`, relative to each light (`AreaLight::
    /// intersect`); the traced ray only says what lies in front of it. The path ends at
    /// the light, as it would on its surface (lights do not reflect).
    ///
    /// `w` is `ray.d` normalised.
    fn area_light_on_line(
        &self,
        v: PrevVertex,
        ray: &Ray,
        w: Vec3,
        hit: Option<&PrimHit>,
    ) -> Option<Color> {
        // How far along the line from v.p the traced ray's hit lies (∞ for a miss).
        let t_hit = hit.map_or(f32::INFINITY, |h| (ray.at(h.t) - v.p).dot(w));
        // Primitives past the triangles are spheres, never lights.
        let hit_light = hit
            .and_then(|h| self.scene.triangles.get(h.prim as usize))
            .map_or(NO_LIGHT, |t| t.light);
        let mut best: Option<(f32, &Light)> = None;
        for (i, light) in self.scene.lights.iter().enumerate() {
            let Some(t) = light.intersect_area(v.p, w) else {
                continue;
            };
            // The light the ray hit counts wherever the line meets it (they differ by the offset).
            if (t < t_hit || i as u32 == hit_light) && best.is_none_or(|(b, _)| t < b) {
                best = Some((t, light));
            }
        }
        let (_, light) = best?;
        let le = light.as_area()?.radiance;
        Some(le * self.bsdf_hit_weight(Some(v), Some(light), w))
    }

    fn emitted(&self, si: &SurfaceInteraction, wo: Vec3, prev: Option<PrevVertex>) -> Color {
        let le = self.scene.emission(si, wo);
        if le == Color::ZERO {
            return le;
        }
        let light = (si.light != NO_LIGHT).then(|| &self.scene.lights[si.light as usize]);
        // `area_light_on_line` already counted any area light the sampled line meets.
        if let (Some(v), Some(l)) = (prev, light) {
            if !l.seen_along(v.p, -wo) {
                return Color::ZERO;
            }
        }
        le * self.bsdf_hit_weight(prev, light, -wo)
    }

    /// Light reaching a ray that left the scene in unit direction `d`.
    fn escaped(&self, d: Vec3, prev: Option<PrevVertex>) -> Color {
        let mut l = Color::ZERO;
        for light in &self.scene.lights {
            let le = light.le_escaped(d);
            if le != Color::ZERO {
                l += le * self.bsdf_hit_weight(prev, Some(light), d);
            }
        }
        l
    }

    /// Direct light at a non-delta vertex by the chosen strategy.
    fn direct(
        &self,
        si: &SurfaceInteraction,
        frame: &Frame,
        m: &Material,
        wo: Vec3,
        s: &mut Sampler,
    ) -> Color {
        match self.strategy {
            DirectStrategy::Hemisphere => self.direct_hemisphere(si, frame, m, wo, s),
            DirectStrategy::Bsdf => Color::ZERO,
            DirectStrategy::Light | DirectStrategy::Mis => {
                let mut l = Color::ZERO;
                for light in &self.scene.lights {
                    let n = if light.is_delta() {
                        1
                    } else {
                        self.light_samples.max(1)
                    };
                    for _ in 0..n {
                        l += self.light_sample(si, frame, m, wo, light, n, s) / n as f32;
                    }
                }
                l
            }
        }
    }

    /// One light sample's contribution `f·Li·|cos|/pdf`, MIS-weighted when asked.
    #[allow(clippy::too_many_arguments)]
    fn light_sample(
        &self,
        si: &SurfaceInteraction,
        frame: &Frame,
        m: &Material,
        wo: Vec3,
        light: &Light,
        n: u32,
        s: &mut Sampler,
    ) -> Color {
        let Some(ls) = light.sample_li(si.p, s.next_2d()) else {
            return Color::ZERO;
        };
        if ls.pdf.is_nan() || ls.pdf <= 0.0 || ls.li == Color::ZERO {
            return Color::ZERO;
        }
        let wi = frame.to_local(ls.wi);
        let wo_world = frame.to_world(wo);
        if !geometrically_consistent(si, wo_world, ls.wi, wi.z * wo.z > 0.0) {
            return Color::ZERO;
        }
        let f = m.eval(wo, wi);
        if f == Color::ZERO {
            return Color::ZERO;
        }
        if self.shadowed(si, &ls) {
            return Color::ZERO;
        }
        let w = if ls.delta || self.strategy != DirectStrategy::Mis {
            1.0
        } else {
            power_heuristic(n as f32, ls.pdf, 1.0, m.pdf(wo, wi))
        };
        f * ls.li * (wi.z.abs() * w / ls.pdf)
    }

    fn shadowed(&self, si: &SurfaceInteraction, ls: &crate::lights::LightSample) -> bool {
        let ray = if ls.dist.is_finite() {
            si.spawn_segment(ls.p_light, 1.0 - SHADOW_EPSILON)
        } else {
            si.spawn_ray(ls.wi)
        };
        self.accel.occluded(&ray)
    }

    /// `-H`: `l` uniform directions on the hemisphere of `wo`, counting whatever emission they find.
    fn direct_hemisphere(
        &self,
        si: &SurfaceInteraction,
        frame: &Frame,
        m: &Material,
        wo: Vec3,
        s: &mut Sampler,
    ) -> Color {
        let n = self.light_samples.max(1);
        let mut l = Color::ZERO;
        for _ in 0..n {
            let mut wi = uniform_hemisphere(s.next_2d());
            if wo.z < 0.0 {
                wi.z = -wi.z;
            }
            let wi_world = frame.to_world(wi);
            let f = m.eval(wo, wi);
            if f == Color::ZERO || !geometrically_consistent(si, frame.to_world(wo), wi_world, true)
            {
                continue;
            }
            let ray = si.spawn_ray(wi_world);
            let le = match self.accel.intersect(&ray) {
                Some(h) => {
                    let hit = self.scene.interaction(&ray, &h);
                    let light =
                        (hit.light != NO_LIGHT).then(|| &self.scene.lights[hit.light as usize]);
                    if light.is_some_and(|l| !l.seen_along(si.p, wi_world)) {
                        Color::ZERO
                    } else {
                        self.scene.emission(&hit, -wi_world)
                    }
                }
                None => self
                    .scene
                    .lights
                    .iter()
                    .map(|lt| lt.le_escaped(wi_world))
                    .sum(),
            };
            l += f * le * (wi.z.abs() / uniform_hemisphere_pdf());
        }
        l / n as f32
    }
}

/// Rejects directions whose side of the geometric surface contradicts the BSDF's
/// (shading-frame) reflection/transmission choice, so shading normals cannot leak light.
#[inline]
fn geometrically_consistent(si: &SurfaceInteraction, wo: Vec3, wi: Vec3, reflect: bool) -> bool {
    let a = wo.dot(si.ng);
    let b = wi.dot(si.ng);
    if reflect {
        a * b > 0.0
    } else {
        a * b < 0.0
    }
}
