//! `ember bench accel`: build time, memory and ray throughput of every backend this
//! build has, per scene and thread count, as data plus a Markdown table.

use super::measure::{make_rays, measure, tracing_pool, Backend, Builder, Measurement, Repeats};
use super::meshes;
use crate::accel::{AccelError, BvhBuilder, EmbreeQuality};
use crate::scene::collada::{self, LoadError};
use crate::scene::Scene;
use std::fmt::Write as _;
use std::path::PathBuf;

/// A scene to measure.
#[derive(Clone, Debug, PartialEq)]
pub enum BenchScene {
    File(PathBuf),
    /// [`meshes::displaced_sphere`] with about this many triangles.
    DisplacedSphere(usize),
}

impl BenchScene {
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
    /// Incoherent and shadow rays per measurement (camera rays are `width × height`).
    pub rays: usize,
    pub width: u32,
    pub height: u32,
    pub threads: Vec<usize>,
    /// Each figure is the median of this many runs.
    pub repeats: usize,
    pub embree_quality: EmbreeQuality,
    pub seed: u64,
}

impl Default for AccelBenchOptions {
    fn default() -> Self {
        let sky = PathBuf::from(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../shared/scenes/cs184/sky"
        ));
        AccelBenchOptions {
            scenes: vec![
                BenchScene::File(sky.join("CBbunny.dae")),
                BenchScene::File(sky.join("CBspheres_lambertian.dae")),
                BenchScene::DisplacedSphere(1_000_000),
            ],
            rays: 500_000,
            width: 480,
            height: 360,
            threads: vec![1, 2],
            repeats: 5,
            embree_quality: EmbreeQuality::Medium,
            seed: 7,
        }
    }
}

/// One backend at one thread count on one scene. Throughputs are in Mrays/s.
#[derive(Clone, Debug, PartialEq)]
pub struct AccelBenchRow {
    pub scene: String,
    pub prims: usize,
    pub backend: String,
    pub is_embree: bool,
    pub threads: usize,
    pub measured: Measurement,
}

#[derive(Clone, Debug, Default, PartialEq)]
pub struct AccelBenchReport {
    pub rows: Vec<AccelBenchRow>,
}

#[derive(Debug, thiserror::Error)]
pub enum BenchError {
    #[error(transparent)]
    Load(#[from] LoadError),
    #[error(transparent)]
    Accel(#[from] AccelError),
    #[error("thread pool: {0}")]
    ThreadPool(#[from] rayon::ThreadPoolBuildError),
}

fn backends(opts: &AccelBenchOptions) -> Vec<Backend> {
    let mut list = vec![
        Backend::Native(BvhBuilder::Midpoint),
        Backend::Native(BvhBuilder::Sah),
    ];
    if cfg!(any(feature = "embree", feature = "embree4")) {
        list.push(Backend::Embree(opts.embree_quality));
    }
    list
}

/// Runs the whole benchmark; `progress` hears one line per finished row.
pub fn run(
    opts: &AccelBenchOptions,
    mut progress: impl FnMut(&str),
) -> Result<AccelBenchReport, BenchError> {
    let mut report = AccelBenchReport::default();
    let repeats = Repeats {
        count: opts.repeats,
        budget_s: f64::INFINITY,
    };
    for bench_scene in &opts.scenes {
        let scene = bench_scene.load()?;
        let rays = make_rays(&scene, opts.width, opts.height, opts.rays, opts.seed);
        for &threads in &opts.threads {
            let pool = tracing_pool(threads)?;
            let builder = Builder::new(threads)?;
            for backend in backends(opts) {
                let m = measure(&scene, &rays, &pool, &builder, backend, repeats)?;
                let row = AccelBenchRow {
                    scene: bench_scene.name(),
                    prims: scene.num_prims(),
                    backend: backend.label().to_string(),
                    is_embree: backend.is_embree(),
                    threads: pool.current_num_threads(),
                    measured: m,
                };
                progress(&format!(
                    "{} / {} / {} threads: done",
                    row.scene, row.backend, row.threads
                ));
                report.rows.push(row);
            }
        }
    }
    Ok(report)
}

impl AccelBenchReport {
    /// Markdown table; the ratio column is native/Embree throughput (camera,
    /// incoherent, shadow) at the same scene and thread count.
    pub fn to_markdown(&self) -> String {
        let mut s = String::from(
            "| scene | prims | backend | threads | build (ms) | memory (MB) | camera (Mrays/s) \
             | incoherent (Mrays/s) | shadow (Mrays/s) | nodes | leaves | SAH cost \
             | native/Embree (cam / inc / shadow) |\n\
             |---|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|\n",
        );
        for r in &self.rows {
            let ratio = self.embree_row(r).filter(|_| !r.is_embree).map_or_else(
                || "—".to_string(),
                |e| {
                    format!(
                        "{:.2} / {:.2} / {:.2}",
                        r.measured.camera_mrays / e.measured.camera_mrays,
                        r.measured.incoherent_mrays / e.measured.incoherent_mrays,
                        r.measured.shadow_mrays / e.measured.shadow_mrays
                    )
                },
            );
            let _ = writeln!(
                s,
                "| {} | {} | {} | {} {} {} | {} |",
                r.scene,
                r.prims,
                r.backend,
                r.threads,
                r.measured.markdown_cells(),
                r.measured.tree_cells(),
                ratio
            );
        }
        s
    }

    fn embree_row(&self, r: &AccelBenchRow) -> Option<&AccelBenchRow> {
        self.rows
            .iter()
            .find(|e| e.is_embree && e.scene == r.scene && e.threads == r.threads)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn markdown_ratio_is_native_over_embree() {
        let row = |backend: &str, is_embree, mrays| AccelBenchRow {
            scene: "s".into(),
            prims: 1,
            backend: backend.into(),
            is_embree,
            threads: 1,
            measured: Measurement {
                build_ms: 1.0,
                memory_mb: 1.0,
                camera_mrays: mrays,
                incoherent_mrays: mrays,
                shadow_mrays: mrays,
                tree: None,
            },
        };
        let report = AccelBenchReport {
            rows: vec![row("native SAH", false, 5.0), row("Embree", true, 10.0)],
        };
        let md = report.to_markdown();
        assert!(md.contains("| 0.50 / 0.50 / 0.50 |"), "{md}");
        assert_eq!(md.lines().count(), 4);
    }
}
