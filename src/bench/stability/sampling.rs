//! Cases 7 and 8: sample-count policies that can bias an image. Adaptive sampling
//! must not stop a pixel on zero variance seen in too few samples; Russian roulette
//! with a tiny continuation probability must stay unbiased, only noisier.

use super::lights::scale_area_lights;
use super::measure::{lum, Budget, Halves};
use super::scenes::embedded;
use super::Row;
use crate::integrators::{DirectStrategy, Roulette};
use crate::render::{Adaptive, RenderOutput, RenderSettings, StopRule};
use anyhow::Result;

/// Adaptive batch size and tolerance of case 7.
pub const BATCH: u32 = 8;
const TOL: f32 = 0.05;
/// The fixed-spp reference of case 7 takes this many times the adaptive cap.
pub const REFERENCE_FACTOR: u32 = 8;

pub struct AdaptiveRun {
    pub name: &'static str,
    /// The `-s` cap of this run.
    pub cap: u32,
    pub min_samples_if_constant: u32,
    /// Mean over the lit pixels.
    pub mean: f64,
    /// Standard error of `mean` if the pixels were unbiased: the reference's per-pixel
    /// variance scaled to each pixel's sample count.
    pub se: f64,
    /// `E[adaptive − fixed]` over the lit pixels, against the fixed-count render of the
    /// same seed at `cap` (unbiased, and equal wherever the pixel ran to the cap), with
    /// its standard error `√Σ σᵢ²(1/nᵢ − 1/cap) / N` (σᵢ² from the reference).
    pub paired_bias: f64,
    pub paired_se: f64,
    /// Samples per lit pixel, and per pixel of the whole image.
    pub mean_samples: f64,
    pub image_samples: f64,
    /// Pixels (with a lit reference) that stopped after one batch at exactly 0.
    pub stopped_at_zero_after_one_batch: usize,
    /// Lit pixels that stopped with all samples zero, before the cap.
    pub stopped_at_zero: usize,
    pub output: RenderOutput,
}

impl AdaptiveRun {
    /// `paired_bias` relative to the lit pixels' mean, with its standard error.
    pub fn relative_bias(&self, reference_mean: f64) -> (f64, f64) {
        (
            self.paired_bias / reference_mean,
            self.paired_se / reference_mean,
        )
    }
}

pub struct AdaptiveCase {
    /// Non-adaptive reference mean and standard error over the lit pixels.
    pub reference: (f64, f64),
    pub lit_pixels: Vec<usize>,
    pub guarded: AdaptiveRun,
    pub unguarded: AdaptiveRun,
    /// The default rule (`crate::adaptive`) at the same cap as the others.
    pub default_rule: AdaptiveRun,
    /// The default rule at the largest cap (a multiple of the batch) whose every pixel
    /// costs no more than the guard's mean spend per lit pixel.
    pub default_at_guard_spend: AdaptiveRun,
    /// An ordinary scene (cornell.dae, `-m 5`, the default estimator, the same size and
    /// cap): samples per pixel of the default rule and of the guard.
    pub cornell_samples: (f64, f64),
}

