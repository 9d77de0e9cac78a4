//! `ember bench render`: samples per second of whole renders (load, build and render
//! timed apart), the median of several repetitions per scene, engine and backend. All
//! the runs of a scene are made in turn within each repetition (every engine through
//! every backend), so a drift of the machine's speed weighs on them alike and the
//! native and Embree rows of one table compare the backends on the same renders.

use super::table::Table;
use super::{create_out_dir, Report};
use crate::accel::{AccelKind, Backend, BvhBuilder, EmbreeQuality};
use crate::lanes::InstructionSet;
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
    /// Backends to compare, each a row per engine ([`RenderBenchOptions::accels_for`]).
    pub accels: Vec<AccelKind>,
    /// Engines to compare, each a row per backend.
    pub engines: Vec<Engine>,
    /// Instruction sets to compare (the packets' and the node tests'), each a row per
    /// engine and backend; the set is capped for each render in turn
    /// (`lanes::limit_instruction_set`) and the cap put back after.
    pub instruction_sets: Vec<InstructionSet>,
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

    /// The backends `--accel` names: `auto` compares the native SAH tree with Embree
    /// (its default mode, what `--accel embree` renders with) in builds that have it.
    /// `embree_steps` adds, after the native tree, every way of driving Embree that
    /// `ember bench accel`'s variants table marks for whole renders (issue 27's steps).
    pub fn accels_for(backend: Backend, embree_steps: bool) -> Vec<AccelKind> {
        let native = AccelKind::Native(BvhBuilder::Sah);
        let embree = AccelKind::embree(EmbreeQuality::default());
        let mut list = match backend {
            Backend::Native => vec![native],
            Backend::Embree => vec![embree],
            Backend::None => vec![AccelKind::None],
            Backend::Auto if Backend::Embree.available() => vec![native, embree],
            Backend::Auto => vec![native],
        };
        if embree_steps {
            for kind in super::embree_modes::render_steps() {
                if !list.contains(&kind) {
                    list.push(kind);
                }
            }
        }
        list
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
            accels: RenderBenchOptions::accels_for(Backend::Auto, false),
            engines: vec![Engine::Auto, Engine::Scalar],
            instruction_sets: vec![crate::lanes::instruction_set()],
        }
    }
}

/// The image size of every measured render.
pub const WIDTH: u32 = 480;
pub const HEIGHT: u32 = 360;

/// The median run of one scene, engine and backend (seconds).
#[derive(Clone, Debug)]
pub struct RenderBenchRow {
    pub scene: String,
    /// The engine asked for, and what ran ("packets (AVX-512)", "scalar").
    pub engine: Engine,
    pub ran: String,
    /// The instruction set the render was capped at.
    pub instruction_set: InstructionSet,
    /// The backend asked for, and its full name as built (Embree's version, ISA and
    /// mode: the variant measured).
    pub accel: AccelKind,
    pub backend: String,
    pub threads: usize,
    pub spp: u32,
    pub max_depth: u32,
    pub render_s: f64,
    /// The median of the renders' CPU seconds (all threads).
    pub cpu_s: f64,
    pub load_s: f64,
    pub build_s: f64,
    pub samples: u64,
}

impl RenderBenchRow {
    /// Render-only samples per second.
    pub fn samples_per_s(&self) -> f64 {
        self.samples as f64 / self.render_s
    }
}

pub struct RenderBenchReport {
    pub rows: Vec<RenderBenchRow>,
}

/// Renders on the current rayon pool (its thread count is each row's).
pub fn run(opts: &RenderBenchOptions) -> Result<RenderBenchReport> {
    let mut rows = Vec::new();
    for p in &opts.scenes {
        rows.extend(measure(p, opts)?);
    }
    Ok(RenderBenchReport { rows })
}

/// One run: render, load and build seconds, samples, what ran, the backend's name,
/// and the process's CPU seconds during the render.
type Run = (f64, f64, f64, u64, String, String, f64);

