//! Spot light (COLLADA `<spot>`): a point light whose radiant intensity depends on the
//! angle `θ` from its axis, `I(θ) = c·cos^e θ` inside the cone `θ ≤ falloff_angle/2`
//! and 0 outside. `c` is the point light's unit (W/sr, spec §5), reached on the axis;
//! `e = falloff_exponent` gives COLLADA's smooth falloff (`e = 0`: a sharp-edged cone).
//! `falloff_angle` is the cone's full angle, as Blender and most exporters write it
//! (its default, 180°, lights the front hemisphere; 360° with `e = 0` is the point
//! light). The
//! functions here are small and pure, so scalar and vector transports can share them.

use super::emit::EmissionSample;
use super::Incident;
use crate::geometry::Frame;
use crate::lanes::math::{exp, ln};
use crate::lanes::{Lanes, Real, V3};
use crate::sampling::uniform_cone;
use crate::Color;
use glam::{Vec2, Vec3};
use std::f32::consts::PI;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpotLight {
    pub position: Vec3,
    /// Unit axis: the direction the light shines along.
    pub direction: Vec3,
    /// Radiant intensity on the axis (W/sr).
    pub intensity: Color,
    /// `cos(falloff_angle/2)`; −1 when the cone covers every direction.
    pub cos_cutoff: f32,
    /// `falloff_exponent` (≥ 0).
    pub exponent: f32,
}

impl SpotLight {
    /// A spot from COLLADA's parameters: `falloff_angle` in degrees (the cone's full
    /// angle), `falloff_exponent`.
    pub fn new(
        position: Vec3,
        direction: Vec3,
        intensity: Color,
        falloff_angle: f32,
        exponent: f32,
    ) -> Self {
        let half = (0.5 * falloff_angle).clamp(0.0, 180.0).to_radians();
        SpotLight {
            position,
            direction: direction.normalize(),
            intensity,
            cos_cutoff: if falloff_angle >= 360.0 {
                -1.0
            } else {
                half.cos()
            },
            exponent: exponent.max(0.0),
        }
    }

    /// The cone's half angle in degrees.
    pub fn cutoff_degrees(&self) -> f32 {
        self.cos_cutoff.clamp(-1.0, 1.0).acos().to_degrees()
    }

    /// `I(θ)/c` for `cos θ` with the axis: `cos^e θ` inside the cone, 0 outside.
    /// Behind the light (`cos θ < 0`) a positive exponent gives 0, as `max(cos, 0)^e`.
    pub fn falloff(&self, cos_theta: f32) -> f32 {
        self.falloff_l(cos_theta)
    }

    /// [`falloff`](Self::falloff) per lane (`cos^e` as `exp(e·ln cos)`).
    #[inline(always)]
    pub fn falloff_l<F: Real>(&self, cos_theta: F) -> F {
        let power = if self.exponent == 0.0 {
            cos_theta.splat_as(1.0)
        } else {
            exp(cos_theta.splat_as(self.exponent) * ln(cos_theta.max(cos_theta.splat_as(0.0))))
        };
        F::select(
            cos_theta.lt(cos_theta.splat_as(self.cos_cutoff)),
            cos_theta.splat_as(0.0),
            power,
        )
    }

    /// The lowest `cos θ` at which light leaves: the cone's edge, or the axis's
    /// perpendicular when a positive exponent ends the light there first.
    fn cos_min(&self) -> f32 {
        if self.exponent > 0.0 {
            self.cos_cutoff.max(0.0)
        } else {
            self.cos_cutoff
        }
    }

    /// `∫ falloff dω` over the sphere: the power is `c` times this.
    pub fn solid_angle_weight(&self) -> f32 {
        let c = self.cos_min();
        if self.exponent == 0.0 {
            2.0 * PI * (1.0 - c)
        } else {
            // 2π ∫_c^1 x^e dx, with c ≥ 0 here.
            let e = self.exponent;
            2.0 * PI * (1.0 - c.powf(e + 1.0)) / (e + 1.0)
        }
    }