/// A floor under a 0.4 × 0.4 light seen by BSDF sampling alone: a single sample finds
/// the light with probability p ≤ Ω·cosθ/π ≈ 0.05, so a batch of 8 is all zero with
/// probability ≥ 0.95⁸ ≈ 0.66 although every floor pixel's mean is > 0. No lit pixel
/// can meet the tolerance below the cap: a sample is 0 or one value, so `σ²/μ² =
/// (1 − p)/p ≥ 19` and the rule needs `(1.96/TOL)²·19 ≈ 29 000` samples.
pub fn adaptive(b: &Budget) -> Result<AdaptiveCase> {
    let scene = scale_area_lights(embedded("small_light.dae")?, 4.0);
    let setup = b.job(scene)?;
    let base = RenderSettings {
        max_depth: 1,
        strategy: Some(DirectStrategy::Bsdf),
        roulette: Roulette::Off,
        ..Default::default()
    };
    // 8× the adaptive cap, so that a bias of 1% is measurable.
    let ref_spp = REFERENCE_FACTOR * b.spp;
    let reference: Halves = setup.halves(&RenderSettings {
        spp: ref_spp,
        ..b.settings(base.clone())
    });
    let avg = reference.average();
    let lit_pixels: Vec<usize> = (0..avg.pixels.len())
        .filter(|&i| lum(&avg, i) > 0.0)
        .collect();
    // Per-sample variance of each lit pixel: a half of `ref_spp / 2` samples has variance σ²/(ref_spp/2).
    let var: Vec<f64> = lit_pixels
        .iter()
        .map(|&i| {
            let d = lum(&reference.a.image, i) - lum(&reference.b.image, i);
            0.25 * d * d * ref_spp as f64
        })
        .collect();
    let n = lit_pixels.len().max(1) as f64;
    let over_lit = |f: &dyn Fn(usize, usize) -> f64| -> f64 {
        lit_pixels.iter().enumerate().map(|(k, &i)| f(k, i)).sum()
    };
    let run = |name: &'static str, cap: u32, guard: u32, rule: StopRule| {
        let adaptive = Adaptive {
            min_samples_if_constant: guard,
            rule,
            ..Adaptive::new(BATCH, TOL)
        };
        let settings = RenderSettings {
            spp: cap,
            ..b.settings(base.clone())
        };
        let fixed = setup.render(&settings);
        let output = setup.render(&RenderSettings {
            adaptive: Some(adaptive),
            ..settings
        });
        let samples = |i: usize| output.samples[i].max(1) as f64;
        let paired_var = over_lit(&|k, i| var[k] * (1.0 / samples(i) - 1.0 / cap as f64));
        AdaptiveRun {
            name,
            cap,
            min_samples_if_constant: guard,
            mean: over_lit(&|_, i| lum(&output.image, i)) / n,
            se: over_lit(&|k, i| var[k] / samples(i)).sqrt() / n,
            paired_bias: over_lit(&|_, i| lum(&output.image, i) - lum(&fixed.image, i)) / n,
            paired_se: paired_var.max(0.0).sqrt() / n,
            mean_samples: over_lit(&|_, i| samples(i)) / n,
            image_samples: output.samples.iter().map(|&s| s as f64).sum::<f64>()
                / output.samples.len() as f64,
            stopped_at_zero_after_one_batch: lit_pixels
                .iter()
                .filter(|&&i| output.samples[i] == BATCH && lum(&output.image, i) == 0.0)
                .count(),
            stopped_at_zero: lit_pixels
                .iter()
                .filter(|&&i| output.samples[i] < cap && lum(&output.image, i) == 0.0)
                .count(),
            output,
        }
    };
    let guarded = run(
        "adaptive, guard 4·batch",
        b.spp,
        4 * BATCH,
        StopRule::PerPixel,
    );
    let cap_at_guard_spend = (guarded.mean_samples as u32 / BATCH * BATCH).max(BATCH);
    let cornell = b.job(embedded("cornell.dae")?)?;
    let cornell_samples = |rule: StopRule| {
        let output = cornell.render(&b.settings(RenderSettings {
            max_depth: 5,
            adaptive: Some(Adaptive {
                rule,
                ..Adaptive::new(BATCH, TOL)
            }),
            ..Default::default()
        }));
        output.samples.iter().map(|&s| s as f64).sum::<f64>() / output.samples.len() as f64
    };
    Ok(AdaptiveCase {
        reference: reference.mean_and_se(Some(&lit_pixels)),
        unguarded: run("adaptive, no guard", b.spp, 0, StopRule::PerPixel),
        default_rule: run(
            "adaptive, neighbour-rate rule (default)",
            b.spp,
            4 * BATCH,
            StopRule::Neighbourhood,
        ),
        default_at_guard_spend: run(
            "adaptive, default rule at the guard's spend",
            cap_at_guard_spend,
            4 * BATCH,
            StopRule::Neighbourhood,
        ),
        guarded,
        lit_pixels,
        cornell_samples: (
            cornell_samples(StopRule::Neighbourhood),
            cornell_samples(StopRule::PerPixel),
        ),
    })
}

