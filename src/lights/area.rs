//! One-sided parallelogram (rectangle in every scene) emitting constant radiance
//! toward `normal`, sampled uniformly by area and converted to solid angle. The light
//! owns its surface: `Scene::add_area_light` emits its triangles from `quad`, and a
//! ray hitting them reads the radiance here (`emitted`).

use super::emit::EmissionSample;
use super::Incident;
use crate::geometry::{offset_ray_origin, ray::gamma, Frame};
use crate::lanes::{Lanes, One, Real, V3};
use crate::sampling::cosine_hemisphere;
use crate::sampling::warps::uniform_parallelogram_l;
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

    /// A point uniform by area, as seen from points `p`, per lane. The vector to it
    /// is computed relative to the light (`(centre − p) + s·ex + t·ey`, the first
    /// difference exact for nearby points however far from the origin), not as the
    /// difference of two rounded absolute positions.
    #[inline(always)]
    pub fn sample_incident<L: Lanes>(&self, l: L, p: V3<L::F>, u: (L::F, L::F)) -> Incident<L::F> {
        let (ex, ey) = (V3::splat(l, self.ex), V3::splat(l, self.ey));
        let local = uniform_parallelogram_l(u.0, u.1, ex, ey);
        let centre = V3::splat(l, self.centre);
        let to_light = (centre - p) + local;
        let dist = to_light.length_squared().sqrt();
        let wi = to_light / dist;
        let (pdf, facing) = self.solid_angle_pdf(l, wi, dist);
        let lit = dist.gt(l.f(0.0)) & dist.is_finite() & facing;
        Incident {
            wi,
            dist,
            p_light: centre + local,
            li: V3::splat(l, self.radiance),
            pdf,
            valid: lit
                & l.mask(if self.radiance == Color::ZERO {
                    0
                } else {
                    l.all()
                }),
        }
    }

    /// Emitted light leaving the surface (`Light::sample_le`): a point uniform by area
    /// (`pdf_pos = 1/area`), a direction by the cosine (`pdf_dir = cos/π`), so
    /// `β = L·cos/(pdf_pos·pdf_dir) = L·π·area`. The ray's origin is moved off the
    /// surface by the point's rounding error; `on_surface` keeps the point itself.
    pub fn sample_le(&self, u_pos: Vec2, u_dir: Vec2) -> EmissionSample {
        let (ex, ey) = (self.ex.into(), self.ey.into());
        let p = self.centre + uniform_parallelogram_l(u_pos.x, u_pos.y, ex, ey).vec3();
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

    /// The density of `sample_incident` at `wi` from `p`, per lane: found by
    /// intersecting the ray `(p, wi)`.
    #[inline(always)]
    pub fn pdf_incident<L: Lanes>(&self, l: L, p: V3<L::F>, wi: V3<L::F>) -> L::F {
        let (met, dist) = self.intersect_l(l, p, wi);
        let (pdf, ok) = self.solid_angle_pdf(l, wi, dist);
        L::F::select(met & ok, pdf, l.f(0.0))
    }

    /// `pdf_incident` for one path.
    pub fn pdf_li(&self, p: Vec3, wi: Vec3) -> f32 {
        self.pdf_incident(One, p.into(), wi.into())
    }

    /// Distance along unit `wi` from `p` to the emitting front of the light, if the
    /// ray hits it there (rays reaching the back see nothing emitted).
    pub fn intersect(&self, p: Vec3, wi: Vec3) -> Option<f32> {
        let (met, dist) = self.intersect_l(One, p.into(), wi.into());
        met.then_some(dist)
    }

    /// `intersect` per lane: the lanes that meet the front, and the distance.
    #[inline(always)]
    pub fn intersect_l<L: Lanes>(&self, l: L, p: V3<L::F>, wi: V3<L::F>) -> (L::M, L::F) {
        let normal = V3::splat(l, self.normal);
        let denom = wi.dot(normal);
        let to_centre = V3::splat(l, self.centre) - p;
        let dist = to_centre.dot(normal) / denom;
        let met = denom.lt(l.f(0.0)) & dist.gt(l.f(0.0)) & dist.is_finite();
        let m = self.ex.cross(self.ey);
        let m2 = m.length_squared();
        if m2.is_nan() || m2 <= 0.0 {
            return (l.mask(0), dist);
        }
        // The hit relative to the centre, in the dual basis (sheared edges work too),
        // without rounding it to an absolute position.
        let (ex, ey, mv, m2v) = (
            V3::splat(l, self.ex),
            V3::splat(l, self.ey),
            V3::splat(l, m),
            l.f(m2),
        );
        let d = wi * dist - to_centre;
        let s = d.cross(ey).dot(mv) / m2v;
        let t = ex.cross(d).dot(mv) / m2v;
        let half = l.f(0.5);
        (met & s.abs().le(half) & t.abs().le(half), dist)
    }

    /// Area density `1/area` converted to solid angle: `dist²/(area·cos θl)`, and the
    /// lanes where it is defined (the front of a non-degenerate light).
    #[inline(always)]
    fn solid_angle_pdf<L: Lanes>(&self, l: L, wi: V3<L::F>, dist: L::F) -> (L::F, L::M) {
        let cos_light = -wi.dot(V3::splat(l, self.normal));
        let area = self.area();
        let pdf = dist * dist / (l.f(area) * cos_light);
        let ok = cos_light.gt(l.f(0.0)) & pdf.is_finite() & pdf.gt(l.f(0.0));
        (pdf, ok & l.mask(if area > 0.0 { l.all() } else { 0 }))
    }
}
