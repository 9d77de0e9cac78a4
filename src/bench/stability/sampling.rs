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
    pub min_samples_if_constant: u32,
    pub mean: f64,
    /// Standard error of `mean` if the pixels were unbiased: the reference's per-pixel
    /// variance scaled to each pixel's sample count.
    pub se: f64,
    pub mean_samples: f64,
    /// Pixels (with a lit reference) that stopped after one batch at exactly 0.
    pub stopped_at_zero_after_one_batch: usize,
    pub output: RenderOutput,
}

pub struct AdaptiveCase {
    /// Non-adaptive reference mean and standard error over the lit pixels.
    pub reference: (f64, f64),
    pub lit_pixels: Vec<usize>,
    pub guarded: AdaptiveRun,
    pub unguarded: AdaptiveRun,
    /// The default rule (`crate::adaptive`: constant pixels stop only in quiet neighbourhoods).
    pub neighbourhood: AdaptiveRun,
}

/// A floor under a 0.4 × 0.4 light seen by BSDF sampling alone: a single sample finds
/// the light with probability p ≤ Ω·cosθ/π ≈ 0.05, so a batch of 8 is all zero with
/// probability ≥ 0.95⁸ ≈ 0.66 although every floor pixel's mean is > 0.
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
    let reference: Halves = setup.halves(&RenderSettings {
        spp: REFERENCE_FACTOR * b.spp,
        ..b.settings(base.clone())
    });
    let avg = reference.average();
    let lit_pixels: Vec<usize> = (0..avg.pixels.len())
        .filter(|&i| lum(&avg, i) > 0.0)
        .collect();
    let run = |name: &'static str, guard: u32, rule: StopRule| {
        let adaptive = Adaptive {
            min_samples_if_constant: guard,
            rule,
            ..Adaptive::new(BATCH, TOL)
        };
        let output = setup.render(&b.settings(RenderSettings {
            adaptive: Some(adaptive),
            ..base.clone()
        }));
        let n = lit_pixels.len().max(1) as f64;
        let mean = lit_pixels
            .iter()
            .map(|&i| lum(&output.image, i))
            .sum::<f64>()
            / n;
        let mean_samples = lit_pixels
            .iter()
            .map(|&i| output.samples[i] as f64)
            .sum::<f64>()
            / n;
        let ref_spp = (REFERENCE_FACTOR * b.spp) as f64;
        let var: f64 = lit_pixels
            .iter()
            .map(|&i| {
                let d = lum(&reference.a.image, i) - lum(&reference.b.image, i);
                0.25 * d * d * ref_spp / output.samples[i].max(1) as f64
            })
            .sum();
        let se = var.sqrt() / n;
        let stopped_at_zero_after_one_batch = lit_pixels
            .iter()
            .filter(|&&i| output.samples[i] == BATCH && lum(&output.image, i) == 0.0)
            .count();
        AdaptiveRun {
            name,
            min_samples_if_constant: guard,
            mean,
            se,
            mean_samples,
            stopped_at_zero_after_one_batch,
            output,
        }
    };
    Ok(AdaptiveCase {
        reference: reference.mean_and_se(Some(&lit_pixels)),
        guarded: run("adaptive, guard 4·batch", 4 * BATCH, StopRule::PerPixel),
        unguarded: run("adaptive, no guard", 0, StopRule::PerPixel),
        neighbourhood: run(
            "adaptive, quiet-neighbourhood rule (default)",
            0,
            StopRule::Neighbourhood,
        ),
        lit_pixels,
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
        for r in [&self.neighbourhood, &self.guarded, &self.unguarded] {
            rows.push(Row {
                case: case.into(),
                method: r.name.into(),
                mean: r.mean,
                stderr: 0.0,
                expected: Some(rm),
                noise: 0.0,
                nonfinite: r.output.nonfinite_samples,
                note: format!(
                    "bias {:+.1}% ({:.1} reference σ); {} lit pixels stopped at 0 after one batch; {:.1} samples/pixel",
                    100.0 * (r.mean / rm - 1.0),
                    (r.mean - rm) / rse.max(1e-12),
                    r.stopped_at_zero_after_one_batch,
                    r.mean_samples
                ),
            });
        }
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
    (
        "fixed q = 0.05 from bounce 1",
        Roulette::Fixed {
            start: 1,
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
