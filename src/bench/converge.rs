//! `ember bench converge`: error against time for each method, so speed and
//! accuracy can be charted against each other.
//!
//! Each point is a fresh render (its own seed) at a doubled sample count, timed
//! render-only with all threads. Errors are measured against a reference: a given
//! EXR (e.g. the Mitsuba references, whose noise is negligible at their spp and
//! is subtracted anyway when known) or ember's own high-spp render, rendered as
//! two halves so that its own noise variance can be subtracted from every MSE.

use super::chart::{write_chart, ChartSpec, Series};
use super::mitsuba::MitsubaRunner;
use super::table::Table;
use super::{create_out_dir, write_text, Report};
use crate::accel::{AccelKind, BvhBuilder, EmbreeQuality};
use crate::camera::Camera;
use crate::film::Image;
use crate::image_io::{read_image, write_image};
use crate::integrators::{DirectStrategy, Estimator, Roulette};
use crate::render::{average, Adaptive, RenderJob, RenderSettings};
use crate::scene::{collada, Scene};
use anyhow::{bail, Context, Result};
use std::path::{Path, PathBuf};
use std::time::Instant;

#[derive(Clone, Debug)]
pub struct ConvergeOptions {
    pub scene: PathBuf,
    /// Linear EXR to measure against; None renders (and caches) ember's own.
    pub reference: Option<PathBuf>,
    /// Per-pixel RMS noise of `reference`, if known (e.g. from the references' manifest).
    pub reference_noise: Option<f64>,
    pub width: u32,
    pub height: u32,
    pub max_depth: u32,
    /// Largest spp of the doubling sequence.
    pub max_spp: u32,
    /// A method stops doubling once one render takes longer than this.
    pub max_seconds_per_point: f64,
    /// spp of ember's own reference (split into two halves).
    pub reference_spp: u32,
    pub out_dir: PathBuf,
    /// RMSE whose time-to-reach is tabulated; None: the median of the methods' final RMSEs.
    pub target_rmse: Option<f64>,
    pub seed: u64,
    /// Add the Embree backend as a method when this build has it.
    pub compare_backends: bool,
    /// Mitsuba 3 as a peer method, one curve per variant.
    pub mitsuba: Option<MitsubaPeer>,
}

/// Where Mitsuba 3 is and which of its variants to run.
#[derive(Clone, Debug)]
pub struct MitsubaPeer {
    /// A Python interpreter that imports `mitsuba` (`scripts/mitsuba-env` prints one).
    pub python: PathBuf,
    pub variants: Vec<String>,
}

/// One way of rendering the image.
#[derive(Clone, Debug)]
pub struct Method {
    pub name: String,
    pub settings: RenderSettings,
    pub accel: AccelKind,
}

#[derive(Clone, Debug)]
pub struct Point {
    pub method: String,
    pub spp: u32,
    pub samples: u64,
    pub seconds: f64,
    pub rmse: f64,
    pub rel_mse: f64,
}

pub struct ConvergeReport {
    /// The scene's file stem, which names the report's files.
    pub scene: String,
    pub max_depth: u32,
    pub width: u32,
    pub height: u32,
    pub points: Vec<Point>,
    pub target_rmse: f64,
    /// (method, seconds to reach the target RMSE, if it did).
    pub time_to_target: Vec<(String, Option<f64>)>,
    pub reference_note: String,
}

