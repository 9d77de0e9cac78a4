//! `ember bench stability`: small scenes where an estimator or the geometry code is
//! pushed to where methods fail, what each method does there, and what ember does
//! about it. Every case is a function returning its measurements; the integration
//! tests (tests/stability.rs) assert on the same functions at small budgets.

pub mod glass;
pub mod lights;
pub mod measure;
pub mod robust;
pub mod sampling;
pub mod scenes;

use super::chart::{write_chart, ChartSpec, Series};
use anyhow::{Context, Result};
pub use measure::Budget;
use std::fmt::Write as _;
use std::path::PathBuf;

#[derive(Clone, Debug)]
pub struct StabilityOptions {
    /// Where `stability.csv`, `stability.md` and the charts go (created if missing).
    pub out_dir: PathBuf,
    /// Multiplies every case's samples per pixel (1 = the report's defaults).
    pub spp_scale: f32,
    pub seed: u64,
}

impl Default for StabilityOptions {
    fn default() -> Self {
        StabilityOptions { out_dir: PathBuf::from("stability"), spp_scale: 1.0, seed: 1 }
    }
}

/// One method in one case.
#[derive(Clone, Debug)]
pub struct Row {
    pub case: String,
    pub method: String,
    /// Image (or region) mean luminance, or the case's own measure (see `note`).
    pub mean: f64,
    pub stderr: f64,
    pub expected: Option<f64>,
    /// RMS noise of one pixel (luminance); 0 where not measured.
    pub noise: f64,
    pub nonfinite: u64,
    pub note: String,
}

pub struct StabilityReport {
    pub rows: Vec<Row>,
}

/// What ember does about each case, for the report.
pub const EMBER_DOES: [(&str, &str); 8] = [
    ("1", "Hemisphere and BSDF-only sampling cannot see delta lights; `render_warnings` says so in RenderOutput.warnings (the CLI prints it). The default strategies sample lights."),
    ("2", "Light sampling (default for -m 1) and MIS (default beyond) sample the light's area: their noise does not grow as the light shrinks; -H's grows as √(2π/Ω)."),
    ("3", "MIS (power heuristic) is the default for -m > 1: never much worse than the better of light and BSDF sampling."),
    ("4", "Specular chains are followed by BSDF sampling with weight 1 at delta vertices; exact Fresnel; non-finite samples are counted and dropped (0 here)."),
    ("5", "Ray origins are offset by the hit point's own floating-point error bound, shadow rays stop a relative 1e-4 short: every epsilon scales with the scene."),
    ("6", "Watertight triangle test (Woop et al.) with shared-edge tie rules; degenerate triangles have zero area and are never hit or sampled."),
    ("7", "Adaptive::min_samples_if_constant (4·batch by default) keeps a pixel whose samples are all equal sampling beyond the first batch."),
    ("8", "Roulette divides by the continuation probability (unbiased); the default is throughput-based from bounce 3 with q ≥ 0.05."),
];

pub fn run_stability(opts: &StabilityOptions) -> Result<StabilityReport> {
    let spp = |base: u32| ((base as f32 * opts.spp_scale).round() as u32).max(2);
    let budget = |w: u32, h: u32, s: u32| Budget { width: w, height: h, spp: spp(s), seed: opts.seed };
    let mut rows = Vec::new();
    rows.extend(lights::point_light(&budget(160, 120, 8))?.rows());
    for size in [4.0, 1.0, 0.25] {
        rows.extend(lights::small_light(&budget(80, 60, 256), size)?.rows());
    }
    for scene in lights::GLOSSY_SCENES {
        rows.extend(lights::glossy(&budget(80, 60, 256), scene)?.rows());
    }
    rows.extend(glass::caustic(&budget(120, 90, 512))?.rows());
    rows.extend(glass::slab(&budget(40, 30, 256))?.rows());
    rows.extend(robust::scale(&budget(160, 120, 64))?.rows());
    rows.extend(robust::grid(&budget(320, 240, 4))?.rows());
    rows.extend(sampling::adaptive(&budget(80, 60, 512))?.rows());
    rows.extend(sampling::roulette(&budget(80, 60, 256))?.rows());
    let report = StabilityReport { rows };
    report.write(opts)?;
    Ok(report)
}

impl StabilityReport {
    pub fn to_csv(&self) -> String {
        let mut s = String::from("case,method,mean,stderr,expected,noise_per_pixel,nonfinite,note\n");
        for r in &self.rows {
            let expected = r.expected.map_or(String::new(), |e| format!("{e:.6e}"));
            let note = r.note.replace('"', "'");
            let _ = writeln!(s, "{},{},{:.6e},{:.3e},{expected},{:.4e},{},\"{note}\"", r.case, r.method, r.mean, r.stderr, r.noise, r.nonfinite);
        }
        s
    }

    pub fn to_markdown(&self) -> String {
        let mut s = String::from("| case | method | mean | ± s.e. | expected | noise/pixel | NaN/Inf | finding |\n|---|---|---|---|---|---|---|---|\n");
        for r in &self.rows {
            let expected = r.expected.map_or("–".to_string(), |e| format!("{e:.4}"));
            let _ = writeln!(s, "| {} | {} | {:.4} | {:.2e} | {expected} | {:.3e} | {} | {} |", r.case, r.method, r.mean, r.stderr, r.noise, r.nonfinite, r.note);
        }
        s.push_str("\n| case | what ember does |\n|---|---|\n");
        for (case, does) in EMBER_DOES {
            let _ = writeln!(s, "| {case} | {does} |");
        }
        s
    }

    /// Relative per-pixel noise (noise / mean) of each method, x = case number.
    pub fn noise_series(&self) -> Vec<Series> {
        let mut out: Vec<Series> = Vec::new();
        for (k, r) in self.rows.iter().enumerate() {
            if r.noise <= 0.0 || r.mean <= 0.0 {
                continue;
            }
            let case_no: f64 = r.case.split(' ').next().and_then(|c| c.parse().ok()).unwrap_or(k as f64);
            let p = (case_no, r.noise / r.mean);
            match out.iter_mut().find(|s| s.name == r.method) {
                Some(s) => s.points.push(p),
                None => out.push(Series { name: r.method.clone(), points: vec![p] }),
            }
        }
        out
    }

    /// Writes `stability.csv`, `stability.md` and `stability_noise.{png,svg}` into `opts.out_dir`.
    pub fn write(&self, opts: &StabilityOptions) -> Result<()> {
        let dir = &opts.out_dir;
        std::fs::create_dir_all(dir).with_context(|| format!("{}: cannot create", dir.display()))?;
        let csv = dir.join("stability.csv");
        std::fs::write(&csv, self.to_csv()).with_context(|| format!("{}: cannot write", csv.display()))?;
        let md = dir.join("stability.md");
        std::fs::write(&md, self.to_markdown()).with_context(|| format!("{}: cannot write", md.display()))?;
        let spec = ChartSpec { title: "Stability: relative per-pixel noise per method", x_label: "case", y_label: "noise / mean (per pixel)", log_x: false, log_y: true };
        write_chart(&dir.join("stability_noise"), &spec, &self.noise_series())
    }
}
