//! `ember bench accel`: build time, memory, tree shape and ray throughput of every
//! backend this build has (the native builders; Embree robust and fast), per scene
//! and thread count, plus every Embree mode on camera rays. Each row names the Embree
//! of the build that measured it, so the tables of an Embree 3 and an Embree 4 build
//! merge into one ([`AccelBenchReport::merge`], `--append`).

use super::embree_modes::{self, EmbreeModeRow, EmbreeVariantRow};
use super::measure::{make_rays, measure_all, three_digits, Measurement, Repeats, TreeShape};
use super::meshes;
use super::render_calls::{CallRates, RenderCalls};
use super::table::Table;
use super::Report;
use crate::accel::{
    self, AccelBuilder, AccelError, AccelKind, BvhBuilder, EmbreeMode, EmbreeQuality,
};
use crate::scene::collada::{self, LoadError};
use crate::scene::Scene;
use anyhow::Context;
use std::path::{Path, PathBuf};

/// A scene to measure.
#[derive(Clone, Debug, PartialEq)]
pub enum BenchScene {
    File(PathBuf),
    /// [`meshes::displaced_sphere`] with about this many triangles.
    DisplacedSphere(usize),
}

impl BenchScene {
    /// `mesh:N` (N triangles, with an optional k or M suffix: `mesh:250k`) is a
    /// generated displaced sphere; anything else a scene file.
    pub fn parse(s: &str) -> Result<BenchScene, String> {
        let Some(count) = s.strip_prefix("mesh:") else {
            return Ok(BenchScene::File(PathBuf::from(s)));
        };
        let (digits, scale) = match count.strip_suffix(['k', 'K']) {
            Some(d) => (d, 1_000),
            None => match count.strip_suffix('M') {
                Some(d) => (d, 1_000_000),
                None => (count, 1),
            },
        };
        digits
            .parse::<usize>()
            .ok()
            .and_then(|n| n.checked_mul(scale))
            .filter(|&n| (1..=1 << 28).contains(&n))
            .map(BenchScene::DisplacedSphere)
            .ok_or_else(|| {
                format!("{s:?}: expected mesh:N with 1 ≤ N ≤ 2^28 triangles (e.g. mesh:250k)")
            })
    }

    pub fn name(&self) -> String {
        match self {
            BenchScene::File(p) => p.file_stem().map_or_else(
                || p.display().to_string(),
                |s| s.to_string_lossy().into_owned(),
            ),
            BenchScene::DisplacedSphere(n) => format!("displaced sphere ({}k tris)", n / 1000),
        }
    }

    fn load(&self) -> Result<Scene, LoadError> {
        match self {
            BenchScene::File(p) => collada::load(p),
            BenchScene::DisplacedSphere(n) => Ok(meshes::displaced_sphere(*n)),
        }
    }
}

#[derive(Clone, Debug)]
pub struct AccelBenchOptions {
    pub scenes: Vec<BenchScene>,
    /// Incoherent and shadow rays per measurement.
    pub rays: usize,
    /// Camera rays: one per pixel of a `width × height` render of the scene's camera.
    pub width: u32,
    pub height: u32,
    pub threads: Vec<usize>,
    /// Each figure is the median of this many runs.
    pub repeats: usize,
    /// Build quality of the Embree rows of the main table (robust and fast).
    pub embree_quality: EmbreeQuality,
    /// Also measure every Embree mode (scene flags × quality × packet width) on
    /// camera rays, and every way of driving Embree on a render's calls
    /// ([`embree_modes::variants`]), when this build has Embree.
    pub embree_modes: bool,
    pub seed: u64,
}

impl AccelBenchOptions {
    /// CBbunny, CBspheres_lambertian and a ~1M-triangle displaced sphere.
    pub fn default_scenes() -> anyhow::Result<Vec<BenchScene>> {
        let sky = crate::data::scene("cs184/sky")?;
        Ok(vec![
            BenchScene::File(sky.join("CBbunny.dae")),
            BenchScene::File(sky.join("CBspheres_lambertian.dae")),
            BenchScene::DisplacedSphere(1_000_000),
        ])
    }
}

impl Default for AccelBenchOptions {
    fn default() -> Self {
        AccelBenchOptions {
            // Filled by the caller (`default_scenes` needs the data folder).
            scenes: Vec::new(),
            rays: 500_000,
            width: 480,
            height: 360,
            threads: vec![1, 2],
            repeats: 5,
            embree_quality: EmbreeQuality::Medium,
            embree_modes: true,
            seed: 7,
        }
    }
}