/// The methods compared for depth `m`: the direct-lighting estimators at `m = 1`,
/// MIS with and without roulette and at several `-l` beyond; adaptive sampling and
/// (optionally) Embree with the scene's default (`DirectStrategy::auto_for`).
pub fn methods(base: &RenderSettings, scene: &Scene, compare_backends: bool) -> Vec<Method> {
    let native = AccelKind::Native(BvhBuilder::Sah);
    let m = |name: &str, s: RenderSettings| Method {
        name: name.to_string(),
        settings: s,
        accel: native,
    };
    let mut v = Vec::new();
    let default_strategy = None;
    if base.max_depth <= 1 {
        v.push(m(
            "hemisphere",
            RenderSettings {
                strategy: Some(DirectStrategy::Hemisphere),
                ..base.clone()
            },
        ));
        v.push(m(
            "light sampling",
            RenderSettings {
                strategy: Some(DirectStrategy::Light),
                ..base.clone()
            },
        ));
        v.push(m(
            "MIS",
            RenderSettings {
                strategy: Some(DirectStrategy::Mis),
                ..base.clone()
            },
        ));
    } else {
        v.push(m(
            "light sampling, RR",
            RenderSettings {
                strategy: Some(DirectStrategy::Light),
                ..base.clone()
            },
        ));
        v.push(m(
            "MIS, RR",
            RenderSettings {
                strategy: Some(DirectStrategy::Mis),
                ..base.clone()
            },
        ));
        v.push(m(
            "MIS, no RR",
            RenderSettings {
                strategy: Some(DirectStrategy::Mis),
                roulette: Roulette::Off,
                ..base.clone()
            },
        ));
        v.push(m(
            "MIS, RR, -l 4",
            RenderSettings {
                strategy: Some(DirectStrategy::Mis),
                light_samples: 4,
                ..base.clone()
            },
        ));
        v.push(m(
            "MIS, RR, -l 16",
            RenderSettings {
                strategy: Some(DirectStrategy::Mis),
                light_samples: 16,
                ..base.clone()
            },
        ));
    }
    // Light tracing cannot show specular surfaces to the camera: only where it can converge.
    if !scene.materials.iter().any(|mat| mat.is_delta()) {
        v.push(m(
            "light tracing",
            RenderSettings {
                estimator: Some(Estimator::LightTracing),
                ..base.clone()
            },
        ));
    }
    v.push(m(
        "adaptive (-a 16 0.05)",
        RenderSettings {
            strategy: default_strategy,
            adaptive: Some(Adaptive::new(16, 0.05)),
            ..base.clone()
        },
    ));
    if compare_backends && cfg!(any(feature = "embree", feature = "embree4")) {
        v.push(Method {
            name: "Embree backend".into(),
            settings: RenderSettings {
                strategy: default_strategy,
                ..base.clone()
            },
            accel: AccelKind::embree(EmbreeQuality::Medium),
        });
    }
    v
}

struct Reference {
    image: Image,
    /// Per-pixel-channel noise variance of the reference, subtracted from every MSE.
    noise_var: f64,
    note: String,
}

pub fn run(opts: &ConvergeOptions, log: &mut dyn FnMut(&str)) -> Result<ConvergeReport> {
    let scene = collada::load(&opts.scene)?;
    let base = RenderSettings {
        max_depth: opts.max_depth,
        seed: opts.seed,
        ..Default::default()
    };
    let reference = reference(opts, &scene, &base, log)?;
    let mut points = Vec::new();
    for method in methods(&base, &scene, opts.compare_backends) {
        log(&format!("method: {}", method.name));
        points.extend(run_method(&scene, &method, opts, &reference)?);
    }
    if let Some(peer) = &opts.mitsuba {
        for variant in &peer.variants {
            let dir = opts.out_dir.join("mitsuba");
            let runner = MitsubaRunner::new(&peer.python, variant, &dir)?;
            log(&format!("method: Mitsuba 3 {variant}"));
            points.extend(run_mitsuba(&scene, &runner, opts, &reference)?);
        }
    }
    let target = opts.target_rmse.unwrap_or_else(|| default_target(&points));
    let time_to_target = time_to_reach(&points, target);
    Ok(ConvergeReport {
        scene: scene_stem(&opts.scene),
        max_depth: opts.max_depth,
        width: opts.width,
        height: opts.height,
        points,
        target_rmse: target,
        time_to_target,
        reference_note: reference.note,
    })
}