impl AdaptiveCase {
    pub fn rows(&self) -> Vec<Row> {
        let case = "7 adaptive, zero first batch";
        let (rm, rse) = self.reference;
        let mut rows = vec![Row {
            case: case.into(),
            method: "fixed spp (reference)".into(),
            mean: rm,
            stderr: rse,
            expected: None,
            noise: 0.0,
            nonfinite: 0,
            note: format!("{} lit pixels", self.lit_pixels.len()),
        }];
        for r in [
            &self.default_rule,
            &self.default_at_guard_spend,
            &self.guarded,
            &self.unguarded,
        ] {
            let (bias, se) = r.relative_bias(rm);
            rows.push(Row {
                case: case.into(),
                method: format!("{} (-s {})", r.name, r.cap),
                mean: r.mean,
                stderr: r.se,
                expected: Some(rm),
                noise: 0.0,
                nonfinite: r.output.nonfinite_samples,
                note: format!(
                    "bias {:+.2}% ± {:.2}% against the fixed -s {} render of the same seed ({:+.2}% ± {:.2}% against the reference); {} lit pixels stopped at 0; {:.1} samples per lit pixel, {:.1} per pixel",
                    100.0 * bias,
                    100.0 * se,
                    r.cap,
                    100.0 * (r.mean / rm - 1.0),
                    100.0 * (rse.powi(2) + r.se.powi(2)).sqrt() / rm,
                    r.stopped_at_zero,
                    r.mean_samples,
                    r.image_samples,
                ),
            });
        }
        let (default, guard) = self.cornell_samples;
        rows.push(Row {
            case: case.into(),
            method: "cornell.dae, default rule vs guard".into(),
            mean: default,
            stderr: 0.0,
            expected: None,
            noise: 0.0,
            nonfinite: 0,
            note: format!(
                "samples per pixel at the same -s: default rule {default:.1}, guard {guard:.1} (-m 5, default estimator)"
            ),
        });
        rows
    }
}

pub const ROULETTES: [(&str, Roulette); 4] = [
    ("no roulette", Roulette::Off),
    (
        "throughput (default)",
        Roulette::Throughput {
            start: 3,
            min_prob: 0.05,
        },
    ),
    (
        "fixed q = 0.2 from bounce 1",
        Roulette::Fixed {
            start: 1,
            prob: 0.2,
        },
    ),
    // q = 0.05 once, at the last bounce: from bounce 1 it compounds, and a path that
    // reaches the fifth vertex carries weight 20⁴ = 1.6e5. No test budget samples that
    // tail: 24 seeds of 64 spp at 40x30 gave means from 0.052 to 0.084 (true 0.061),
    // and a one-render standard error (from its pixels) put unbiased runs 5 σ low.
    (
        "fixed q = 0.05 at bounce 4",
        Roulette::Fixed {
            start: ROULETTE_DEPTH - 1,
            prob: 0.05,
        },
    ),
];

#[derive(Clone, Debug)]
pub struct RouletteRun {
    pub name: &'static str,
    pub mean: f64,
    pub se: f64,
    pub noise: f64,
    pub nonfinite: u64,
}

pub struct RouletteCase {
    pub runs: Vec<RouletteRun>,
}

pub const ROULETTE_DEPTH: u32 = 5;

pub fn roulette(b: &Budget) -> Result<RouletteCase> {
    let setup = b.job(embedded("cornell.dae")?)?;
    let runs = ROULETTES
        .iter()
        .map(|&(name, roulette)| {
            let s = RenderSettings {
                max_depth: ROULETTE_DEPTH,
                strategy: Some(DirectStrategy::Mis),
                roulette,
                ..Default::default()
            };
            let h = setup.halves(&b.settings(s));
            let (mean, se) = h.mean_and_se(None);
            RouletteRun {
                name,
                mean,
                se,
                noise: h.noise_per_pixel(),
                nonfinite: h.nonfinite(),
            }
        })
        .collect();
    Ok(RouletteCase { runs })
}

impl RouletteCase {
    pub fn off(&self) -> &RouletteRun {
        &self.runs[0]
    }

    pub fn rows(&self) -> Vec<Row> {
        let off = self.off().clone();
        self.runs
            .iter()
            .map(|r| Row {
                case: "8 roulette".into(),
                method: r.name.into(),
                mean: r.mean,
                stderr: r.se,
                expected: Some(off.mean),
                noise: r.noise,
                nonfinite: r.nonfinite,
                note: format!(
                    "variance ×{:.2} of no roulette; mean {:.1} σ from it",
                    (r.noise / off.noise).powi(2),
                    super::measure::z_score((r.mean, r.se), (off.mean, off.se))
                ),
            })
            .collect()
    }
}