/// CPU seconds (user and system) this process has used so far: unlike the wall time,
/// it does not grow when other processes take the cores, so two renders' CPU times
/// compare on a busy machine too.
fn cpu_seconds() -> f64 {
    // SAFETY: getrusage only writes the struct it is given.
    let mut u: libc::rusage = unsafe { std::mem::zeroed() };
    if unsafe { libc::getrusage(libc::RUSAGE_SELF, &mut u) } != 0 {
        return f64::NAN;
    }
    let secs = |t: libc::timeval| t.tv_sec as f64 + t.tv_usec as f64 * 1e-6;
    secs(u.ru_utime) + secs(u.ru_stime)
}

/// One row per engine and backend for the scene at `path`.
fn measure(path: &Path, opts: &RenderBenchOptions) -> Result<Vec<RenderBenchRow>> {
    let base = RenderSettings {
        spp: opts.spp,
        max_depth: opts.max_depth,
        strategy: None,
        ..Default::default()
    };
    let cases: Vec<(Engine, InstructionSet, AccelKind)> = (opts.engines.iter())
        .flat_map(|&e| opts.instruction_sets.iter().map(move |&i| (e, i)))
        .flat_map(|(e, i)| opts.accels.iter().map(move |&a| (e, i, a)))
        .collect();
    let mut runs: Vec<Vec<Run>> = vec![Vec::new(); cases.len()];
    let cap = crate::lanes::instruction_set_limit();
    let measured = (|| {
        for _ in 0..opts.repeat.max(1) {
            for (k, &(engine, set, accel)) in cases.iter().enumerate() {
                crate::lanes::limit_instruction_set(set);
                runs[k].push(render_once(path, &base, engine, accel)?);
            }
        }
        Ok::<_, anyhow::Error>(())
    })();
    crate::lanes::limit_instruction_set(cap);
    measured?;
    let scene = path
        .file_name()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let threads = rayon::current_num_threads();
    Ok(runs
        .into_iter()
        .zip(cases)
        .map(|(mut runs, (engine, instruction_set, accel))| {
            let mut cpu: Vec<f64> = runs.iter().map(|r| r.6).collect();
            let cpu_s = super::median(&mut cpu);
            runs.sort_by(|a, b| a.0.total_cmp(&b.0));
            let (render_s, load_s, build_s, samples, ran, backend, _) =
                runs.swap_remove(runs.len() / 2);
            RenderBenchRow {
                scene: scene.clone(),
                engine,
                ran,
                instruction_set,
                accel,
                backend,
                threads,
                spp: opts.spp,
                max_depth: opts.max_depth,
                render_s,
                cpu_s,
                load_s,
                build_s,
                samples,
            }
        })
        .collect())
}

/// One load, build and render of the scene at `path` with `engine` and `accel`.
fn render_once(
    path: &Path,
    base: &RenderSettings,
    engine: Engine,
    accel: AccelKind,
) -> Result<Run> {
    let settings = RenderSettings {
        engine,
        ..base.clone()
    };
    let t0 = Instant::now();
    let scene = collada::load(path)?;
    let load_s = t0.elapsed().as_secs_f64();
    let t1 = Instant::now();
    // A device per build, as a render makes it (with Embree 4's TBB, a scene of
    // Embree's own spheres leaves a worker yielding in a loop for as long as its
    // device lives: it must not outlive its own render).
    let job = RenderJob::new(scene, accel, WIDTH, HEIGHT)?;
    let build_s = t1.elapsed().as_secs_f64();
    let ran = if settings.uses_packets() {
        format!("packets ({})", crate::lanes::instruction_set())
    } else {
        "scalar".into()
    };
    let (t2, cpu) = (Instant::now(), cpu_seconds());
    let out = job.render(&settings);
    let render_s = t2.elapsed().as_secs_f64();
    let cpu_s = cpu_seconds() - cpu;
    let samples = out.total_samples();
    Ok((
        render_s,
        load_s,
        build_s,
        samples,
        ran,
        job.accel.name(),
        cpu_s,
    ))
}