fn run_method(
    scene: &Scene,
    method: &Method,
    opts: &ConvergeOptions,
    r: &Reference,
) -> Result<Vec<Point>> {
    let job = RenderJob::new(scene.clone(), method.accel, opts.width, opts.height)?;
    let mut out = Vec::new();
    let mut spp = 1;
    while spp <= opts.max_spp {
        let s = RenderSettings {
            spp,
            seed: opts.seed.wrapping_add(1000 + spp as u64),
            ..method.settings.clone()
        };
        let t = Instant::now();
        let o = job.render(&s);
        let seconds = t.elapsed().as_secs_f64();
        let (rmse, rel_mse) = errors(&o.image, r);
        out.push(Point {
            method: method.name.clone(),
            spp,
            samples: o.total_samples(),
            seconds,
            rmse,
            rel_mse,
        });
        if seconds > opts.max_seconds_per_point {
            break;
        }
        spp *= 2;
    }
    Ok(out)
}

/// The same doubling sequence as [`run_method`], rendered by Mitsuba: each point
/// is the render-only time of a warm call in its own process.
fn run_mitsuba(
    scene: &Scene,
    runner: &MitsubaRunner,
    opts: &ConvergeOptions,
    r: &Reference,
) -> Result<Vec<Point>> {
    let camera = Camera::new(&scene.camera, &scene.bounds, opts.width, opts.height);
    let mut out = Vec::new();
    let mut spp = 1;
    while spp <= opts.max_spp {
        let seed = opts.seed.wrapping_add(1000 + spp as u64);
        let m = runner.render(scene, &camera, opts.max_depth, spp, seed)?;
        let (rmse, rel_mse) = errors(&m.image, r);
        out.push(Point {
            method: format!("Mitsuba 3 {}", runner.variant()),
            spp,
            samples: u64::from(spp) * u64::from(opts.width) * u64::from(opts.height),
            seconds: m.seconds,
            rmse,
            rel_mse,
        });
        if m.seconds > opts.max_seconds_per_point {
            break;
        }
        spp *= 2;
    }
    Ok(out)
}

/// RMSE and relMSE with the reference's own noise variance removed (never below 0).
fn errors(img: &Image, r: &Reference) -> (f64, f64) {
    let mse = img.rmse(&r.image).powi(2);
    let rmse = (mse - r.noise_var).max(0.0).sqrt();
    let n = (3 * img.pixels.len()) as f64;
    let mut rel = 0.0;
    for (a, b) in img.pixels.iter().zip(&r.image.pixels) {
        for c in 0..3 {
            let (a, b) = (a[c] as f64, b[c] as f64);
            rel += ((a - b).powi(2) - r.noise_var) / (b * b + 0.01);
        }
    }
    (rmse, (rel / n).max(0.0))
}

fn reference(
    opts: &ConvergeOptions,
    scene: &Scene,
    base: &RenderSettings,
    log: &mut dyn FnMut(&str),
) -> Result<Reference> {
    if let Some(p) = &opts.reference {
        let image = read_image(p)?;
        if (image.width, image.height) != (opts.width, opts.height) {
            bail!(
                "{}: reference is {}x{}, but the renders are {}x{} (use -r)",
                p.display(),
                image.width,
                image.height,
                opts.width,
                opts.height
            );
        }
        let noise_var = opts.reference_noise.map_or(0.0, |n| n * n);
        let note = format!(
            "reference {} (its per-pixel noise {} is subtracted from every MSE)",
            p.display(),
            opts.reference_noise
                .map_or("unknown, taken as negligible,".to_string(), |n| format!(
                    "{n:.2e}"
                ))
        );
        return Ok(Reference {
            image,
            noise_var,
            note,
        });
    }
    own_reference(opts, scene, base, log)
}

/// Seed of ember's own reference.
const REFERENCE_SEED: u64 = 0x607FF7;

