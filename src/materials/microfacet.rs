//! Rough conductor of spec §6: Beckmann NDF, separable Smith shadowing-masking
//! with the exact Beckmann Λ, exact conductor Fresnel. Sampled by the
//! distribution of normals `D(h)·cos θh`, reflected about `h`. Two-sided: on the
//! back face the frame is mirrored (z of both directions flipped).

use super::fresnel::ConductorIor;
use super::BsdfSample;
use crate::sampling::{beckmann_d, beckmann_normal, beckmann_normal_pdf};
use crate::Color;
use glam::{Vec2, Vec3};

/// Below this roughness the Beckmann lobe is narrower than f32 can resolve
/// (α² underflows D's exponent), so α is clamped: a near-mirror remains a valid,
/// finite glossy lobe rather than turning into a delta.
pub const MIN_ALPHA: f32 = 1e-3;

/// A rough conductor's parameters, built once when the material is made (the loader):
/// α clamped, the Fresnel terms of its complex index precomputed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Conductor {
    /// Beckmann roughness, at least [`MIN_ALPHA`] (a non-finite α is taken as 1).
    pub alpha: f32,
    pub ior: ConductorIor,
}

impl Conductor {
    pub fn new(alpha: f32, eta: Color, k: Color) -> Self {
        let alpha = if alpha.is_finite() { alpha } else { 1.0 };
        Conductor {
            alpha: alpha.max(MIN_ALPHA),
            ior: ConductorIor::new(eta, k),
        }
    }

    /// The real part of the complex index, per channel.
    pub fn eta(&self) -> Color {
        self.ior.eta
    }

    /// The imaginary part (absorption) of the complex index, per channel.
    pub fn k(&self) -> Color {
        self.ior.k
    }

    pub fn eval(&self, wo: Vec3, wi: Vec3) -> Color {
        let Some((wo, wi, h)) = upper_pair(wo, wi) else {
            return Color::ZERO;
        };
        let d = beckmann_d(h, self.alpha);
        let g = self.g1(wo, h) * self.g1(wi, h);
        let f = self.ior.reflectance(wi.dot(h).abs());
        let value = f * (d * g / (4.0 * wi.z * wo.z));
        if crate::color::is_finite(value) {
            value
        } else {
            Color::ZERO
        }
    }

    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        let Some((wo, _, h)) = upper_pair(wo, wi) else {
            return 0.0;
        };
        reflected_pdf(beckmann_normal_pdf(h, self.alpha), wo.dot(h))
    }

    pub fn sample(&self, wo: Vec3, u: Vec2) -> Option<BsdfSample> {
        if wo.z == 0.0 {
            return None;
        }
        let flip = wo.z < 0.0;
        let wo_up = mirror_z(wo, flip);
        let h = beckmann_normal(u, self.alpha);
        let wo_dot_h = wo_up.dot(h);
        if wo_dot_h <= 0.0 {
            return None;
        }
        let wi_up = (2.0 * wo_dot_h * h - wo_up).normalize();
        if wi_up.z <= 0.0 {
            // Reflected below the surface: that mass is lost (pdf() is 0 there).
            return None;
        }
        let wi = mirror_z(wi_up, flip);
        let pdf = self.pdf(wo, wi);
        if !(pdf > 0.0 && pdf.is_finite()) {
            return None;
        }
        let weight = self.eval(wo, wi) * (wi.z.abs() / pdf);
        crate::color::is_finite(weight).then_some(BsdfSample {
            wi,
            weight,
            pdf,
            delta: false,
        })
    }

    /// Smith masking of one direction; 0 when `w` sees the back of the microfacet.
    pub fn g1(&self, w: Vec3, h: Vec3) -> f32 {
        if w.dot(h) * w.z <= 0.0 {
            return 0.0;
        }
        1.0 / (1.0 + beckmann_lambda(w, self.alpha))
    }
}

/// `Λ(w) = (erf(a) − 1)/2 + exp(−a²)/(2a√π)`, `a = 1/(α·tan θ)`. Written with
/// `erfc(a) = 1 − erf(a)`, the same function without the cancellation for large a.
pub fn beckmann_lambda(w: Vec3, alpha: f32) -> f32 {
    let cos = w.z.abs() as f64;
    let sin = (1.0 - cos * cos).max(0.0).sqrt();
    if sin == 0.0 {
        return 0.0;
    }
    if cos == 0.0 {
        return f32::INFINITY;
    }
    let a = cos / (alpha as f64 * sin);
    let inv_sqrt_pi = 0.5 * std::f64::consts::FRAC_2_SQRT_PI;
    let lambda = 0.5 * ((-a * a).exp() * inv_sqrt_pi / a - libm::erfc(a));
    lambda.max(0.0) as f32
}

/// Both directions moved to the upper hemisphere (mirroring the frame on the back
/// face) with their half vector, or `None` when they are not strictly on one side.
fn upper_pair(wo: Vec3, wi: Vec3) -> Option<(Vec3, Vec3, Vec3)> {
    if wo.z * wi.z <= 0.0 {
        return None;
    }
    let flip = wo.z < 0.0;
    let (wo, wi) = (mirror_z(wo, flip), mirror_z(wi, flip));
    let h = (wo + wi).try_normalize()?;
    Some((wo, wi, h))
}

/// Density of the reflected direction given the half-vector density:
/// the Jacobian of `wi = reflect(wo, h)` is `1/(4·|wo·h|)`.
fn reflected_pdf(pdf_h: f32, wo_dot_h: f32) -> f32 {
    if wo_dot_h <= 0.0 {
        return 0.0;
    }
    let pdf = pdf_h / (4.0 * wo_dot_h);
    if pdf.is_finite() {
        pdf
    } else {
        0.0
    }
}

#[inline]
fn mirror_z(w: Vec3, flip: bool) -> Vec3 {
    if flip {
        Vec3::new(w.x, w.y, -w.z)
    } else {
        w
    }
}
