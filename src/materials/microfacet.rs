//! Rough conductor of spec §6: Beckmann NDF, separable Smith shadowing-masking
//! with the Beckmann Λ, exact conductor Fresnel, all in lanes. Sampled by the
//! distribution of normals `D(h)·cos θh`, reflected about `h`. Two-sided: on the
//! back face the frame is mirrored (z of both directions flipped).

use super::fresnel::conductor_l;
use super::{gather_f, BsdfFlags, BsdfSample, Scatter};
use crate::lanes::math::{exp, ln, sin_cos_turns};
use crate::lanes::{Lanes, Real, V3};
use crate::Color;
use std::f32::consts::PI;

/// Below this roughness the Beckmann lobe is narrower than f32 can resolve
/// (α² underflows D's exponent), so α is clamped: a near-mirror remains a valid,
/// finite glossy lobe rather than turning into a delta.
pub const MIN_ALPHA: f32 = 1e-3;

/// Conductors at most this rough focus light into caustics (`Scatter::focuses`): on
/// CS184's microfacet spheres under their area light, light-tracing those caustics
/// (`Estimator::Caustics`) took 0.48x path tracing's noise² × time at α 0.025 and
/// 0.25, 1.05x at 0.35 and 2.6x at 0.6 (BENCHMARKS §3).
pub const FOCUS_ALPHA: f32 = 0.3;

/// A rough conductor's parameters: α (clamped when made) and the complex index
/// `eta + i·k` per channel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Conductor<F: Real = f32> {
    /// Beckmann roughness, at least [`MIN_ALPHA`] (a non-finite α is taken as 1).
    pub alpha: F,
    pub eta: V3<F>,
    pub k: V3<F>,
}

impl Conductor {
    pub fn new(alpha: f32, eta: Color, k: Color) -> Self {
        let alpha = if alpha.is_finite() { alpha } else { 1.0 };
        Conductor {
            alpha: alpha.max(MIN_ALPHA),
            eta: eta.into(),
            k: k.into(),
        }
    }

    /// The real part of the complex index, per channel.
    pub fn eta(&self) -> Color {
        self.eta.into()
    }

    /// The imaginary part (absorption) of the complex index, per channel.
    pub fn k(&self) -> Color {
        self.k.into()
    }
}

impl<F: Real> Scatter<F> for Conductor<F> {
    type One = Conductor;
    const FLAGS: BsdfFlags = BsdfFlags::GLOSSY;

    #[inline(always)]
    fn gather<L: Lanes<F = F>>(l: L, each: &F::Array<Conductor>) -> Self {
        let v3 = |f: fn(&Conductor) -> V3<f32>| {
            V3::new(
                gather_f(l, each, |m| f(m).x),
                gather_f(l, each, |m| f(m).y),
                gather_f(l, each, |m| f(m).z),
            )
        };
        Conductor {
            alpha: gather_f(l, each, |m| m.alpha),
            eta: v3(|m| m.eta),
            k: v3(|m| m.k),
        }
    }

    fn focuses(c: &Conductor) -> bool {
        c.alpha <= FOCUS_ALPHA
    }

    fn describe(c: &Conductor) -> String {
        let v = crate::color::compact;
        format!(
            "microfacet: alpha {}, eta {}, k {}",
            c.alpha,
            v(c.eta()),
            v(c.k())
        )
    }

    #[inline(always)]
    fn eval(&self, wo: V3<F>, wi: V3<F>) -> V3<F> {
        let (wo, wi, h, ok) = upper_pair(wo, wi);
        let d = beckmann_d(h, self.alpha);
        let g = self.g1(wo, h) * self.g1(wi, h);
        let f = self.fresnel(wi.dot(h).abs());
        let value = f * (d * g / (wo.x.splat_as(4.0) * wi.z * wo.z));
        let zero = wo.x.splat_as(0.0);
        V3::select(ok & value.is_finite(), value, V3::new(zero, zero, zero))
    }

    #[inline(always)]
    fn pdf(&self, wo: V3<F>, wi: V3<F>) -> F {
        let (wo, _, h, ok) = upper_pair(wo, wi);
        let pdf = reflected_pdf(beckmann_normal_pdf(h, self.alpha), wo.dot(h));
        F::select(ok, pdf, wo.x.splat_as(0.0))
    }

