//! Case 9: CBempty's point light, 1 cm below the ceiling. The ceiling spot above it
//! lights the room indirectly; camera paths find that spot only by chance (heavy-tailed
//! pixels), light paths start next to it. Measured as the issue states it: 16 renders
//! with independent seeds, a per-pixel, per-channel Welch t-test of their mean against
//! the light-traced Mitsuba reference and its noise, Šidák-corrected to 1 % family-wise.
//!
//! Needs ember's data folder (`crate::data`: the repository, or `$EMBER_DATA`);
//! without it the case reports that it was skipped.

use super::measure::{Budget, NATIVE};
use super::Row;
use crate::film::Image;
use crate::image_io::read_image;
use crate::integrators::{DirectStrategy, Estimator, Roulette};
use crate::render::{RenderJob, RenderSettings};
use crate::scene::collada;
use anyhow::{bail, Context, Result};
use std::path::Path;
use std::time::Instant;

/// Independent renders per estimator.
pub const RENDERS: usize = 16;
pub const MAX_DEPTH: u32 = 5;

/// One estimator's 16 renders against the reference.
#[derive(Clone, Debug)]
pub struct PixelTestRun {
    pub name: &'static str,
    /// Fraction of pixels whose three channels all pass.
    pub pass_rate: f64,
    /// Image mean luminance (average of the renders) and its standard error over renders.
    pub mean: f64,
    pub se: f64,
    pub reference_mean: f64,
    /// Failing pixels above / below the reference.
    pub fail_high: usize,
    pub fail_low: usize,
    /// The failing pixels' indices, row-major.
    pub failing: Vec<usize>,
    pub seconds: f64,
    pub nonfinite: u64,
}

pub struct CbemptyCase {
    pub runs: Vec<PixelTestRun>,
}

impl CbemptyCase {
    pub fn run(&self, name: &str) -> &PixelTestRun {
        self.runs.iter().find(|r| r.name == name).expect("run")
    }

    pub fn rows(&self) -> Vec<Row> {
        self.runs
            .iter()
            .map(|r| Row {
                case: "9 CBempty point light (m 5)".into(),
                method: r.name.into(),
                mean: r.mean,
                stderr: r.se,
                expected: Some(r.reference_mean),
                noise: 0.0,
                nonfinite: r.nonfinite,
                note: format!(
                    "per-pixel Welch t vs Mitsuba (16 renders, Šidák 1%): {:.2}% of pixels pass ({} fail high, {} low); {:.1} s",
                    100.0 * r.pass_rate,
                    r.fail_high,
                    r.fail_low,
                    r.seconds
                ),
            })
            .collect()
    }
}

/// The estimators compared: the path tracer's default for the scene, and light tracing.
pub const ESTIMATORS: [(&str, Estimator, DirectStrategy); 2] = [
    ("path tracing (MIS)", Estimator::Path, DirectStrategy::Mis),
    (
        "light tracing",
        Estimator::LightTracing,
        DirectStrategy::Light,
    ),
];

/// Case 9 at `b.spp` per render (the figure is 32), at the reference's 160×120.
/// `data` is ember's data folder (`crate::data::root`).
pub fn cbempty(b: &Budget, data: &Path) -> Result<CbemptyCase> {
    let scene_path = data.join("scenes/cs184/sky/CBempty.dae");
    let scene = collada::load(&scene_path)?;
    let (reference, noise) = reference(&data.join("tests/data/references"), "CBempty_m5.exr")?;
    let (w, h) = (reference.width, reference.height);
    let job = RenderJob::new(scene, NATIVE, w, h)?;
    let mut runs = Vec::new();
    for (name, estimator, strategy) in ESTIMATORS {
        let t0 = Instant::now();
        let mut nonfinite = 0;
        let renders: Vec<Image> = (0..RENDERS as u64)
            .map(|k| {
                let s = RenderSettings {
                    spp: b.spp,
                    max_depth: MAX_DEPTH,
                    estimator: Some(estimator),
                    strategy: Some(strategy),
                    roulette: Roulette::default(),
                    seed: b.seed.wrapping_mul(1000).wrapping_add(k),
                    ..Default::default()
                };
                let out = job.render(&s);
                nonfinite += out.nonfinite_samples;
                out.image
            })
            .collect();
        let seconds = t0.elapsed().as_secs_f64();
        let t = welch_pixel_test(&renders, &reference, noise);
        let means: Vec<f64> = renders.iter().map(|i| i.mean_luminance() as f64).collect();
        let (mean, se) = mean_and_se(&means);
        runs.push(PixelTestRun {
            name,
            pass_rate: t.pass_rate,
            mean,
            se,
            reference_mean: reference.mean_luminance() as f64,
            fail_high: t.fail_high,
            fail_low: t.fail_low,
            failing: t.failing,
            seconds,
            nonfinite,
        });
    }
    Ok(CbemptyCase { runs })
}