    /// Incident light at points `p`, per lane: a delta in direction, `I(θ)/d²`.
    #[inline(always)]
    pub fn sample_incident<L: Lanes>(&self, l: L, p: V3<L::F>) -> Incident<L::F> {
        let position = V3::splat(l, self.position);
        let to_light = position - p;
        let dist2 = to_light.length_squared();
        let dist = dist2.sqrt();
        let wi = to_light / dist;
        let f = self.falloff_l(-wi.dot(V3::splat(l, self.direction)));
        let li = V3::splat(l, self.intensity) * (f / dist2);
        let zero = l.f(0.0);
        Incident {
            wi,
            dist,
            p_light: position,
            li,
            pdf: l.f(1.0),
            valid: dist.gt(zero) & dist.is_finite() & f.gt(zero) & li.is_finite(),
        }
    }

    /// A ray of emitted light, its direction uniform in the cone of `cos θ ≥ cos_min`:
    /// pdf `1/(2π(1 − cos_min))`, so β = `I(θ)·2π(1 − cos_min)`.
    pub fn sample_le(&self, u: Vec2) -> Option<EmissionSample> {
        let c = self.cos_min();
        let local = uniform_cone(u, 1.0 - c);
        let dir = Frame::from_normal(self.direction).to_world(local);
        let beta = self.intensity * (self.falloff(local.z) * 2.0 * PI * (1.0 - c));
        (beta != Color::ZERO).then_some(EmissionSample {
            origin: self.position,
            on_surface: None,
            dir,
            beta,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spot(angle: f32, e: f32) -> SpotLight {
        SpotLight::new(Vec3::ZERO, Vec3::NEG_Y, Color::ONE, angle, e)
    }

    #[test]
    fn falloff_follows_collada() {
        let s = spot(60.0, 2.0);
        assert_eq!(s.falloff(1.0), 1.0);
        let c20 = 20f32.to_radians().cos();
        assert!((s.falloff(c20) - c20 * c20).abs() < 1e-6);
        assert_eq!(s.falloff(40f32.to_radians().cos()), 0.0);
        // 180° is the front hemisphere; 360° with exponent 0 is the point light.
        assert_eq!(spot(180.0, 0.0).falloff(-0.1), 0.0);
        let p = spot(360.0, 0.0);
        assert_eq!(p.falloff(-0.9), 1.0);
        assert!((p.solid_angle_weight() - 4.0 * PI).abs() < 1e-4);
    }

    /// `solid_angle_weight` is the integral of the falloff (midpoint rule in cos θ).
    #[test]
    fn solid_angle_weight_is_the_falloff_integral() {
        for (angle, e) in [
            (60.0, 0.0),
            (60.0, 3.0),
            (170.0, 1.5),
            (300.0, 0.0),
            (300.0, 2.0),
        ] {
            let s = spot(angle, e);
            let n = 200_000;
            let sum: f64 = (0..n)
                .map(|i| {
                    let c = -1.0 + 2.0 * (i as f64 + 0.5) / n as f64;
                    s.falloff(c as f32) as f64
                })
                .sum();
            let numeric = 2.0 * std::f64::consts::PI * sum * 2.0 / n as f64;
            let w = s.solid_angle_weight() as f64;
            assert!(
                (numeric - w).abs() < 2e-3 * w.max(1.0),
                "{angle} {e}: {numeric} vs {w}"
            );
        }
    }

    /// The mean β of emission samples is the power `c·∫falloff dω`.
    #[test]
    fn emission_beta_is_power() {
        let s = spot(70.0, 4.0);
        let n = 256;
        let mut sum = 0.0;
        for i in 0..n {
            for j in 0..n {
                let u = Vec2::new((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
                if let Some(e) = s.sample_le(u) {
                    assert!(e.dir.dot(s.direction) >= s.cos_cutoff - 1e-5);
                    sum += e.beta.x as f64;
                }
            }
        }
        let mean = sum / (n * n) as f64;
        let w = s.solid_angle_weight() as f64;
        assert!((mean - w).abs() < 1e-3 * w, "{mean} vs {w}");
    }
}