/// One backend at one thread count on one scene, measured by one build of ember.
#[derive(Clone, Debug, PartialEq)]
pub struct AccelBenchRow {
    pub scene: String,
    pub prims: usize,
    pub threads: usize,
    /// [`AccelKind`]'s name, e.g. "native SAH" or "Embree medium fast".
    pub backend: String,
    /// `Some` for Embree rows.
    pub embree_mode: Option<EmbreeMode>,
    /// The Embree this build of ember links ("Embree 4.4.0 AVX2"), "none" without one:
    /// tells apart the rows of an Embree 3 and an Embree 4 build in a merged table.
    pub build: String,
    /// Whether `--accel auto` picks this backend for this scene in that build.
    pub auto: bool,
    /// Incoherent (and shadow) rays traced, and how many runs each figure is the median of.
    pub rays: usize,
    pub repeats: usize,
    pub measured: Measurement,
    /// The calls of [`RENDER_TILES`] tiles of a render of the scene as `ember bench
    /// render` makes it, replayed: the same four `Accel` calls, packet for packet.
    pub render: Option<CallRates>,
}

impl AccelBenchRow {
    pub fn is_embree(&self) -> bool {
        self.embree_mode.is_some()
    }

    /// The Embree scene flags of the row ("—" for the native BVH).
    pub fn scene_flags(&self) -> &'static str {
        self.embree_mode.map_or("—", EmbreeMode::scene_flags)
    }
}

/// The main table's rows, the Embree modes rows and the Embree variants rows.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct AccelBenchReport {
    pub rows: Vec<AccelBenchRow>,
    pub modes: Vec<EmbreeModeRow>,
    /// Not read back by [`AccelBenchReport::read`] (`--append` keeps the file's rows
    /// apart: see [`Report::write`]).
    pub variants: Vec<EmbreeVariantRow>,
    /// Set when the run was stopped before its last scene: what it left out.
    pub stopped: Option<String>,
}

/// What [`run`] tells its caller as it goes.
pub enum Progress<'a> {
    /// One measurement done (a backend on a scene at a thread count).
    Line(String),
    /// Every row measured so far, after each scene and thread count: the caller can
    /// write them, so a run that is killed still leaves the rows it finished.
    Rows(&'a AccelBenchReport),
}

/// Below these, a run's figures are too noisy to say where Embree overtakes the
/// native BVH ([`AccelBenchReport::crossover_note`]).
pub const MIN_REPEATS_TO_CONCLUDE: usize = 3;
pub const MIN_RAYS_TO_CONCLUDE: usize = 200_000;