impl RenderBenchReport {
    /// One line per scene, engine, instruction set and backend; "÷ native" is a row's
    /// render-only samples/s over the native row's of the same scene, engine and
    /// instruction set, by wall time and by CPU time (the figure to read on a machine
    /// other work keeps busy).
    pub fn table(&self) -> Table {
        let mut t = Table::new([
            "scene",
            "resolution",
            "threads",
            "engine",
            "instruction set",
            "backend",
            "Embree variant",
            "spp",
            "-m",
            "render-only M samples/s",
            "÷ native",
            "÷ native (CPU time)",
            "incl. load+build M samples/s",
            "render s",
            "render CPU s",
            "load ms",
            "build ms",
        ]);
        for r in &self.rows {
            let n = r.samples as f64;
            let native = self.rows.iter().find(|o| {
                o.scene == r.scene
                    && o.engine == r.engine
                    && o.instruction_set == r.instruction_set
                    && matches!(o.accel, AccelKind::Native(BvhBuilder::Sah))
            });
            t.push(vec![
                r.scene.clone(),
                format!("{WIDTH}×{HEIGHT}"),
                r.threads.to_string(),
                format!("{} → {}", r.engine, r.ran),
                r.instruction_set.to_string(),
                r.backend.clone(),
                embree_variant(r.accel),
                r.spp.to_string(),
                r.max_depth.to_string(),
                format!("{:.2}", r.samples_per_s() / 1e6),
                native.map_or("—".into(), |o| {
                    format!("{:.2}", r.samples_per_s() / o.samples_per_s())
                }),
                native.map_or("—".into(), |o| {
                    let per_cpu = |r: &RenderBenchRow| r.samples as f64 / r.cpu_s;
                    format!("{:.2}", per_cpu(r) / per_cpu(o))
                }),
                format!("{:.2}", n / (r.render_s + r.load_s + r.build_s) / 1e6),
                format!("{:.3}", r.render_s),
                format!("{:.3}", r.cpu_s),
                format!("{:.1}", r.load_s * 1e3),
                format!("{:.1}", r.build_s * 1e3),
            ]);
        }
        t
    }
}

/// How an Embree row drove Embree, in full even for the default ("medium robust:
/// packet8 queries, retry self-hits, ember spheres"); "—" for other backends.
fn embree_variant(accel: AccelKind) -> String {
    match accel {
        AccelKind::Embree(m) => format!(
            "{} {}: {}",
            m.quality,
            if m.robust { "robust" } else { "fast" },
            m.driving()
        ),
        _ => "—".into(),
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

#[cfg(test)]
mod tests {
    use super::*;

    fn row(accel: AccelKind, samples_per_s: f64) -> RenderBenchRow {
        RenderBenchRow {
            scene: "s.dae".into(),
            engine: Engine::Auto,
            ran: "packets (AVX2)".into(),
            instruction_set: InstructionSet::Avx2,
            accel,
            backend: match accel {
                AccelKind::Embree(_) => {
                    "Embree 4.4.0 (AVX2, native ray packets of 8) (medium robust)".into()
                }
                _ => "native BVH (binned SAH)".into(),
            },
            threads: 2,
            spp: 64,
            max_depth: 5,
            render_s: 1.0,
            cpu_s: 2.0,
            load_s: 0.0,
            build_s: 0.0,
            samples: samples_per_s as u64,
        }
    }

    #[test]
    fn embree_rows_name_their_variant_and_compare_with_native() {
        let report = RenderBenchReport {
            rows: vec![
                row(AccelKind::Native(BvhBuilder::Sah), 10e6),
                row(AccelKind::embree(EmbreeQuality::Medium), 9e6),
            ],
        };
        let md = report.table().to_markdown();
        assert!(md.contains("| s.dae | 480×360 | 2 | auto → packets (AVX2) | AVX2 | native BVH (binned SAH) | — | 64 | 5 | 10.00 | 1.00 |"), "{md}");
        assert!(
            md.contains(
                "(medium robust) | medium robust: packet8 queries, retry self-hits, ember spheres | 64 | 5 | 9.00 | 0.90 |"
            ),
            "{md}"
        );
    }

    /// (With Embree, auto adds it: tests/embree_backend.rs, which scripts/test runs in
    /// the Embree builds.)
    #[cfg(not(any(feature = "embree", feature = "embree4")))]
    #[test]
    fn auto_is_the_native_bvh_alone_without_embree() {
        assert_eq!(
            RenderBenchOptions::accels_for(Backend::Auto, false),
            [AccelKind::Native(BvhBuilder::Sah)]
        );
        assert_eq!(
            RenderBenchOptions::accels_for(Backend::Embree, false),
            [AccelKind::embree(EmbreeQuality::Medium)]
        );
    }
}
