//! Statistics shared by the BSDF and light tests: a pbrt-v4 style chi-square
//! goodness-of-fit test of a direction sampler against its pdf, and mean/σ.

use ember::sampling::Rng;
use glam::Vec3;
use std::f64::consts::PI;

pub const THETA_BINS: usize = 10;
pub const PHI_BINS: usize = 20;
/// Bins whose expected count is below this are pooled (chi² needs ~5 per cell).
const MIN_EXPECTED: f64 = 5.0;

/// Per-test significance after Šidák's correction for `num_tests` tests at an
/// overall significance of 0.01.
pub fn sidak_significance(num_tests: usize) -> f64 {
    1.0 - (1.0 - 0.01f64).powf(1.0 / num_tests as f64)
}

/// Mean and standard error of the mean.
pub fn mean_and_stderr(values: &[f64]) -> (f64, f64) {
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, (var / n).sqrt())
}

fn bin_of(w: Vec3) -> Option<usize> {
    let w = w.as_dvec3();
    if !w.is_finite() || (w.length() - 1.0).abs() > 1e-3 {
        return None;
    }
    let theta = w.z.clamp(-1.0, 1.0).acos();
    let mut phi = w.y.atan2(w.x);
    if phi < 0.0 {
        phi += 2.0 * PI;
    }
    let ti = ((theta / PI * THETA_BINS as f64) as usize).min(THETA_BINS - 1);
    let pi = ((phi / (2.0 * PI) * PHI_BINS as f64) as usize).min(PHI_BINS - 1);
    Some(ti * PHI_BINS + pi)
}

/// Observed counts per θ×φ bin, plus the number of samples that returned nothing.
/// A sample that is not a unit vector panics: it is a bug, not a statistic.
pub fn histogram(
    n: usize,
    seed: u64,
    mut sample: impl FnMut(&mut Rng) -> Option<Vec3>,
) -> (Vec<f64>, f64) {
    let mut sampler = Rng::from_seed(seed);
    let mut counts = vec![0.0; THETA_BINS * PHI_BINS];
    let mut lost = 0.0;
    for _ in 0..n {
        match sample(&mut sampler) {
            Some(w) => counts[bin_of(w).expect("sampled direction is not a unit vector")] += 1.0,
            None => lost += 1.0,
        }
    }
    (counts, lost)
}

const NUDGE: f64 = 1e-6;

/// `∫ pdf dω` over every bin, by adaptive Simpson quadrature in θ and φ.
pub fn integrate_bins(pdf: &dyn Fn(Vec3) -> f64) -> Vec<f64> {
    let dt = PI / THETA_BINS as f64;
    let dp = 2.0 * PI / PHI_BINS as f64;
    let mut out = Vec::with_capacity(THETA_BINS * PHI_BINS);
    for ti in 0..THETA_BINS {
        for pi in 0..PHI_BINS {
            let (t0, p0) = (ti as f64 * dt, pi as f64 * dp);
            let row = |theta: f64| {
                // Evaluate endpoints just inside the bin: at θ = 90° the f32 cosine
                // would otherwise take the other face's side of a discontinuity.
                let theta = theta.clamp(t0 + NUDGE, t0 + dt - NUDGE);
                let (st, ct) = theta.sin_cos();
                let f = |phi: f64| {
                    let (sp, cp) = phi.sin_cos();
                    pdf(Vec3::new((st * cp) as f32, (st * sp) as f32, ct as f32)) * st
                };
                simpson_segments(&f, p0, p0 + dp, 1e-7)
            };
            out.push(simpson_segments(&row, t0, t0 + dt, 1e-7));
        }
    }
    out
}

/// Adaptive Simpson over 16 initial segments, fine enough (about 1.1° per bin)
/// that a glossy lobe of α = 0.05 seen at grazing incidence is not stepped over.
fn simpson_segments(f: &dyn Fn(f64) -> f64, a: f64, b: f64, eps: f64) -> f64 {
    const SEGMENTS: usize = 16;
    let h = (b - a) / SEGMENTS as f64;
    (0..SEGMENTS)
        .map(|i| {
            let (x0, x1) = (a + i as f64 * h, a + (i + 1) as f64 * h);
            let (f0, fm, f1) = (f(x0), f(0.5 * (x0 + x1)), f(x1));
            let whole = (x1 - x0) / 6.0 * (f0 + 4.0 * fm + f1);
            adaptive_simpson(f, x0, x1, f0, fm, f1, whole, eps / SEGMENTS as f64, 8)
        })
        .sum()
}

#[allow(clippy::too_many_arguments)]
fn adaptive_simpson(
    f: &dyn Fn(f64) -> f64,
    a: f64,
    b: f64,
    fa: f64,
    fm: f64,
    fb: f64,
    whole: f64,
    eps: f64,
    depth: u32,
) -> f64 {
    let m = 0.5 * (a + b);
    let (flm, frm) = (f(0.5 * (a + m)), f(0.5 * (m + b)));
    let left = (m - a) / 6.0 * (fa + 4.0 * flm + fm);
    let right = (b - m) / 6.0 * (fm + 4.0 * frm + fb);
    let delta = left + right - whole;
    if depth == 0 || delta.abs() <= 15.0 * eps {
        return left + right + delta / 15.0;
    }
    adaptive_simpson(f, a, m, fa, flm, fm, left, 0.5 * eps, depth - 1)
        + adaptive_simpson(f, m, b, fm, frm, fb, right, 0.5 * eps, depth - 1)
}