fn own_reference(
    opts: &ConvergeOptions,
    scene: &Scene,
    base: &RenderSettings,
    log: &mut dyn FnMut(&str),
) -> Result<Reference> {
    let stem = scene_stem(&opts.scene);
    let cache = opts.out_dir.join("cache");
    std::fs::create_dir_all(&cache)
        .with_context(|| format!("{}: cannot create", cache.display()))?;
    let name = |half: &str| {
        cache.join(format!(
            "{stem}_m{}_{}x{}_{}spp_{half}.exr",
            opts.max_depth, opts.width, opts.height, opts.reference_spp
        ))
    };
    let (pa, pb) = (name("a"), name("b"));
    let (a, b) = if pa.exists() && pb.exists() {
        log(&format!("reference: cached {}", pa.display()));
        (read_image(&pa)?, read_image(&pb)?)
    } else {
        log(&format!(
            "reference: rendering {} spp (two halves) with MIS, no roulette",
            opts.reference_spp
        ));
        let job = RenderJob::new(
            scene.clone(),
            AccelKind::Native(BvhBuilder::Sah),
            opts.width,
            opts.height,
        )?;
        let h = job.halves(&RenderSettings {
            spp: opts.reference_spp,
            strategy: Some(if base.max_depth > 1 {
                DirectStrategy::Mis
            } else {
                DirectStrategy::Light
            }),
            roulette: Roulette::Off,
            // The halves' seeds 2·seed + 1 and 2·seed + 2 are 0xC0FFEE + 1 and + 2.
            seed: REFERENCE_SEED,
            ..base.clone()
        });
        write_image(&h.a.image, &pa)?;
        write_image(&h.b.image, &pb)?;
        (h.a.image, h.b.image)
    };
    let noise_var = a.rmse(&b).powi(2) / 4.0;
    let image = average(&a, &b);
    let note = format!(
        "ember's own reference, {} spp in two halves; its per-pixel noise {:.2e} (from the halves) is subtracted from every MSE",
        opts.reference_spp,
        noise_var.sqrt()
    );
    Ok(Reference {
        image,
        noise_var,
        note,
    })
}

/// The median of the methods' final RMSEs: about half the methods reach it, and the
/// heavy-tailed ones (whose curves wander) do not set it.
fn default_target(points: &[Point]) -> f64 {
    let mut finals: std::collections::BTreeMap<&str, f64> = Default::default();
    for p in points {
        finals.insert(&p.method, p.rmse);
    }
    let mut v: Vec<f64> = finals.values().copied().collect();
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(0.0)
}

/// Seconds each method needs to reach `target`, from its Monte Carlo efficiency:
/// an unbiased estimator has MSE ∝ 1/time, so `k = RMSE²·time` is constant in the
/// converged regime and the time to reach `target` is `k/target²`. `k` is the median
/// over the points with at least `MIN_SPP` samples per pixel (the first few points
/// are dominated by fixed costs). A single run's crossing point would be decided by
/// noise; this uses every point. Methods whose error stalls (bias) get a growing `k`
/// and so a long time, as they should.
pub fn time_to_reach(points: &[Point], target: f64) -> Vec<(String, Option<f64>)> {
    const MIN_SPP: u32 = 8;
    let mut names: Vec<String> = Vec::new();
    for p in points {
        if !names.contains(&p.method) {
            names.push(p.method.clone());
        }
    }
    names
        .into_iter()
        .map(|name| {
            let mut ks: Vec<f64> = points
                .iter()
                .filter(|p| {
                    p.method == name && p.spp >= MIN_SPP && p.seconds > 0.0 && p.rmse.is_finite()
                })
                .map(|p| p.rmse * p.rmse * p.seconds)
                .collect();
            let t = (!ks.is_empty() && target > 0.0)
                .then(|| super::median(&mut ks) / (target * target));
            (name, t)
        })
        .collect()
}

/// `method`'s RMSE at `seconds`, interpolated log-log between its two points that
/// bracket it (`None` outside its points' range).
pub fn rmse_at(points: &[Point], method: &str, seconds: f64) -> Option<f64> {
    let mut pts: Vec<(f64, f64)> = points
        .iter()
        .filter(|p| p.method == method && p.seconds > 0.0 && p.rmse > 0.0)
        .map(|p| (p.seconds, p.rmse))
        .collect();
    pts.sort_by(|a, b| a.0.total_cmp(&b.0));
    let (a, b) = pts
        .windows(2)
        .map(|w| (w[0], w[1]))
        .find(|(a, b)| a.0 <= seconds && seconds <= b.0)?;
    if a.0 == b.0 {
        return Some(a.1);
    }
    let f = (seconds / a.0).ln() / (b.0 / a.0).ln();
    Some((a.1.ln() + f * (b.1 / a.1).ln()).exp())
}