    #[inline(always)]
    fn sample(&self, wo: V3<F>, _u_lobe: F, u: (F, F)) -> BsdfSample<F> {
        let flip = wo.z.lt(wo.z.splat_as(0.0));
        let wo_up = mirror_z(wo, flip);
        let h = beckmann_normal(u, self.alpha);
        let wo_dot_h = wo_up.dot(h);
        let wi_up = (h * (wo.z.splat_as(2.0) * wo_dot_h) - wo_up).normalize();
        // Reflected below the surface: that mass is lost (pdf() is 0 there).
        let wi = mirror_z(wi_up, flip);
        let pdf = self.pdf(wo, wi);
        let weight = self.eval(wo, wi) * (wi.z.abs() / pdf);
        BsdfSample {
            wi,
            weight,
            pdf,
            valid: !wo.z.eq(wo.z.splat_as(0.0))
                & wo_dot_h.gt(wo.z.splat_as(0.0))
                & wi_up.z.gt(wo.z.splat_as(0.0))
                & pdf.gt(wo.z.splat_as(0.0))
                & pdf.is_finite()
                & weight.is_finite(),
        }
    }
}

impl<F: Real> Conductor<F> {
    /// Smith masking of one direction; 0 when `w` sees the back of the microfacet.
    #[inline(always)]
    fn g1(&self, w: V3<F>, h: V3<F>) -> F {
        let lambda = beckmann_lambda_l(w.z, self.alpha);
        let g = w.z.splat_as(1.0) / (w.z.splat_as(1.0) + lambda);
        F::select((w.dot(h) * w.z).le(w.z.splat_as(0.0)), w.z.splat_as(0.0), g)
    }

    /// Each lane's conductor reflectance at `|cos θ|`.
    #[inline(always)]
    fn fresnel(&self, cos_theta: F) -> V3<F> {
        conductor_l(cos_theta, self.eta, self.k)
    }
}

/// [`beckmann_lambda`] per lane in f32. `erfc(a)` is Abramowitz and Stegun's 7.1.26,
/// `exp(−a²)·t·P(t)` with `t = 1/(1 + p·a)`, whose absolute error is below 1.5e-7;
/// Λ inherits half of it, and G₁ = 1/(1 + Λ) needs no more, so the difference of
/// two nearly equal terms at large `a` costs nothing that G₁ could show.
#[inline(always)]
pub fn beckmann_lambda_l<F: Real>(cos_theta: F, alpha: F) -> F {
    let c = |x: f32| cos_theta.splat_as(x);
    let cos = cos_theta.abs();
    let sin = (c(1.0) - cos * cos).max(c(0.0)).sqrt();
    // sin = 0: a = ∞ and Λ = 0; cos = 0: a = 0 and Λ = ∞, as the f64 form gives.
    let a = cos / (alpha * sin);
    let t = c(1.0) / (c(1.0) + c(0.327_591_1) * a);
    let p = t
        * (c(0.254_829_6)
            + t * (c(-0.284_496_74)
                + t * (c(1.421_413_7) + t * (c(-1.453_152) + t * c(1.061_405_4)))));
    let e = exp(-(a * a));
    let lambda = c(0.5) * e * (c(0.5 * std::f32::consts::FRAC_2_SQRT_PI) / a - p);
    F::select(sin.eq(c(0.0)), c(0.0), lambda.max(c(0.0)))
}

