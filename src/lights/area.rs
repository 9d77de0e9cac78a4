//! One-sided parallelogram (rectangle in every scene) emitting constant radiance
//! toward `normal`, sampled uniformly by area and converted to solid angle. The light
//! owns its surface: `Scene::add_area_light` emits its triangles from `quad`, and a
//! ray hitting them reads the radiance here (`emitted`).

use super::emit::EmissionSample;
use super::LightSample;
use crate::geometry::{offset_ray_origin, ray::gamma, Frame};
use crate::sampling::{cosine_hemisphere, uniform_parallelogram};
use crate::Color;
use glam::{Vec2, Vec3};
use std::f32::consts::PI;

/// The parallelogram `centre + s·ex + t·ey`, `s,t ∈ [−½,½]`, emitting `radiance` toward unit `normal`
/// (±`ex × ey`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AreaLight {
    pub centre: Vec3,
    pub ex: Vec3,
    pub ey: Vec3,
    pub normal: Vec3,
    pub radiance: Color,
}

impl AreaLight {
    /// Area of the parallelogram (the density of uniform sampling is its inverse).
    pub fn area(&self) -> f32 {
        self.ex.cross(self.ey).length()
    }

    /// Radiance leaving the surface at cosine `cos_out` with `normal` (front side only).
    pub fn emitted(&self, cos_out: f32) -> Color {
        if cos_out > 0.0 {
            self.radiance
        } else {
            Color::ZERO
        }
    }

    /// The two triangles of the light's surface, wound so that their geometric
    /// normal `(p1−p0)×(p2−p0)` is the emitting normal.
    pub fn quad(&self) -> [[Vec3; 3]; 2] {
        let (hx, hy) = (0.5 * self.ex, 0.5 * self.ey);
        let p00 = self.centre - hx - hy;
        let p10 = self.centre + hx - hy;
        let p11 = self.centre + hx + hy;
        let p01 = self.centre - hx + hy;
        if self.ex.cross(self.ey).dot(self.normal) > 0.0 {
            [[p00, p10, p11], [p00, p11, p01]]
        } else {
            [[p00, p11, p10], [p00, p01, p11]]
        }
    }

    /// A point uniform by area, as seen from `p`. The vector to it is computed relative to
    /// the light (`(centre − p) + s·ex + t·ey`, the first difference exact for nearby
    /// points however far from the origin), not as the difference of two rounded
    /// absolute positions.
    pub fn sample_li(&self, p: Vec3, u: Vec2) -> Option<LightSample> {
        let local = uniform_parallelogram(u, Vec3::ZERO, self.ex, self.ey);
        let p_light = self.centre + local;
        let to_light = (self.centre - p) + local;
        let dist2 = to_light.length_squared();
        let dist = dist2.sqrt();
        if !(dist > 0.0 && dist.is_finite()) {
            return None;
        }
        let wi = to_light / dist;
        let pdf = self.solid_angle_pdf(wi, dist)?;
        Some(LightSample {
            wi,
            dist,
            p_light,
            li: self.radiance,
            pdf,
            delta: false,
        })
    }

    /// Emitted light leaving the surface (`Light::sample_le`): a point uniform by area
    /// (`pdf_pos = 1/area`), a direction by the cosine (`pdf_dir = cos/π`), so
    /// `β = L·cos/(pdf_pos·pdf_dir) = L·π·area`. The ray's origin is moved off the
    /// surface by the point's rounding error; `on_surface` keeps the point itself.
    pub fn sample_le(&self, u_pos: Vec2, u_dir: Vec2) -> EmissionSample {
        let p = self.centre + uniform_parallelogram(u_pos, Vec3::ZERO, self.ex, self.ey);
        let dir = Frame::from_normal(self.normal)
            .to_world(cosine_hemisphere(u_dir))
            .normalize();
        // `centre ⊕ local`: one rounding of the sum plus that of `local`.
        let p_error = gamma(2) * p.abs() + gamma(3) * (0.5 * (self.ex.abs() + self.ey.abs()));
        EmissionSample {
            origin: offset_ray_origin(p, p_error, self.normal, dir),
            on_surface: Some(p),
            dir,
            beta: self.radiance * (PI * self.area()),
        }
    }

    /// The density of `sample_li`: found by intersecting the ray `(p, wi)`.
    pub fn pdf_li(&self, p: Vec3, wi: Vec3) -> f32 {
        self.intersect(p, wi)
            .and_then(|dist| self.solid_angle_pdf(wi, dist))
            .unwrap_or(0.0)
    }

    /// Distance along unit `wi` from `p` to the emitting front of the light, if
    /// the ray hits it there (rays reaching the back see nothing emitted).
    pub fn intersect(&self, p: Vec3, wi: Vec3) -> Option<f32> {
        let denom = wi.dot(self.normal);
        if denom.is_nan() || denom >= 0.0 {
            return None;
        }
        let to_centre = self.centre - p;
        let dist = to_centre.dot(self.normal) / denom;
        if !(dist > 0.0 && dist.is_finite()) {
            return None;
        }
        // The hit relative to the centre, without rounding it to an absolute position.
        let (s, t) = self.plane_coords(dist * wi - to_centre)?;
        (s.abs() <= 0.5 && t.abs() <= 0.5).then_some(dist)
    }

    /// `(s, t)` with `d = s·ex + t·ey` for `d` (relative to the centre) in the light's
    /// plane (dual basis, so sheared edges work too).
    fn plane_coords(&self, d: Vec3) -> Option<(f32, f32)> {
        let m = self.ex.cross(self.ey);
        let m2 = m.length_squared();
        if m2.is_nan() || m2 <= 0.0 {
            return None;
        }
        Some((d.cross(self.ey).dot(m) / m2, self.ex.cross(d).dot(m) / m2))
    }

    /// Area density `1/area` converted to solid angle: `dist²/(area·cos θl)`;
    /// `None` from behind or for a degenerate light.
    fn solid_angle_pdf(&self, wi: Vec3, dist: f32) -> Option<f32> {
        let cos_light = -wi.dot(self.normal);
        let area = self.area();
        if !(cos_light > 0.0 && area > 0.0) {
            return None;
        }
        let pdf = dist * dist / (area * cos_light);
        (pdf.is_finite() && pdf > 0.0).then_some(pdf)
    }
}