/// Chi-square test of `n` draws of `sample` against `pdf` (pbrt-v4's scheme:
/// expected counts from the integrated pdf, low cells pooled). Samples that
/// return nothing form one more cell, expected `n·(1 − ∫pdf)`, so lost mass is
/// tested too. Returns the p-value, or an error for an impossible observation.
pub fn chi2_p_value(
    n: usize,
    seed: u64,
    sample: impl FnMut(&mut Rng) -> Option<Vec3>,
    pdf: &dyn Fn(Vec3) -> f64,
) -> Result<f64, String> {
    let (mut observed, lost) = histogram(n, seed, sample);
    let mut expected: Vec<f64> = integrate_bins(pdf).iter().map(|p| p * n as f64).collect();
    let total_expected: f64 = expected.iter().sum();
    if std::env::var("CHI2_DEBUG").is_ok() {
        print_worst_cells(&observed, &expected, lost, n as f64 - total_expected);
    }
    observed.push(lost);
    expected.push((n as f64 - total_expected).max(0.0));
    chi2_from_cells(&observed, &expected)
}

/// Diagnostics (set `CHI2_DEBUG`): the cells contributing most to chi².
fn print_worst_cells(observed: &[f64], expected: &[f64], lost: f64, lost_expected: f64) {
    let contribution = |i: usize| (observed[i] - expected[i]).powi(2) / expected[i].max(1e-9);
    let mut idx: Vec<usize> = (0..observed.len()).collect();
    idx.sort_by(|&a, &b| contribution(b).total_cmp(&contribution(a)));
    for &i in idx.iter().take(6) {
        let (t, p) = (i / PHI_BINS, i % PHI_BINS);
        eprintln!(
            "cell θ{t} φ{p}: observed {} expected {:.2}",
            observed[i], expected[i]
        );
    }
    eprintln!("lost {lost} expected {lost_expected:.2}");
}

fn chi2_from_cells(observed: &[f64], expected: &[f64]) -> Result<f64, String> {
    let mut cells: Vec<(f64, f64)> = observed
        .iter()
        .copied()
        .zip(expected.iter().copied())
        .collect();
    cells.sort_by(|a, b| a.1.total_cmp(&b.1));
    let (mut pooled_obs, mut pooled_exp) = (0.0, 0.0);
    let (mut chi2, mut dof) = (0.0, 0usize);
    let total_observed: f64 = observed.iter().sum();
    for &(obs, exp) in &cells {
        if exp <= 0.0 && obs > 1e-5 * total_observed {
            return Err(format!("{obs} samples fell where the pdf integrates to 0"));
        }
        if exp < MIN_EXPECTED {
            pooled_obs += obs;
            pooled_exp += exp;
        } else if pooled_exp > 0.0 && pooled_exp < MIN_EXPECTED {
            // Merge the pool into the next cell so no cell is too small.
            let (o, e) = (obs + pooled_obs, exp + pooled_exp);
            chi2 += (o - e).powi(2) / e;
            dof += 1;
            (pooled_obs, pooled_exp) = (0.0, 0.0);
        } else {
            chi2 += (obs - exp).powi(2) / exp;
            dof += 1;
        }
    }
    if pooled_exp >= MIN_EXPECTED {
        chi2 += (pooled_obs - pooled_exp).powi(2) / pooled_exp;
        dof += 1;
    }
    if dof < 2 {
        return Err(format!(
            "{dof} cell(s) left after pooling: too few for a chi-square test"
        ));
    }
    Ok(gamma_q(0.5 * (dof - 1) as f64, 0.5 * chi2))
}

/// Regularised upper incomplete gamma `Q(a, x)`: the chi-square survival function
/// with `2a` degrees of freedom at `2x` (series below `a + 1`, continued fraction above).
pub fn gamma_q(a: f64, x: f64) -> f64 {
    if x <= 0.0 {
        return 1.0;
    }
    let log_prefactor = -x + a * x.ln() - libm::lgamma(a);
    if x < a + 1.0 {
        let (mut term, mut sum, mut ap) = (1.0 / a, 1.0 / a, a);
        for _ in 0..10_000 {
            ap += 1.0;
            term *= x / ap;
            sum += term;
            if term.abs() < sum.abs() * 1e-15 {
                break;
            }
        }
        1.0 - sum * log_prefactor.exp()
    } else {
        // Lentz's method.
        let tiny = 1e-300;
        let mut b = x + 1.0 - a;
        let mut c = 1.0 / tiny;
        let mut d = 1.0 / b;
        let mut h = d;
        for i in 1..10_000 {
            let an = -(i as f64) * (i as f64 - a);
            b += 2.0;
            d = an * d + b;
            d = if d.abs() < tiny { tiny } else { d };
            c = b + an / c;
            c = if c.abs() < tiny { tiny } else { c };
            d = 1.0 / d;
            let delta = d * c;
            h *= delta;
            if (delta - 1.0).abs() < 1e-15 {
                break;
            }
        }
        log_prefactor.exp() * h
    }
}

#[test]
fn gamma_q_matches_chi_square_tables() {
    // χ² critical values: P(χ²₁ > 3.841) = 0.05, P(χ²₁₀ > 23.209) = 0.01, P(χ²₁₀₀ > 135.807) = 0.01.
    assert!((gamma_q(0.5, 3.841 / 2.0) - 0.05).abs() < 1e-4);
    assert!((gamma_q(5.0, 23.209 / 2.0) - 0.01).abs() < 1e-4);
    assert!((gamma_q(50.0, 135.807 / 2.0) - 0.01).abs() < 1e-4);
}