/// `Λ(w) = (erf(a) − 1)/2 + exp(−a²)/(2a√π)`, `a = 1/(α·tan θ)`. Written with
/// `erfc(a) = 1 − erf(a)`, the same function without the cancellation for large a.
pub fn beckmann_lambda(cos_theta: f32, alpha: f32) -> f32 {
    let cos = cos_theta.abs() as f64;
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

/// Beckmann distribution of microfacet normals,
/// `D(h) = exp(−tan²θh/α²) / (π·α²·cos⁴θh)`, 0 below the surface.
#[inline(always)]
pub fn beckmann_d<F: Real>(h: V3<F>, alpha: F) -> F {
    let cos2 = h.z * h.z;
    let tan2 = (alpha.splat_as(1.0) - cos2).max(alpha.splat_as(0.0)) / cos2;
    let alpha2 = alpha * alpha;
    let d = exp(-tan2 / alpha2) / (alpha.splat_as(PI) * alpha2 * cos2 * cos2);
    let ok = h.z.gt(alpha.splat_as(0.0)) & cos2.gt(alpha.splat_as(0.0)) & d.is_finite();
    F::select(ok, d, alpha.splat_as(0.0))
}

/// Microfacet normal drawn with density `D(h)·cos θh` (projected-area normalised,
/// so it integrates to 1): `tan²θ = −α²·ln(1−u)`.
#[inline(always)]
pub fn beckmann_normal<F: Real>(u: (F, F), alpha: F) -> V3<F> {
    let tan2 = -(alpha * alpha) * ln(alpha.splat_as(1.0) - u.0);
    let cos_theta = alpha.splat_as(1.0) / (alpha.splat_as(1.0) + tan2).sqrt();
    let sin_theta = (alpha.splat_as(1.0) - cos_theta * cos_theta)
        .max(alpha.splat_as(0.0))
        .sqrt();
    let (sin_phi, cos_phi) = sin_cos_turns(u.1);
    V3::new(sin_theta * cos_phi, sin_theta * sin_phi, cos_theta)
}

#[inline(always)]
pub fn beckmann_normal_pdf<F: Real>(h: V3<F>, alpha: F) -> F {
    beckmann_d(h, alpha) * h.z.max(alpha.splat_as(0.0))
}

/// Both directions moved to the upper hemisphere (mirroring the frame on the back
/// face) with their half vector; the lanes where they are strictly on one side and
/// the half vector exists.
#[inline(always)]
fn upper_pair<F: Real>(wo: V3<F>, wi: V3<F>) -> (V3<F>, V3<F>, V3<F>, F::M) {
    let zero = wo.z.splat_as(0.0);
    let one_side = (wo.z * wi.z).gt(zero);
    let flip = wo.z.lt(zero);
    let (wo, wi) = (mirror_z(wo, flip), mirror_z(wi, flip));
    let sum = wo + wi;
    // glam's `try_normalize`: 1/|sum| finite and positive.
    let rcp = zero.splat_as(1.0) / sum.length();
    let h = sum * rcp;
    (wo, wi, h, one_side & rcp.is_finite() & rcp.gt(zero))
}

/// Density of the reflected direction given the half-vector density:
/// the Jacobian of `wi = reflect(wo, h)` is `1/(4·|wo·h|)`.
#[inline(always)]
fn reflected_pdf<F: Real>(pdf_h: F, wo_dot_h: F) -> F {
    let zero = wo_dot_h.splat_as(0.0);
    let pdf = pdf_h / (wo_dot_h.splat_as(4.0) * wo_dot_h);
    F::select(wo_dot_h.gt(zero) & pdf.is_finite(), pdf, zero)
}

#[inline(always)]
fn mirror_z<F: Real>(w: V3<F>, flip: F::M) -> V3<F> {
    V3::new(w.x, w.y, F::select(flip, -w.z, w.z))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Smooth metal focuses light as mirrors and glass do; rough metal and diffuse
    /// surfaces do not, and the lanes' bits say the same per lane.
    #[test]
    fn smooth_metal_focuses_light() {
        use crate::lanes::{LaneBits, One};
        use crate::materials::{BsdfLanes, Material};
        let metal = |alpha| Material::microfacet(alpha, Color::splat(0.2), Color::splat(3.0));
        let materials = [
            (metal(0.025), true),
            (metal(FOCUS_ALPHA), true),
            (metal(FOCUS_ALPHA * 1.01), false),
            (metal(0.6), false),
            (Material::mirror(Color::ONE), true),
            (Material::glass(1.5, Color::ONE, Color::ONE), true),
            (Material::lambertian(Color::splat(0.5)), false),
        ];
        for (m, focuses) in materials {
            assert_eq!(m.focuses(), focuses, "{m:?}");
            let lanes: BsdfLanes<One> = BsdfLanes::gather(One, 1, |_| m.bsdf);
            assert_eq!(lanes.focus, focuses as LaneBits, "{m:?}");
        }
    }

    /// G₁ from the f32 lanes Λ agrees with G₁ from the f64 Λ to 1e-6, at every
    /// roughness and angle down to grazing.
    #[test]
    fn lanes_lambda_matches_the_f64_form() {
        for alpha in [MIN_ALPHA, 0.01, 0.05, 0.1, 0.3, 0.5, 1.0, 2.0] {
            for i in 0..=4000 {
                let cos = (i as f32 / 4000.0).powi(2);
                let want = 1.0 / (1.0 + beckmann_lambda(cos, alpha));
                let got = 1.0 / (1.0 + beckmann_lambda_l(cos, alpha));
                assert!(
                    (got - want).abs() < 1e-6,
                    "alpha {alpha} cos {cos}: G1 {got} vs {want}"
                );
            }
        }
    }
}
