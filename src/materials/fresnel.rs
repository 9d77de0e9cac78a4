//! Exact unpolarized Fresnel reflectance (spec §6): dielectric for glass, complex
//! index for conductors. Never Schlick: the spec asks for the exact terms.

use crate::lanes::{clamp, Real};
use crate::Color;

/// Reflectance of a smooth dielectric interface for light arriving at
/// `cos_theta_i = |cos θi| ∈ [0, 1]` from the side of index `eta_i` toward
/// `eta_t`. 1 under total internal reflection.
#[inline(always)]
pub fn dielectric<F: Real>(cos_theta_i: F, eta_i: F, eta_t: F) -> F {
    let cos_i = clamp(
        cos_theta_i,
        cos_theta_i.splat_as(0.0),
        cos_theta_i.splat_as(1.0),
    );
    let (cos_t, refracts) = refracted_cos(cos_i, eta_i / eta_t);
    let rs_den = eta_i * cos_i + eta_t * cos_t;
    let rp_den = eta_t * cos_i + eta_i * cos_t;
    let rs = (eta_i * cos_i - eta_t * cos_t) / rs_den;
    let rp = (eta_t * cos_i - eta_i * cos_t) / rp_den;
    let r = clamp(
        cos_theta_i.splat_as(0.5) * (rs * rs + rp * rp),
        cos_theta_i.splat_as(0.0),
        cos_theta_i.splat_as(1.0),
    );
    // Grazing incidence on a degenerate interface: everything reflects.
    let ok = refracts & rs_den.gt(cos_theta_i.splat_as(0.0)) & rp_den.gt(cos_theta_i.splat_as(0.0));
    F::select(ok, r, cos_theta_i.splat_as(1.0))
}

/// `cos θt` from Snell's law with relative index `eta_ratio = ηi/ηt`, and the lanes
/// where it exists (not under total internal reflection).
#[inline(always)]
pub fn refracted_cos<F: Real>(cos_theta_i: F, eta_ratio: F) -> (F, F::M) {
    let sin2_i =
        (cos_theta_i.splat_as(1.0) - cos_theta_i * cos_theta_i).max(cos_theta_i.splat_as(0.0));
    let sin2_t = eta_ratio * eta_ratio * sin2_i;
    let ok = sin2_t.lt(cos_theta_i.splat_as(1.0));
    (
        (cos_theta_i.splat_as(1.0) - sin2_t)
            .max(cos_theta_i.splat_as(0.0))
            .sqrt(),
        ok,
    )
}

/// Reflectance of a conductor with complex index `eta + i·k` (per channel) at
/// `cos_theta = |cos θ|`, with the spec's closed form.
pub fn conductor(cos_theta: f32, eta: Color, k: Color) -> Color {
    ConductorIor::new(eta, k).reflectance(cos_theta)
}

/// A conductor's complex index `eta + i·k` per channel, with the angle-independent
/// terms of the Fresnel closed form (`η² − k²`, `4η²k²`) computed once, at load.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ConductorIor {
    pub eta: Color,
    pub k: Color,
}

impl ConductorIor {
    pub fn new(eta: Color, k: Color) -> Self {
        ConductorIor { eta, k }
    }

    /// Reflectance at `cos_theta = |cos θ|`.
    pub fn reflectance(&self, cos_theta: f32) -> Color {
        // Per channel `η² − k²` and `4η²k²`, in f64 as the formula needs them.
        let [r, g, b] = [0, 1, 2].map(|i| {
            let (eta, k) = (self.eta[i] as f64, self.k[i] as f64);
            conductor_channel(cos_theta, (eta * eta - k * k, 4.0 * eta * eta * k * k))
        });
        Color::new(r, g, b)
    }
}

/// One channel, from `(η² − k², 4η²k²)`.
fn conductor_channel(cos_theta: f32, (eta2_minus_k2, four_eta2_k2): (f64, f64)) -> f32 {
    // f64 because A² − 2ac + c² cancels badly in f32 for k ≫ 1 at grazing angles.
    let c = cos_theta.clamp(0.0, 1.0) as f64;
    let s2 = 1.0 - c * c;
    let t0 = eta2_minus_k2 - s2;
    let a2 = (t0 * t0 + four_eta2_k2).sqrt();
    let a = (0.5 * (a2 + t0)).max(0.0).sqrt();
    let rs = ratio(a2 - 2.0 * a * c + c * c, a2 + 2.0 * a * c + c * c);
    let p_term = c * c * a2 + s2 * s2;
    let rp = rs * ratio(p_term - 2.0 * a * c * s2, p_term + 2.0 * a * c * s2);
    (0.5 * (rs + rp)).clamp(0.0, 1.0) as f32
}

/// `num/den` for the Fresnel ratios, whose numerator and denominator only
/// vanish together (an index of 0 at grazing incidence): total reflection then.
fn ratio(num: f64, den: f64) -> f64 {
    if den > 0.0 {
        num / den
    } else {
        1.0
    }
}