/// Three render times, log-spaced over the range the first method (ember's default)
/// and every Mitsuba method have all measured, from their 8-spp points on.
fn common_times(points: &[Point]) -> Vec<f64> {
    let Some(first) = points.first().map(|p| p.method.clone()) else {
        return Vec::new();
    };
    let (mut lo, mut hi) = (0.0f64, f64::INFINITY);
    let mut names = vec![first];
    for p in points.iter().filter(|p| p.method.starts_with("Mitsuba")) {
        if !names.contains(&p.method) {
            names.push(p.method.clone());
        }
    }
    for name in &names {
        let secs = points
            .iter()
            .filter(|p| &p.method == name && p.spp >= 8)
            .map(|p| p.seconds);
        let (a, b) = secs.fold((f64::INFINITY, 0.0f64), |(a, b), t| (a.min(t), b.max(t)));
        (lo, hi) = (lo.max(a), hi.min(b));
    }
    if !(lo > 0.0 && hi > lo) {
        return Vec::new();
    }
    (0..3)
        .map(|k| lo * (hi / lo).powf(k as f64 / 2.0))
        .collect()
}

/// `path`'s file name without its extension ("" when it has none).
fn scene_stem(path: &Path) -> String {
    path.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default()
}

impl ConvergeReport {
    pub fn to_csv(&self) -> String {
        let mut t = Table::new([
            "scene", "method", "spp", "samples", "seconds", "rmse", "relmse",
        ]);
        for p in &self.points {
            t.push(vec![
                self.scene.clone(),
                p.method.clone(),
                p.spp.to_string(),
                p.samples.to_string(),
                format!("{:.6}", p.seconds),
                format!("{:.6e}", p.rmse),
                format!("{:.6e}", p.rel_mse),
            ]);
        }
        t.to_csv()
    }

    /// Time each method needs to reach the target RMSE, and its ratio to the fastest.
    pub fn efficiency_table(&self) -> String {
        let best = self
            .time_to_target
            .iter()
            .filter_map(|(_, t)| *t)
            .fold(f64::INFINITY, f64::min);
        let mut table = Table::new([
            "method".to_string(),
            format!(
                "seconds to RMSE {:.4} (from median RMSE²·time)",
                self.target_rmse
            ),
            "× fastest".to_string(),
        ]);
        for (name, t) in &self.time_to_target {
            table.push(match t {
                Some(t) => vec![name.clone(), format!("{t:.3}"), format!("{:.2}", t / best)],
                None => vec![name.clone(), "not reached".into(), "–".into()],
            });
        }
        table.to_markdown()
    }

    /// Each method's RMSE at three common render times (interpolated on its curve),
    /// and the first method's RMSE as a fraction of each Mitsuba method's: the
    /// comparison at equal time that holds whatever the shape of the curves.
    pub fn equal_time_table(&self) -> String {
        let times = common_times(&self.points);
        if times.is_empty() {
            return String::new();
        }
        let mut header = vec!["method".to_string()];
        header.extend(times.iter().map(|t| format!("RMSE at {t:.3} s")));
        let mut table = Table::new(header);
        let mut names: Vec<&str> = Vec::new();
        for p in &self.points {
            if !names.contains(&p.method.as_str()) {
                names.push(&p.method);
            }
        }
        let cell =
            |v: Option<f64>, digits: usize| v.map_or("–".into(), |v| format!("{v:.digits$}"));
        for name in &names {
            let mut row = vec![name.to_string()];
            row.extend(
                times
                    .iter()
                    .map(|&t| cell(rmse_at(&self.points, name, t), 5)),
            );
            table.push(row);
        }
        for peer in names.iter().filter(|n| n.starts_with("Mitsuba")) {
            let mut row = vec![format!("{} ÷ {peer}", names[0])];
            row.extend(times.iter().map(|&t| {
                let ratio = rmse_at(&self.points, names[0], t)
                    .zip(rmse_at(&self.points, peer, t))
                    .map(|(a, b)| a / b);
                cell(ratio, 2)
            }));
            table.push(row);
        }
        table.to_markdown()
    }