/// Case 9's rows, or one row saying why it was skipped (no data folder).
pub fn rows_if_data(b: &Budget) -> Result<Vec<Row>> {
    let data = match crate::data::root() {
        Ok(d) => d,
        Err(e) => {
            return Ok(vec![Row {
                case: "9 CBempty point light (m 5)".into(),
                method: "skipped".into(),
                mean: 0.0,
                stderr: 0.0,
                expected: None,
                noise: 0.0,
                nonfinite: 0,
                note: format!("{e:#}"),
            }])
        }
    };
    Ok(cbempty(b, &data)?.rows())
}

/// A reference EXR of the folder `refs` and its per-channel per-pixel noise from
/// the folder's manifest.
pub fn reference(refs: &Path, file: &str) -> Result<(Image, [f64; 3])> {
    let image = read_image(&refs.join(file))?;
    Ok((image, manifest_noise_rgb(refs, file)?))
}

/// The per-pixel RMS noise of the reference EXR `path` (the mean over its channels)
/// from the `manifest.json` beside it; `None` when there is no manifest there.
pub fn manifest_noise(path: &Path) -> Result<Option<f64>> {
    let refs = path.parent().unwrap_or(Path::new("."));
    if !refs.join("manifest.json").is_file() {
        return Ok(None);
    }
    let file = path.file_name().and_then(|f| f.to_str()).unwrap_or("");
    let noise = manifest_noise_rgb(refs, file)?;
    Ok(Some(noise.iter().sum::<f64>() / 3.0))
}

fn manifest_noise_rgb(refs: &Path, file: &str) -> Result<[f64; 3]> {
    let manifest = refs.join("manifest.json");
    let text = std::fs::read_to_string(&manifest)
        .with_context(|| format!("{}: cannot read", manifest.display()))?;
    let key = "\"noise_rmse_per_pixel_rgb\"";
    // The manifest is one object per image; find this image's entry, then its noise array.
    let Some(at) = text.find(&format!("\"{file}\"")) else {
        bail!("{}: no entry for {file}", manifest.display())
    };
    let rest = &text[at..];
    let Some(k) = rest.find(key) else {
        bail!("{}: {file} has no {key}", manifest.display())
    };
    let arr = &rest[k + key.len()..];
    let (open, close) = (arr.find('[').unwrap_or(0), arr.find(']').unwrap_or(0));
    let v: Vec<f64> = arr[open + 1..close]
        .split(',')
        .filter_map(|s| s.trim().parse().ok())
        .collect();
    if v.len() != 3 {
        bail!("{}: {file}: malformed {key}", manifest.display());
    }
    Ok([v[0], v[1], v[2]])
}

fn mean_and_se(v: &[f64]) -> (f64, f64) {
    let n = v.len() as f64;
    let m = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0).max(1.0);
    (m, (var / n).sqrt())
}

/// Outcome of `welch_pixel_test`.
#[derive(Clone, Debug)]
pub struct PixelTest {
    pub pass_rate: f64,
    pub fail_high: usize,
    pub fail_low: usize,
    /// The failing pixels' indices, row-major.
    pub failing: Vec<usize>,
}

/// For every pixel and channel: Welch's t of the mean of `renders` (variance from their
/// spread, `n − 1` degrees of freedom) against `reference` (variance `ref_noise²`,
/// taken as exactly known), two-sided p-value from Student's t with the
/// Welch–Satterthwaite degrees of freedom, at Šidák's per-test level for 1 %
/// family-wise over all tests. A pixel passes when its three channels do.
pub fn welch_pixel_test(renders: &[Image], reference: &Image, ref_noise: [f64; 3]) -> PixelTest {
    let n = renders.len() as f64;
    let npix = reference.pixels.len();
    let alpha = 1.0 - 0.99f64.powf(1.0 / (3 * npix) as f64);
    let (mut pass, mut high, mut low) = (0, 0, 0);
    let mut failing = Vec::new();
    for i in 0..npix {
        let mut ok = true;
        let mut above = false;
        for (c, noise) in ref_noise.iter().enumerate() {
            let xs: Vec<f64> = renders.iter().map(|r| r.pixels[i][c] as f64).collect();
            let m = xs.iter().sum::<f64>() / n;
            let s2 = xs.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0);
            let a = s2 / n;
            let b = noise * noise;
            let d = m - reference.pixels[i][c] as f64;
            let var = a + b;
            let p = if var > 0.0 {
                let t = d / var.sqrt();
                // ν = (a + b)² / (a²/(n−1) + b²/∞)
                let nu = if a > 0.0 {
                    var * var / (a * a / (n - 1.0))
                } else {
                    1e6
                };
                student_t_two_sided(t, nu.min(1e6))
            } else if d == 0.0 {
                1.0
            } else {
                0.0
            };
            if p < alpha {
                ok = false;
                above = d > 0.0;
            }
        }
        if ok {
            pass += 1;
            continue;
        }
        failing.push(i);
        if above {
            high += 1;
        } else {
            low += 1;
        }
    }
    PixelTest {
        pass_rate: pass as f64 / npix.max(1) as f64,
        fail_high: high,
        fail_low: low,
        failing,
    }
}

