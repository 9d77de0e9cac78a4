//! `ember bench render`: samples per second of whole renders (load, build and render
//! timed apart), the median of several repetitions per scene and engine; the engines
//! of a scene are measured in turn within each repetition, so a drift of the
//! machine's speed weighs on them alike.

use super::table::Table;
use super::{create_out_dir, Report};
use crate::accel::{AccelKind, BvhBuilder};
use crate::render::{Engine, RenderJob, RenderSettings};
use crate::scene::collada;
use anyhow::Result;
use std::path::{Path, PathBuf};
use std::time::Instant;

#[derive(Clone, Debug)]
pub struct RenderBenchOptions {
    pub scenes: Vec<PathBuf>,
    pub spp: u32,
    pub max_depth: u32,
    /// Repetitions per scene; the median render is reported.
    pub repeat: u32,
    pub accel: AccelKind,
    /// Engines to compare, each a row.
    pub engines: Vec<Engine>,
}

impl RenderBenchOptions {
    /// The default scenes: CBspheres_lambertian and CBbunny of the course's scenes.
    pub fn default_scenes() -> Result<Vec<PathBuf>> {
        let root = crate::data::scene("cs184/sky")?;
        Ok(vec![
            root.join("CBspheres_lambertian.dae"),
            root.join("CBbunny.dae"),
        ])
    }
}

impl Default for RenderBenchOptions {
    fn default() -> Self {
        RenderBenchOptions {
            // Filled by the caller (`default_scenes` needs the data folder).
            scenes: Vec::new(),
            spp: 64,
            max_depth: 5,
            repeat: 3,
            accel: AccelKind::Native(BvhBuilder::Sah),
            engines: vec![Engine::Auto, Engine::Scalar],
        }
    }
}

/// The image size of every measured render.
pub const WIDTH: u32 = 480;
pub const HEIGHT: u32 = 360;

/// The median run of one scene (seconds).
#[derive(Clone, Debug)]
pub struct RenderBenchRow {
    pub scene: String,
    /// The engine asked for, and what ran ("packets (AVX-512)", "scalar").
    pub engine: Engine,
    pub ran: String,
    pub spp: u32,
    pub max_depth: u32,
    pub render_s: f64,
    pub load_s: f64,
    pub build_s: f64,
    pub samples: u64,
}

pub struct RenderBenchReport {
    pub rows: Vec<RenderBenchRow>,
}

pub fn run(opts: &RenderBenchOptions) -> Result<RenderBenchReport> {
    let mut rows = Vec::new();
    for p in &opts.scenes {
        rows.extend(measure(p, opts)?);
    }
    Ok(RenderBenchReport { rows })
}

/// One row per engine for the scene at `path`.
fn measure(path: &Path, opts: &RenderBenchOptions) -> Result<Vec<RenderBenchRow>> {
    let base = RenderSettings {
        spp: opts.spp,
        max_depth: opts.max_depth,
        strategy: None,
        ..Default::default()
    };
    let mut runs = vec![Vec::new(); opts.engines.len()];
    let mut ran = vec![String::new(); opts.engines.len()];
    for _ in 0..opts.repeat.max(1) {
        for (k, &engine) in opts.engines.iter().enumerate() {
            let settings = RenderSettings {
                engine,
                ..base.clone()
            };
            let t0 = Instant::now();
            let scene = collada::load(path)?;
            let load_s = t0.elapsed().as_secs_f64();
            let t1 = Instant::now();
            let job = RenderJob::new(scene, opts.accel, WIDTH, HEIGHT)?;
            let build_s = t1.elapsed().as_secs_f64();
            ran[k] = if settings.uses_packets(&job) {
                format!("packets ({})", crate::lanes::instruction_set())
            } else {
                "scalar".into()
            };
            let t2 = Instant::now();
            let out = job.render(&settings);
            let render_s = t2.elapsed().as_secs_f64();
            runs[k].push((render_s, load_s, build_s, out.total_samples()));
        }
    }
    let scene = path
        .file_name()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let rows = runs.into_iter().zip(ran).zip(&opts.engines);
    Ok(rows
        .map(|((mut runs, ran), &engine)| {
            runs.sort_by(|a, b| a.0.total_cmp(&b.0));
            let (render_s, load_s, build_s, samples) = runs[runs.len() / 2];
            RenderBenchRow {
                scene: scene.clone(),
                engine,
                ran,
                spp: opts.spp,
                max_depth: opts.max_depth,
                render_s,
                load_s,
                build_s,
                samples,
            }
        })
        .collect())
}

impl RenderBenchReport {
    pub fn table(&self) -> Table {
        let mut t = Table::new([
            "scene",
            "engine",
            "spp",
            "-m",
            "render-only M samples/s",
            "incl. load+build M samples/s",
            "render s",
            "load ms",
            "build ms",
        ]);
        for r in &self.rows {
            let n = r.samples as f64;
            t.push(vec![
                r.scene.clone(),
                format!("{} → {}", r.engine, r.ran),
                r.spp.to_string(),
                r.max_depth.to_string(),
                format!("{:.2}", n / r.render_s / 1e6),
                format!("{:.2}", n / (r.render_s + r.load_s + r.build_s) / 1e6),
                format!("{:.3}", r.render_s),
                format!("{:.1}", r.load_s * 1e3),
                format!("{:.1}", r.build_s * 1e3),
            ]);
        }
        t
    }
}

impl Report for RenderBenchReport {
    /// `<out_dir>/render.csv` and `render.md`.
    fn write(&self, out_dir: &Path) -> Result<Vec<PathBuf>> {
        create_out_dir(out_dir)?;
        let stem = out_dir.join("render");
        self.table().write(&stem)?;
        Ok(vec![stem.with_extension("csv"), stem.with_extension("md")])
    }

    fn summary(&self) -> String {
        self.table().to_markdown()
    }
}