    fn series(&self, y: impl Fn(&Point) -> f64) -> Vec<Series> {
        let mut out: Vec<Series> = Vec::new();
        for p in &self.points {
            match out.iter_mut().find(|s| s.name == p.method) {
                Some(s) => s.points.push((p.seconds, y(p))),
                None => out.push(Series {
                    name: p.method.clone(),
                    points: vec![(p.seconds, y(p))],
                }),
            }
        }
        out
    }
}

impl Report for ConvergeReport {
    /// `<scene>_m<M>.csv`, and error-vs-time charts `<scene>_m<M>_rmse.{png,svg}` and
    /// `<scene>_m<M>_relmse.{png,svg}`.
    fn write(&self, out_dir: &Path) -> Result<Vec<PathBuf>> {
        create_out_dir(out_dir)?;
        let stem = format!("{}_m{}", self.scene, self.max_depth);
        let csv = out_dir.join(format!("{stem}.csv"));
        write_text(&csv, &self.to_csv())?;
        let title = format!(
            "{}, -m {}, {}x{}: error vs time",
            self.scene, self.max_depth, self.width, self.height
        );
        let (rmse, relmse) = (
            out_dir.join(format!("{stem}_rmse")),
            out_dir.join(format!("{stem}_relmse")),
        );
        let spec = ChartSpec {
            title: &title,
            x_label: "render time (s, 2 threads)",
            y_label: "RMSE vs reference",
            log_x: true,
            log_y: true,
        };
        write_chart(&rmse, &spec, &self.series(|p| p.rmse))?;
        let spec = ChartSpec {
            y_label: "relMSE vs reference",
            ..spec
        };
        write_chart(&relmse, &spec, &self.series(|p| p.rel_mse))?;
        let mut files = vec![csv];
        for chart in [rmse, relmse] {
            files.extend(["png", "svg"].map(|ext| chart.with_extension(ext)));
        }
        Ok(files)
    }

    /// Where the reference came from, the time each method needs to reach the target
    /// RMSE, and the RMSEs at equal render time.
    fn summary(&self) -> String {
        format!(
            "{}\n{}\n{}",
            self.reference_note,
            self.efficiency_table(),
            self.equal_time_table()
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn time_to_reach_uses_the_efficiency() {
        let pt = |method: &str, spp, seconds, rmse| Point {
            method: method.into(),
            spp,
            samples: 1,
            seconds,
            rmse,
            rel_mse: 0.0,
        };
        // RMSE² · time = 0.01 at every converged point: 0.05 is reached at 0.01/0.0025 = 4 s.
        let pts = vec![
            pt("a", 1, 0.01, 5.0),
            pt("a", 8, 1.0, 0.1),
            pt("a", 16, 4.0, 0.05),
            pt("a", 32, 16.0, 0.025),
        ];
        let t = time_to_reach(&pts, 0.05);
        assert!((t[0].1.unwrap() - 4.0).abs() < 1e-9);
        assert_eq!(time_to_reach(&[pt("b", 1, 1.0, 1.0)], 0.1)[0].1, None);
        // On the log-log line RMSE = 0.1/√t: 2 s lies between the 1 s and 4 s points.
        let r = rmse_at(&pts, "a", 2.0).unwrap();
        assert!((r - 0.1 / 2f64.sqrt()).abs() < 1e-12, "{r}");
        assert_eq!(rmse_at(&pts, "a", 20.0), None);
        assert_eq!(rmse_at(&pts, "b", 1.0), None);
    }
}
