//! `ember bench stability`: small scenes where an estimator or the geometry code is
//! pushed to where methods fail, what each method does there, and what ember does
//! about it. Every case is a function returning its measurements; the integration
//! tests (tests/stability.rs) assert on the same functions at small budgets.

pub mod environment;
pub mod glass;
pub mod light_paths;
pub mod lights;
pub mod measure;
pub mod robust;
pub mod sampling;
pub mod scenes;

use super::chart::{write_category_chart, ChartSpec, Series};
use super::table::Table;
use super::{create_out_dir, write_text, Report};
use crate::names::Named;
use anyhow::Result;
pub use measure::Budget;
use std::path::{Path, PathBuf};

#[derive(Clone, Debug)]
pub struct StabilityOptions {
    /// Multiplies every case's samples per pixel (1 = the report's defaults).
    pub spp_scale: f32,
    pub seed: u64,
}

impl Default for StabilityOptions {
    fn default() -> Self {
        StabilityOptions {
            spp_scale: 1.0,
            seed: 1,
        }
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
pub const EMBER_DOES: [(&str, &str); 10] = [
    ("1", "Hemisphere and BSDF-only sampling cannot see delta lights; `RenderJob::warnings` says so (the CLI prints it). The default strategies sample lights."),
    ("2", "Light sampling and MIS (the defaults: MIS for glossy or ambient-lit scenes, light sampling otherwise) sample the light's area: their noise does not grow as the light shrinks; -H's grows as √(2π/Ω)."),
    ("3", "MIS (power heuristic) is the default whenever the scene has glossy surfaces: never much worse than the better of light and BSDF sampling."),
    ("4", "Specular chains are followed by BSDF sampling with weight 1 at delta vertices; exact Fresnel; non-finite samples are counted and dropped (0 here)."),
    ("5", "Ray origins are offset by the hit point's own floating-point error bound (hit points relative to a triangle's corner or a sphere's centre, so the bound is ~2 ulps), shadow rays stop a relative 1e-4 short: every epsilon scales with the scene. What a spawned ray finds is placed on the sampled line from the surface point (`Scene::on_line`), and which area light that line meets is decided analytically (`PathIntegrator::area_light_on_line`), so the offset no longer brings lights, mirrors and caustics nearer (+1.6 % at 1e4, +6 % at 1e5 before). On an axis where a triangle's corners agree (walls, floors) the hit point is exact and rays leave from on the plane; a point within half an ulp of a triangle's edge is rounded into the triangle, not onto the neighbouring wall (room edges were dark at 1e5); rays leave a sphere from within about an ulp of their point, on the side the sphere test needs, not 2–3 cm off it (the ball's underside sent rays below the floor). Translations are compared with the original rounded as they round it (the scene itself moves on the f32 grid: balls by up to 4 mm at 1e5), over 12 seeds: surfaces agree within noise and no 8×8 block moves by more than one render's noise; scaling stays exact."),
    ("6", "Watertight triangle test (Woop et al.), f64 edge functions when f32 rounds to zero; degenerate triangles are never hit; zero-area lights are never sampled; no hit is rejected by a rounding bound on t (pbrt-v4's t ≤ δt, which dropped hits below ~2e-4 rad): rays leaving a surface skip the triangle they left, or reach the sphere they left only at its far side."),
    ("7", "The default stopping rule (`crate::adaptive`) never takes a pixel of zeros as converged on its own evidence: it stops once n zeros would have a chance of at most 1 % if light reached it a quarter as often as it reaches the pixels within 5 px in a first batch over the image, `(1 − p̂/4)ⁿ ≤ 0.01` (at most 17 samples where its camera rays met nothing); other pixels follow the course's rule up to -s. Unbiased here (paired with the fixed-count render of the same seed); no lit pixel can meet the 5 % tolerance below ~29 000 samples, so at the same -s every lit pixel runs to the cap, and the old 4·batch guard's smaller spend came only from the pixels it stopped at zero (−43 %). At the guard's spend (-s 248) the default rule is still unbiased; on cornell.dae it spends less than the guard at the same -s."),
    ("8", "Roulette divides by the continuation probability (unbiased); the default is throughput-based from bounce 5 with q ≥ 0.05."),
    ("9", "Light tracing (`--integrator light-tracing`): paths start on the lights and connect to the camera; `--integrator auto` picks it when every light is a point light, nothing is specular or self-emitting and paths may bounce (-m ≥ 2; direct light from point lights is exact per camera sample). The path tracer stays the default elsewhere."),
    ("10", "`-e` samples the environment map by luminance × sin θ (a 2-D piecewise-constant distribution, pbrt's), combined with BSDF sampling by MIS (the default whenever the scene has an environment light)."),
];

pub fn run_stability(opts: &StabilityOptions) -> Result<StabilityReport> {
    let spp = |base: u32| ((base as f32 * opts.spp_scale).round() as u32).max(2);
    let budget = |w: u32, h: u32, s: u32| Budget {
        width: w,
        height: h,
        spp: spp(s),
        seed: opts.seed,
    };
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
    rows.extend(light_paths::rows_if_data(&budget(160, 120, 32))?);
    rows.extend(environment::sun_sky(&budget(80, 60, 64))?.rows());
    Ok(StabilityReport { rows })
}

impl StabilityReport {
    /// The rows at full precision, for scripts.
    pub fn to_csv(&self) -> String {
        let mut t = Table::new([
            "case",
            "method",
            "mean",
            "stderr",
            "expected",
            "noise_per_pixel",
            "nonfinite",
            "note",
        ]);
        for r in &self.rows {
            t.push(vec![
                r.case.clone(),
                r.method.clone(),
                format!("{:.6e}", r.mean),
                format!("{:.3e}", r.stderr),
                r.expected.map_or(String::new(), |e| format!("{e:.6e}")),
                format!("{:.4e}", r.noise),
                r.nonfinite.to_string(),
                r.note.clone(),
            ]);
        }
        t.to_csv()
    }

    /// The rows, then what ember does in each case.
    pub fn to_markdown(&self) -> String {
        let mut t = Table::new([
            "case",
            "method",
            "mean",
            "± s.e.",
            "expected",
            "noise/pixel",
            "NaN/Inf",
            "finding",
        ]);
        for r in &self.rows {
            t.push(vec![
                r.case.clone(),
                r.method.clone(),
                format!("{:.4}", r.mean),
                format!("{:.2e}", r.stderr),
                r.expected.map_or("–".to_string(), |e| format!("{e:.4}")),
                format!("{:.3e}", r.noise),
                r.nonfinite.to_string(),
                r.note.clone(),
            ]);
        }
        let mut does = Table::new(["case", "what ember does"]);
        for (case, what) in EMBER_DOES {
            does.push(vec![case.to_string(), what.to_string()]);
        }
        format!("{}\n{}", t.to_markdown(), does.to_markdown())
    }

    /// Relative per-pixel noise (noise / mean) of each direct-lighting strategy in each
    /// case of the table that compares them (cases 1–3, named as the table names them):
    /// the series' points are `(index of the case, noise / mean)`; a method whose
    /// image is black (it cannot see the light) has no point there.
    pub fn strategy_noise_series(&self) -> (Vec<Series>, Vec<String>) {
        let names: Vec<&str> = lights::STRATEGIES.iter().map(|s| s.name()).collect();
        let mut cases: Vec<String> = Vec::new();
        let mut out: Vec<Series> = names
            .iter()
            .map(|n| Series {
                name: n.to_string(),
                points: Vec::new(),
            })
            .collect();
        for r in self
            .rows
            .iter()
            .filter(|r| names.contains(&r.method.as_str()))
        {
            if !cases.contains(&r.case) {
                cases.push(r.case.clone());
            }
            if r.noise > 0.0 && r.mean > 0.0 {
                let x = (cases.len() - 1) as f64;
                let k = names
                    .iter()
                    .position(|n| *n == r.method)
                    .expect("strategy name");
                out[k].points.push((x, r.noise / r.mean));
            }
        }
        (out, cases)
    }

    /// The noise chart `<stem>.{png,svg}`: one slot per case, labelled as in the table.
    fn write_chart(&self, stem: &Path) -> Result<()> {
        let (series, cases) = self.strategy_noise_series();
        let spec = ChartSpec {
            title: "Direct-lighting strategies where they fail: relative noise per pixel",
            x_label: "case of the table (no marker: the strategy's image is black, it cannot reach the light)",
            y_label: "per-pixel noise / mean (equal spp)",
            log_x: false,
            log_y: true,
        };
        write_category_chart(stem, &spec, &cases, &series)
    }
}

impl Report for StabilityReport {
    /// `stability.csv`, `stability.md` and `stability_noise.{png,svg}`.
    fn write(&self, out_dir: &Path) -> Result<Vec<PathBuf>> {
        create_out_dir(out_dir)?;
        let csv = out_dir.join("stability.csv");
        write_text(&csv, &self.to_csv())?;
        let md = out_dir.join("stability.md");
        write_text(&md, &self.to_markdown())?;
        let chart = out_dir.join("stability_noise");
        self.write_chart(&chart)?;
        Ok(vec![
            csv,
            md,
            chart.with_extension("png"),
            chart.with_extension("svg"),
        ])
    }

    fn summary(&self) -> String {
        self.to_markdown()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(case: &str, method: &str, noise: f64) -> Row {
        Row {
            case: case.into(),
            method: method.into(),
            mean: 0.5,
            stderr: 0.01,
            expected: None,
            noise,
            nonfinite: 0,
            note: "a \"quoted\" note".into(),
        }
    }

    #[test]
    fn report_formats_and_chart() {
        let r = StabilityReport {
            rows: vec![
                row("2 small", "hemisphere", 0.4),
                row("2 small", "light", 0.01),
                row("8 roulette", "no roulette", 0.1),
            ],
        };
        let csv = r.to_csv();
        assert_eq!(csv.lines().count(), 4);
        assert!(csv
            .lines()
            .nth(1)
            .unwrap()
            .ends_with("\"a \"\"quoted\"\" note\""));
        let md = r.to_markdown();
        assert!(md.contains("| 2 small | hemisphere |") && md.contains("what ember does"));
        let (series, cases) = r.strategy_noise_series();
        assert_eq!(cases, vec!["2 small".to_string()]);
        assert_eq!(
            series
                .iter()
                .find(|s| s.name == "hemisphere")
                .unwrap()
                .points,
            vec![(0.0, 0.8)]
        );
        let dir = tempfile::tempdir().unwrap();
        let files = r.write(&dir.path().join("out")).unwrap();
        assert_eq!(files.len(), 4);
        for f in [
            "stability.csv",
            "stability.md",
            "stability_noise.png",
            "stability_noise.svg",
        ] {
            assert!(dir.path().join("out").join(f).exists(), "{f}");
        }
    }
}