#[derive(Debug, thiserror::Error)]
pub enum BenchError {
    #[error(transparent)]
    Load(#[from] LoadError),
    #[error(transparent)]
    Accel(#[from] AccelError),
    #[error("thread pool: {0}")]
    ThreadPool(#[from] rayon::ThreadPoolBuildError),
}

const HAS_EMBREE: bool = cfg!(any(feature = "embree", feature = "embree4"));

/// The backends of the main table: both native builders, and robust and fast Embree.
fn backends(quality: EmbreeQuality) -> Vec<AccelKind> {
    let mut list = vec![
        AccelKind::Native(BvhBuilder::Midpoint),
        AccelKind::Native(BvhBuilder::Sah),
    ];
    if HAS_EMBREE {
        for robust in [true, false] {
            list.push(AccelKind::Embree(EmbreeMode {
                robust,
                ..EmbreeMode::robust(quality)
            }));
        }
    }
    list
}

/// Runs the whole benchmark; `progress` hears each finished measurement and the rows
/// so far after each scene and thread count. Once `stop` says so (Ctrl-C), the run
/// ends after the measurement under way, with the rows it finished.
pub fn run(
    opts: &AccelBenchOptions,
    mut progress: impl FnMut(Progress<'_>),
    stop: &dyn Fn() -> bool,
) -> Result<AccelBenchReport, BenchError> {
    let mut report = AccelBenchReport::default();
    let repeats = Repeats {
        count: opts.repeats.max(1),
        budget_s: f64::INFINITY,
    };
    for (done, bench_scene) in opts.scenes.iter().enumerate() {
        let scene = bench_scene.load()?;
        let name = bench_scene.name();
        let rays = make_rays(&scene, opts.width, opts.height, opts.rays, opts.seed);
        let calls = render_calls(&scene, opts)?;
        let auto = AccelKind::default().resolve(&scene).kind;
        for &threads in &opts.threads {
            if stop() {
                report.stopped = Some(stopped_note(opts, done, threads));
                return Ok(report);
            }
            let pool = accel::tracing_pool(Some(threads))?;
            let builder = AccelBuilder::new(threads);
            let build = embree_modes::build_label(&builder)?;
            let kinds = backends(opts.embree_quality);
            let measured = measure_all(&scene, &rays, &pool, &builder, &kinds, repeats)?;
            let accels = kinds
                .iter()
                .map(|&k| pool.install(|| builder.build(&scene, k)))
                .collect::<Result<Vec<_>, _>>()?;
            let refs: Vec<&dyn accel::Accel> = accels.iter().map(|a| a.as_ref()).collect();
            let replayed = calls.measure(&refs, &pool, opts.repeats);
            drop(accels);
            for ((kind, m), render) in kinds.into_iter().zip(measured).zip(replayed) {
                let row = AccelBenchRow {
                    scene: name.clone(),
                    prims: scene.num_prims(),
                    threads: pool.current_num_threads(),
                    backend: kind.to_string(),
                    embree_mode: match kind {
                        AccelKind::Embree(m) => Some(m),
                        _ => None,
                    },
                    build: build.clone(),
                    auto: kind == auto,
                    rays: opts.rays,
                    repeats: repeats.count,
                    measured: m,
                    render: Some(render),
                };
                progress(Progress::Line(progress_line(&row)));
                report.rows.push(row);
            }
            if HAS_EMBREE && opts.embree_modes && !stop() {
                let modes = embree_modes::embree_modes(
                    &scene,
                    &name,
                    &rays.camera,
                    &pool,
                    &builder,
                    opts.repeats,
                )?;
                progress(Progress::Line(format!(
                    "{name} / Embree modes / {}: done",
                    crate::names::thread_count(threads)
                )));
                report.modes.extend(modes);
                let variants = embree_modes::embree_variants(
                    &scene,
                    &name,
                    &calls,
                    &pool,
                    &builder,
                    opts.repeats,
                )?;
                progress(Progress::Line(format!(
                    "{name} / Embree variants / {}: done",
                    crate::names::thread_count(threads)
                )));
                report.variants.extend(variants);
            }
            progress(Progress::Rows(&report));
        }
    }
    Ok(report)
}

/// The calls of 24 tiles of a render of `scene` as `ember bench render` makes it (64
/// samples per pixel, `-m 5`) at the camera rays' resolution (seed `opts.seed`).
fn render_calls(scene: &Scene, opts: &AccelBenchOptions) -> Result<RenderCalls, BenchError> {
    let bench = super::render::RenderBenchOptions::default();
    let settings = crate::render::RenderSettings {
        spp: bench.spp,
        max_depth: bench.max_depth,
        strategy: None,
        seed: opts.seed,
        ..Default::default()
    };
    Ok(RenderCalls::record(
        scene.clone(),
        (opts.width, opts.height),
        &settings,
        RENDER_TILES,
    )?)
}

/// Tiles of the render whose calls `ember bench accel` replays.
pub const RENDER_TILES: usize = 24;

/// "CBbunny / native SAH / 1 thread: camera 29.64, incoherent 11.86, shadow 9.21 Mrays/s, build 4.97 ms".
fn progress_line(row: &AccelBenchRow) -> String {
    let m = &row.measured;
    format!(
        "{} / {} / {} thread{}: camera {:.2}, incoherent {:.2}, shadow {:.2} Mrays/s, build {} ms",
        row.scene,
        row.backend,
        row.threads,
        if row.threads == 1 { "" } else { "s" },
        m.camera_mrays,
        m.incoherent_mrays,
        m.shadow_mrays,
        three_digits(m.build_ms)
    )
}

/// What a run stopped at scene `done` of `opts`, before its `threads` measurement, left out.
fn stopped_note(opts: &AccelBenchOptions, done: usize, threads: usize) -> String {
    let left: Vec<String> = opts.scenes[done..].iter().map(BenchScene::name).collect();
    format!(
        "stopped at {} thread(s) of scene {} of {}; not measured from there: {}",
        threads,
        done + 1,
        opts.scenes.len(),
        left.join(", ")
    )
}

const HEADER: [&str; 23] = [
    "scene",
    "prims",
    "threads",
    "backend",
    "scene flags",
    "Embree",
    "build (ms)",
    "memory (MB)",
    "camera (Mrays/s)",
    "incoherent (Mrays/s)",
    "shadow (Mrays/s)",
    "nodes",
    "leaves",
    "depth",
    "SAH cost",
    "auto picks",
    "native/Embree robust (cam / inc / shadow / render)",
    "native/Embree fast (cam / inc / shadow / render)",
    "render calls: intersect (Mrays/s)",
    "render calls: occluded (Mrays/s)",
    "render calls (s)",
    "rays",
    "runs",
];

impl AccelBenchReport {
    /// The main table. The ratio columns are a native row's throughput over the
    /// Embree row of the same build, scene and thread count (robust, then fast).
    pub fn table(&self) -> Table {
        let mut t = Table::new(HEADER);
        for r in &self.rows {
            let m = &r.measured;
            let tree = |f: fn(&TreeShape) -> String| m.tree.as_ref().map_or("—".into(), f);
            let ratio = |robust: bool| {
                self.embree_row(r, robust)
                    .filter(|_| !r.is_embree())
                    .map_or("—".into(), |e| {
                        let render = match (r.render, e.render) {
                            (Some(n), Some(e)) => format!("{:.2}", e.seconds / n.seconds),
                            _ => "—".into(),
                        };
                        let e = &e.measured;
                        format!(
                            "{:.2} / {:.2} / {:.2} / {render}",
                            m.camera_mrays / e.camera_mrays,
                            m.incoherent_mrays / e.incoherent_mrays,
                            m.shadow_mrays / e.shadow_mrays
                        )
                    })
            };
            t.push(vec![
                r.scene.clone(),
                r.prims.to_string(),
                r.threads.to_string(),
                r.backend.clone(),
                r.scene_flags().into(),
                // The Embree a row ran; a native row's build is that of the Embree rows after it.
                if r.is_embree() {
                    r.build.clone()
                } else {
                    String::new()
                },
                three_digits(m.build_ms),
                three_digits(m.memory_mb),
                format!("{:.2}", m.camera_mrays),
                format!("{:.2}", m.incoherent_mrays),
                format!("{:.2}", m.shadow_mrays),
                tree(|t| t.nodes.to_string()),
                tree(|t| t.leaves.to_string()),
                tree(|t| t.depth.to_string()),
                tree(|t| format!("{:.2}", t.sah_cost)),
                if r.auto { "yes" } else { "" }.into(),
                ratio(true),
                ratio(false),
                r.render
                    .map_or("—".into(), |c| format!("{:.2}", c.intersect_mrays)),
                r.render
                    .map_or("—".into(), |c| format!("{:.2}", c.occluded_mrays)),
                r.render.map_or("—".into(), |c| format!("{:.4}", c.seconds)),
                r.rays.to_string(),
                r.repeats.to_string(),
            ]);
        }
        t
    }

    /// Where `--accel auto` should switch, from these rows: the fewest primitives from
    /// which, on every measured scene that large, robust Embree traces both
    /// incoherent and shadow rays faster than the native SAH tree of the same build at
    /// every thread count. `None` when the largest scene still favours the native tree.
    pub fn crossover(&self) -> Option<usize> {
        let embree_ahead = |scene: &str| {
            self.rows
                .iter()
                .filter(|r| r.scene == scene && r.backend == "native SAH")
                .all(|n| {
                    self.embree_row(n, true).is_some_and(|e| {
                        e.measured.incoherent_mrays > n.measured.incoherent_mrays
                            && e.measured.shadow_mrays > n.measured.shadow_mrays
                    })
                })
        };
        let mut scenes: Vec<(usize, bool)> = first_seen(self.rows.iter().map(|r| r.scene.clone()))
            .iter()
            .map(|s| {
                let prims = self
                    .rows
                    .iter()
                    .find(|r| &r.scene == s)
                    .map_or(0, |r| r.prims);
                (prims, embree_ahead(s))
            })
            .collect();
        scenes.sort_by_key(|&(prims, _)| std::cmp::Reverse(prims));
        let mut from = None;
        for (prims, ahead) in scenes {
            if !ahead {
                break;
            }
            from = Some(prims);
        }
        from
    }

    /// One line on [`AccelBenchReport::crossover`] against the crossover `--accel auto`
    /// uses; none from a run too small to tell (fewer than [`MIN_REPEATS_TO_CONCLUDE`]
    /// runs or [`MIN_RAYS_TO_CONCLUDE`] rays per figure), or without Embree rows.
    pub fn crossover_note(&self) -> String {
        let repeats = self.rows.iter().map(|r| r.repeats).min().unwrap_or(0);
        let rays = self.rows.iter().map(|r| r.rays).min().unwrap_or(0);
        if repeats < MIN_REPEATS_TO_CONCLUDE || rays < MIN_RAYS_TO_CONCLUDE {
            return format!(
                "Too small a run to say where Embree overtakes the native BVH ({repeats} run{} of {rays} rays per figure; \
                 that needs --repeats {MIN_REPEATS_TO_CONCLUDE} and --rays {MIN_RAYS_TO_CONCLUDE} or more).",
                if repeats == 1 { "" } else { "s" }
            );
        }
        if !self.rows.iter().any(AccelBenchRow::is_embree) {
            return "No Embree rows (this build has no Embree), so no crossover to measure.".into();
        }
        let now = match accel::AUTO_EMBREE_MIN_PRIMS {
            Some(p) => format!("--accel auto switches at {p}"),
            None => "--accel auto never switches to Embree".to_string(),
        };
        match self.crossover() {
            Some(p) => format!(
                "Robust Embree is ahead of native SAH (incoherent and shadow rays, every thread count) \
                 on every measured scene from {p} primitives up; {now}."
            ),
            None => format!(
                "Native SAH keeps up with robust Embree on the largest measured scene \
                 (incoherent or shadow rays); {now}."
            ),
        }
    }

    fn embree_row(&self, r: &AccelBenchRow, robust: bool) -> Option<&AccelBenchRow> {
        self.rows.iter().find(|e| {
            e.embree_mode.is_some_and(|m| m.robust == robust)
                && e.scene == r.scene
                && e.threads == r.threads
                && e.build == r.build
        })
    }

    pub fn modes_table(&self) -> Table {
        embree_modes::table(&self.modes)
    }

    /// Reads back the rows of a main table written by [`AccelBenchReport::table`] (its
    /// CSV); the ratio columns are recomputed, not read. A native row's build is that of
    /// the first Embree row after it of the same scene and thread count ("none" without).
    pub fn rows_from_table(t: &Table) -> Result<Vec<AccelBenchRow>, String> {
        if t.header != HEADER {
            return Err(format!(
                "not a bench accel table of this version of ember: header {:?}",
                t.header
            ));
        }
        let mut rows: Vec<AccelBenchRow> = t
            .rows
            .iter()
            .map(|c| row_from_cells(c))
            .collect::<Result<_, _>>()?;
        for i in 0..rows.len() {
            if !rows[i].is_embree() {
                let same = |e: &&AccelBenchRow| {
                    e.is_embree() && e.scene == rows[i].scene && e.threads == rows[i].threads
                };
                rows[i].build = rows[i + 1..]
                    .iter()
                    .find(same)
                    .map_or("none".into(), |e| e.build.clone());
            }
        }
        Ok(rows)
    }

    /// `other`'s rows after this report's, grouped by scene (in first-seen order) and
    /// thread count, so the rows of two builds sit together.
    pub fn merge(mut self, other: AccelBenchReport) -> AccelBenchReport {
        self.rows.extend(other.rows);
        self.modes.extend(other.modes);
        self.variants.extend(other.variants);
        self.stopped = self.stopped.or(other.stopped);
        let scenes = first_seen(self.rows.iter().map(|r| r.scene.clone()));
        let rank = |s: &str| scenes.iter().position(|x| x == s);
        self.rows.sort_by_key(|r| (rank(&r.scene), r.threads));
        self.modes.sort_by_key(|r| (rank(&r.scene), r.threads));
        self.variants.sort_by_key(|r| (rank(&r.scene), r.threads));
        self
    }

    /// What [`Report::write`] left in `out_dir` (no modes when that file is absent).
    pub fn read(out_dir: &Path) -> anyhow::Result<AccelBenchReport> {
        let main = out_dir.join("accel.csv");
        let text = std::fs::read_to_string(&main)
            .with_context(|| format!("{}: cannot read", main.display()))?;
        let rows = Table::from_csv(&text)
            .and_then(|t| Self::rows_from_table(&t))
            .map_err(|e| anyhow::anyhow!("{}: {e}", main.display()))?;
        let modes = read_optional(
            &out_dir.join("embree_modes.csv"),
            embree_modes::rows_from_table,
        )?;
        let variants = read_optional(
            &out_dir.join("embree_variants.csv"),
            embree_modes::variant_rows_from_table,
        )?;
        Ok(AccelBenchReport {
            rows,
            modes,
            variants,
            stopped: None,
        })
    }
}

/// The rows of the table at `path`, none when the file does not exist.
fn read_optional<R>(
    path: &Path,
    rows: fn(&Table) -> Result<Vec<R>, String>,
) -> anyhow::Result<Vec<R>> {
    match std::fs::read_to_string(path) {
        Ok(text) => Table::from_csv(&text)
            .and_then(|t| rows(&t))
            .map_err(|e| anyhow::anyhow!("{}: {e}", path.display())),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(Vec::new()),
        Err(e) => Err(anyhow::anyhow!("{}: cannot read: {e}", path.display())),
    }
}

fn first_seen(items: impl Iterator<Item = String>) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    for s in items {
        if !out.contains(&s) {
            out.push(s);
        }
    }
    out
}

fn row_from_cells(c: &[String]) -> Result<AccelBenchRow, String> {
    let num = |i: usize| {
        c[i].parse::<f64>()
            .map_err(|_| format!("{}: not a number: {:?}", HEADER[i], c[i]))
    };
    let count = |i: usize| {
        c[i].parse::<usize>()
            .map_err(|_| format!("{}: not a count: {:?}", HEADER[i], c[i]))
    };
    let embree_mode = match c[3].strip_prefix("Embree ") {
        None => None,
        Some(mode) => {
            let quality = EmbreeQuality::ALL
                .into_iter()
                .find(|q| mode.starts_with(&q.to_string()))
                .ok_or_else(|| format!("unknown Embree backend {:?}", c[3]))?;
            Some(EmbreeMode {
                robust: c[4] == "ROBUST",
                ..EmbreeMode::robust(quality)
            })
        }
    };
    let tree = if c[11] == "—" {
        None
    } else {
        Some(TreeShape {
            nodes: count(11)?,
            leaves: count(12)?,
            depth: count(13)?,
            sah_cost: num(14)?,
        })
    };
    let render = if c[18] == "—" {
        None
    } else {
        Some(CallRates {
            intersect_mrays: num(18)?,
            occluded_mrays: num(19)?,
            seconds: num(20)?,
        })
    };
    Ok(AccelBenchRow {
        scene: c[0].clone(),
        prims: count(1)?,
        threads: count(2)?,
        backend: c[3].clone(),
        embree_mode,
        build: c[5].clone(),
        auto: c[15] == "yes",
        rays: count(21)?,
        repeats: count(22)?,
        measured: Measurement {
            build_ms: num(6)?,
            memory_mb: num(7)?,
            camera_mrays: num(8)?,
            incoherent_mrays: num(9)?,
            shadow_mrays: num(10)?,
            tree,
        },
        render,
    })
}

impl Report for AccelBenchReport {
    /// `accel.csv`/`.md`, and `embree_modes.csv`/`.md` and `embree_variants.csv`/`.md`
    /// when there are such rows.
    fn write(&self, out_dir: &Path) -> anyhow::Result<Vec<PathBuf>> {
        super::create_out_dir(out_dir)?;
        let mut stems = vec![out_dir.join("accel")];
        self.table().write(&stems[0])?;
        if !self.modes.is_empty() {
            stems.push(out_dir.join("embree_modes"));
            self.modes_table().write(stems.last().expect("pushed"))?;
        }
        if !self.variants.is_empty() {
            stems.push(out_dir.join("embree_variants"));
            embree_modes::variants_table(&self.variants).write(stems.last().expect("pushed"))?;
        }
        Ok(stems
            .iter()
            .flat_map(|s| [s.with_extension("csv"), s.with_extension("md")])
            .collect())
    }

    fn summary(&self) -> String {
        let mut out = self.table().to_markdown();
        if !self.modes.is_empty() {
            out += "\n";
            out += &self.modes_table().to_markdown();
        }
        if !self.variants.is_empty() {
            out += "\n";
            out += &embree_modes::variants_table(&self.variants).to_markdown();
        }
        out += "\n";
        if let Some(s) = &self.stopped {
            out += &format!("Interrupted: {s}.\n");
        }
        out + &self.crossover_note() + "\n"
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(backend: AccelKind, build: &str, mrays: f64) -> AccelBenchRow {
        AccelBenchRow {
            scene: "s".into(),
            prims: 1,
            threads: 1,
            backend: backend.to_string(),
            embree_mode: match backend {
                AccelKind::Embree(m) => Some(m),
                _ => None,
            },
            build: build.into(),
            auto: false,
            rays: 500_000,
            repeats: 5,
            measured: Measurement {
                build_ms: 1.0,
                memory_mb: 1.5,
                camera_mrays: mrays,
                incoherent_mrays: mrays,
                shadow_mrays: mrays,
                tree: matches!(backend, AccelKind::Native(_)).then_some(TreeShape {
                    nodes: 3,
                    leaves: 9,
                    depth: 2,
                    sah_cost: 4.25,
                }),
            },
            render: Some(CallRates {
                intersect_mrays: mrays,
                occluded_mrays: mrays,
                seconds: 2.5 / mrays,
            }),
        }
    }

    const SAH: AccelKind = AccelKind::Native(BvhBuilder::Sah);
    const FAST: AccelKind = AccelKind::Embree(EmbreeMode::fast(EmbreeQuality::Medium));

    #[test]
    fn ratios_are_native_over_embree_of_the_same_build() {
        let e3 = "Embree 3.13.5 (AVX2, native ray packets of 8)";
        let e4 = "Embree 4.4.0 (AVX2, native ray packets of 8)";
        let first = AccelBenchReport {
            rows: vec![
                row(SAH, e3, 5.0),
                row(AccelKind::embree(EmbreeQuality::Medium), e3, 10.0),
                row(FAST, e3, 20.0),
            ],
            modes: vec![],
            variants: vec![],
            stopped: None,
        };
        let second = AccelBenchReport {
            rows: vec![
                row(SAH, e4, 6.0),
                row(AccelKind::embree(EmbreeQuality::Medium), e4, 3.0),
            ],
            modes: vec![],
            variants: vec![],
            stopped: None,
        };
        let md = first.merge(second).table().to_markdown();
        assert!(
            md.contains("| 0.50 / 0.50 / 0.50 / 0.50 | 0.25 / 0.25 / 0.25 / 0.25 |"),
            "{md}"
        );
        assert!(md.contains("| 2.00 / 2.00 / 2.00 / 2.00 | — |"), "{md}");
        assert!(
            md.contains("| Embree medium fast | NONE | Embree 3.13.5"),
            "{md}"
        );
        assert!(md.contains("| 3 | 9 | 2 | 4.25 |"), "{md}");
        assert_eq!(md.lines().count(), 2 + 5);
        // Native rows name no Embree; every row has the header's cells.
        assert!(md.contains("| native SAH | — |  | 1.00 |"), "{md}");
        let counts = crate::bench::table::markdown_cell_counts(&md);
        assert!(counts.iter().all(|&n| n == HEADER.len()), "{counts:?}");
    }

    #[test]
    fn a_small_run_draws_no_conclusion() {
        let small = |repeats, rays| AccelBenchReport {
            rows: vec![
                AccelBenchRow {
                    repeats,
                    rays,
                    ..row(SAH, "e", 2.0)
                },
                row(AccelKind::embree(EmbreeQuality::Medium), "e", 1.0),
            ],
            modes: vec![],
            variants: vec![],
            stopped: None,
        };
        for (repeats, rays) in [(1, 500_000), (5, 50_000)] {
            let note = small(repeats, rays).crossover_note();
            assert!(note.starts_with("Too small a run"), "{note}");
        }
        assert!(small(3, 200_000)
            .crossover_note()
            .starts_with("Native SAH keeps up"));
    }

    #[test]
    fn crossover_is_where_embree_stays_ahead() {
        let at = |scene: &str, prims, kind: AccelKind, mrays| AccelBenchRow {
            scene: scene.into(),
            prims,
            ..row(kind, "e", mrays)
        };
        let robust = AccelKind::embree(EmbreeQuality::Medium);
        let rows = |sizes: &[(usize, f64)]| AccelBenchReport {
            rows: sizes
                .iter()
                .flat_map(|&(p, native)| {
                    let name = p.to_string();
                    [at(&name, p, SAH, native), at(&name, p, robust, 1.0)]
                })
                .collect(),
            modes: vec![],
            variants: vec![],
            stopped: None,
        };
        // Native ahead at 10, behind at 100 and 1000, ahead again at 50 (noise).
        let r = rows(&[(10, 2.0), (50, 1.5), (100, 0.5), (1000, 0.5)]);
        assert_eq!(r.crossover(), Some(100));
        assert!(r.crossover_note().contains("from 100 primitives up"));
        assert_eq!(rows(&[(10, 0.5), (1000, 1.5)]).crossover(), None);
        assert_eq!(rows(&[(10, 0.5), (1000, 0.5)]).crossover(), Some(10));
    }

    #[test]
    fn the_csv_reads_back_into_the_same_rows() {
        let mut fast = row(FAST, "Embree 4.4.0 (AVX2, x)", 7.25);
        fast.render = Some(CallRates {
            intersect_mrays: 7.25,
            occluded_mrays: 3.5,
            seconds: 0.125,
        });
        let report = AccelBenchReport {
            rows: vec![row(SAH, "none", 5.0), fast],
            modes: vec![],
            variants: vec![],
            stopped: None,
        };
        let t = Table::from_csv(&report.table().to_csv()).expect("csv");
        // The native row's build is read from the Embree row after it.
        let mut want = report.rows.clone();
        want[0].build = want[1].build.clone();
        assert_eq!(AccelBenchReport::rows_from_table(&t), Ok(want));
        let alone = AccelBenchReport {
            rows: vec![row(SAH, "none", 5.0)],
            ..report.clone()
        };
        let t = Table::from_csv(&alone.table().to_csv()).expect("csv");
        assert_eq!(AccelBenchReport::rows_from_table(&t), Ok(alone.rows));
        let mut bad = t.clone();
        bad.rows[0][8] = "fast".into();
        assert!(AccelBenchReport::rows_from_table(&bad)
            .unwrap_err()
            .contains("camera"));
    }

    #[test]
    fn merge_groups_rows_by_scene_then_threads() {
        let at = |scene: &str, threads, build: &str| AccelBenchRow {
            scene: scene.into(),
            threads,
            ..row(SAH, build, 1.0)
        };
        let a = AccelBenchReport {
            rows: vec![at("x", 1, "3"), at("x", 2, "3"), at("y", 1, "3")],
            modes: vec![],
            variants: vec![],
            stopped: None,
        };
        let b = AccelBenchReport {
            rows: vec![at("x", 1, "4"), at("x", 2, "4"), at("y", 1, "4")],
            modes: vec![],
            variants: vec![],
            stopped: None,
        };
        let order: Vec<(String, usize, String)> = a
            .merge(b)
            .rows
            .into_iter()
            .map(|r| (r.scene, r.threads, r.build))
            .collect();
        let want = [
            ("x", 1, "3"),
            ("x", 1, "4"),
            ("x", 2, "3"),
            ("x", 2, "4"),
            ("y", 1, "3"),
            ("y", 1, "4"),
        ];
        assert_eq!(
            order,
            want.map(|(s, t, b)| (s.to_string(), t, b.to_string()))
        );
    }

    #[test]
    fn scenes_parse_as_files_or_generated_meshes() {
        assert_eq!(
            BenchScene::parse("mesh:250k"),
            Ok(BenchScene::DisplacedSphere(250_000))
        );
        assert_eq!(
            BenchScene::parse("mesh:2M"),
            Ok(BenchScene::DisplacedSphere(2_000_000))
        );
        assert_eq!(
            BenchScene::parse("mesh:5000"),
            Ok(BenchScene::DisplacedSphere(5_000))
        );
        assert_eq!(
            BenchScene::parse("a/b.dae"),
            Ok(BenchScene::File("a/b.dae".into()))
        );
        for bad in ["mesh:", "mesh:0", "mesh:x", "mesh:-3", "mesh:999999M"] {
            assert!(BenchScene::parse(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn a_small_run_measures_every_backend_and_mode() {
        let opts = AccelBenchOptions {
            scenes: vec![BenchScene::DisplacedSphere(2_000)],
            rays: 1_000,
            width: 16,
            height: 12,
            threads: vec![1],
            repeats: 1,
            ..Default::default()
        };
        let mut lines = 0;
        let report = run(
            &opts,
            |p| lines += matches!(p, Progress::Line(l) if l.contains("camera ")) as usize,
            &|| false,
        )
        .expect("runs");
        assert!(lines >= 2, "progress lines name the ray types");
        assert!(report.stopped.is_none());
        let stopped = run(&opts, |_| {}, &|| true).expect("runs");
        assert!(stopped.rows.is_empty() && stopped.stopped.is_some());
        let embree_rows = if HAS_EMBREE { 2 } else { 0 };
        assert_eq!(report.rows.len(), 2 + embree_rows);
        assert_eq!(report.modes.len(), if HAS_EMBREE { 24 } else { 0 });
        assert_eq!(report.variants.is_empty(), !HAS_EMBREE);
        assert!(report.rows.iter().all(|r| r.render.is_some()));
        // Auto picks the native SAH tree for 2k triangles.
        let auto: Vec<&str> = report
            .rows
            .iter()
            .filter(|r| r.auto)
            .map(|r| r.backend.as_str())
            .collect();
        assert_eq!(auto, ["native SAH"]);
        for r in &report.rows {
            assert_eq!(r.is_embree(), r.measured.tree.is_none(), "{}", r.backend);
            assert!(r.measured.incoherent_mrays > 0.0 && r.measured.memory_mb > 0.0);
        }
    }
}