/// `P(|T| ≥ |t|)` for Student's t with `nu` degrees of freedom: `I_{ν/(ν+t²)}(ν/2, ½)`.
pub fn student_t_two_sided(t: f64, nu: f64) -> f64 {
    if !t.is_finite() {
        return 0.0;
    }
    incomplete_beta(0.5 * nu, 0.5, nu / (nu + t * t))
}

/// Regularized incomplete beta `I_x(a, b)` (Numerical Recipes' continued fraction).
pub fn incomplete_beta(a: f64, b: f64, x: f64) -> f64 {
    if x <= 0.0 {
        return 0.0;
    }
    if x >= 1.0 {
        return 1.0;
    }
    let ln_front = ln_gamma(a + b) - ln_gamma(a) - ln_gamma(b) + a * x.ln() + b * (1.0 - x).ln();
    let front = ln_front.exp();
    if x < (a + 1.0) / (a + b + 2.0) {
        front * beta_cf(a, b, x) / a
    } else {
        1.0 - front * beta_cf(b, a, 1.0 - x) / b
    }
}

fn beta_cf(a: f64, b: f64, x: f64) -> f64 {
    const TINY: f64 = 1e-300;
    let (qab, qap, qam) = (a + b, a + 1.0, a - 1.0);
    let mut c = 1.0;
    let mut d = 1.0 - qab * x / qap;
    if d.abs() < TINY {
        d = TINY;
    }
    d = 1.0 / d;
    let mut h = d;
    for m in 1..300 {
        let m = m as f64;
        let m2 = 2.0 * m;
        for aa in [
            m * (b - m) * x / ((qam + m2) * (a + m2)),
            -(a + m) * (qab + m) * x / ((a + m2) * (qap + m2)),
        ] {
            d = 1.0 + aa * d;
            if d.abs() < TINY {
                d = TINY;
            }
            c = 1.0 + aa / c;
            if c.abs() < TINY {
                c = TINY;
            }
            d = 1.0 / d;
            h *= d * c;
        }
        if (d * c - 1.0).abs() < 1e-14 {
            break;
        }
    }
    h
}

/// Lanczos approximation (g = 7, n = 9) of `ln Γ(x)` for `x > 0`.
fn ln_gamma(x: f64) -> f64 {
    const C: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x < 0.5 {
        let pi = std::f64::consts::PI;
        return (pi / (pi * x).sin()).ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let mut s = C[0];
    for (i, c) in C.iter().enumerate().skip(1) {
        s += c / (x + i as f64);
    }
    let t = x + 7.5;
    0.5 * (2.0 * std::f64::consts::PI).ln() + (x + 0.5) * t.ln() - t + s.ln()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn student_t_matches_tables() {
        // t_{0.975, 10} = 2.228, t_{0.995, 15} = 2.947; ν → ∞: normal 1.96.
        assert!((student_t_two_sided(2.228, 10.0) - 0.05).abs() < 2e-4);
        assert!((student_t_two_sided(2.947, 15.0) - 0.01).abs() < 1e-4);
        assert!((student_t_two_sided(1.959964, 1e6) - 0.05).abs() < 1e-4);
        assert!((student_t_two_sided(0.0, 5.0) - 1.0).abs() < 1e-12);
    }

    /// The shipped references' noise is read from their manifest (CBbunny_m5's
    /// channels are about 0.00199 each); a reference without a manifest beside it has none.
    #[test]
    fn manifest_noise_of_a_reference() {
        let refs = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/references");
        let noise = manifest_noise(&refs.join("CBbunny_m5.exr"))
            .unwrap()
            .unwrap();
        assert!((noise - 0.00199).abs() < 5e-6, "{noise}");
        let elsewhere = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell.dae");
        assert_eq!(manifest_noise(&elsewhere).unwrap(), None);
        assert!(manifest_noise(&refs.join("no_such.exr")).is_err());
    }
}
