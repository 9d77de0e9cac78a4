//! `ember bench accel`: build time, memory and ray throughput of every backend this
//! build has, per scene and thread count, as data plus a Markdown table.

use super::{median, meshes};
use crate::accel::{self, Accel, AccelError, AccelKind, BvhBuilder, EmbreeQuality};
use crate::camera::Camera;
use crate::geometry::{offset_ray_origin, Ray};
use crate::sampling::{uniform_sphere, Sampler};
use crate::scene::collada::{self, LoadError};
use crate::scene::Scene;
use glam::{Vec2, Vec3};
use rayon::prelude::*;
use std::fmt::Write as _;
use std::path::PathBuf;
use std::time::Instant;

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
    pub build_ms: f64,
    pub memory_mb: f64,
    pub camera_mrays: f64,
    pub incoherent_mrays: f64,
    pub shadow_mrays: f64,
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

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Backend {
    Native(BvhBuilder),
    #[cfg_attr(not(feature = "embree"), allow(dead_code))]
    Embree(EmbreeQuality),
}

impl Backend {
    fn label(self) -> &'static str {
        match self {
            Backend::Native(BvhBuilder::Midpoint) => "native midpoint",
            Backend::Native(BvhBuilder::Sah) => "native SAH",
            Backend::Embree(_) => "Embree",
        }
    }
}

fn backends(opts: &AccelBenchOptions) -> Vec<Backend> {
    let mut list = vec![
        Backend::Native(BvhBuilder::Midpoint),
        Backend::Native(BvhBuilder::Sah),
    ];
    if cfg!(feature = "embree") {
        list.push(Backend::Embree(opts.embree_quality));
    }
    list
}

/// The three ray sets of one scene, made once so every backend traces the same rays.
struct RaySets {
    camera: Vec<Ray>,
    incoherent: Vec<Ray>,
    shadow: Vec<Ray>,
}

/// Runs the whole benchmark; `progress` hears one line per finished row.
pub fn run(
    opts: &AccelBenchOptions,
    mut progress: impl FnMut(&str),
) -> Result<AccelBenchReport, BenchError> {
    let mut report = AccelBenchReport::default();
    for bench_scene in &opts.scenes {
        let scene = bench_scene.load()?;
        let rays = make_rays(&scene, opts);
        for &threads in &opts.threads {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .start_handler(|_| accel::set_flush_denormals())
                .build()?;
            let mut builder = Builder::new(threads)?;
            for backend in backends(opts) {
                let row = measure(&scene, &rays, &pool, &mut builder, backend, opts)?;
                let row = AccelBenchRow {
                    scene: bench_scene.name(),
                    ..row
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

/// Builds backends for one thread count. Embree builds on its own TBB pool, so it
/// gets a device limited to the same number of threads, created before any timing.
struct Builder {
    #[cfg(feature = "embree")]
    device: std::sync::Arc<accel::embree::EmbreeDevice>,
}

impl Builder {
    #[cfg_attr(not(feature = "embree"), allow(unused_variables))]
    fn new(threads: usize) -> Result<Builder, AccelError> {
        Ok(Builder {
            #[cfg(feature = "embree")]
            device: std::sync::Arc::new(accel::embree::EmbreeDevice::new(threads)?),
        })
    }

    fn build(&self, scene: &Scene, backend: Backend) -> Result<Box<dyn Accel>, AccelError> {
        match backend {
            Backend::Native(b) => accel::build(scene, AccelKind::Native(b)),
            #[cfg(feature = "embree")]
            Backend::Embree(q) => Ok(Box::new(accel::embree::EmbreeAccel::build_on(
                self.device.clone(),
                scene,
                q,
            )?)),
            #[cfg(not(feature = "embree"))]
            Backend::Embree(q) => accel::build(scene, AccelKind::Embree(q)),
        }
    }
}

fn measure(
    scene: &Scene,
    rays: &RaySets,
    pool: &rayon::ThreadPool,
    builder: &mut Builder,
    backend: Backend,
    opts: &AccelBenchOptions,
) -> Result<AccelBenchRow, BenchError> {
    let repeats = opts.repeats.max(1);
    let mut build_ms = Vec::with_capacity(repeats);
    let mut accel = None;
    for _ in 0..repeats {
        drop(accel.take());
        let start = Instant::now();
        let built = pool.install(|| builder.build(scene, backend))?;
        build_ms.push(start.elapsed().as_secs_f64() * 1e3);
        accel = Some(built);
    }
    let accel = accel.expect("repeats >= 1");
    let throughput = |rays: &[Ray], shadow: bool| {
        let mut samples: Vec<f64> = (0..repeats)
            .map(|_| mrays_per_s(pool, accel.as_ref(), rays, shadow))
            .collect();
        median(&mut samples)
    };
    Ok(AccelBenchRow {
        scene: String::new(),
        prims: scene.num_prims(),
        backend: backend.label().to_string(),
        is_embree: matches!(backend, Backend::Embree(_)),
        threads: pool.current_num_threads(),
        build_ms: median(&mut build_ms),
        memory_mb: accel.memory_bytes() as f64 / (1024.0 * 1024.0),
        camera_mrays: throughput(&rays.camera, false),
        incoherent_mrays: throughput(&rays.incoherent, false),
        shadow_mrays: throughput(&rays.shadow, true),
    })
}

fn mrays_per_s(pool: &rayon::ThreadPool, accel: &dyn Accel, rays: &[Ray], shadow: bool) -> f64 {
    let start = Instant::now();
    let hits: usize = pool.install(|| {
        rays.par_chunks(1024)
            .map(|chunk| {
                chunk
                    .iter()
                    .filter(|r| {
                        if shadow {
                            accel.occluded(r)
                        } else {
                            accel.intersect(r).is_some()
                        }
                    })
                    .count()
            })
            .sum()
    });
    std::hint::black_box(hits);
    rays.len() as f64 / start.elapsed().as_secs_f64().max(1e-9) / 1e6
}

fn make_rays(scene: &Scene, opts: &AccelBenchOptions) -> RaySets {
    let mut rng = Sampler::from_seed(opts.seed);
    let cam = Camera::new(&scene.camera, &scene.bounds, opts.width, opts.height);
    let camera = (0..opts.height)
        .flat_map(|j| (0..opts.width).map(move |i| (i, j)))
        .map(|(i, j)| cam.generate_ray(i, j, Vec2::splat(0.5)))
        .collect();
    let incoherent: Vec<Ray> = (0..opts.rays)
        .map(|_| {
            Ray::new(
                point_in_bounds(scene, &mut rng),
                uniform_sphere(rng.next_2d()),
            )
        })
        .collect();
    // Shadow rays start at surface points, found with the SAH BVH, and end at random
    // points of the bounds; origins come from misses' far ends when too few rays hit.
    let reference = accel::bvh::Bvh::build(scene, BvhBuilder::Sah);
    let shadow = incoherent
        .iter()
        .map(|r| {
            let origin = match reference.intersect(r) {
                Some(h) => {
                    let si = scene.interaction(r, &h);
                    offset_ray_origin(si.p, si.p_error, si.ng, -r.d)
                }
                None => r.o,
            };
            Ray::segment(origin, point_in_bounds(scene, &mut rng) - origin, 1.0)
        })
        .collect();
    RaySets {
        camera,
        incoherent,
        shadow,
    }
}

fn point_in_bounds(scene: &Scene, rng: &mut Sampler) -> Vec3 {
    let u = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
    scene.bounds.min + u * scene.bounds.diagonal()
}

impl AccelBenchReport {
    /// Markdown table; the ratio column is native/Embree throughput (camera,
    /// incoherent, shadow) at the same scene and thread count.
    pub fn to_markdown(&self) -> String {
        let mut s = String::from(
            "| scene | prims | backend | threads | build (ms) | memory (MB) | camera (Mrays/s) \
             | incoherent (Mrays/s) | shadow (Mrays/s) | native/Embree (cam / inc / shadow) |\n\
             |---|---:|---|---:|---:|---:|---:|---:|---:|---|\n",
        );
        for r in &self.rows {
            let ratio = self.embree_row(r).filter(|_| !r.is_embree).map_or_else(
                || "—".to_string(),
                |e| {
                    format!(
                        "{:.2} / {:.2} / {:.2}",
                        r.camera_mrays / e.camera_mrays,
                        r.incoherent_mrays / e.incoherent_mrays,
                        r.shadow_mrays / e.shadow_mrays
                    )
                },
            );
            let _ = writeln!(
                s,
                "| {} | {} | {} | {} | {} | {} | {:.2} | {:.2} | {:.2} | {} |",
                r.scene,
                r.prims,
                r.backend,
                r.threads,
                three_digits(r.build_ms),
                three_digits(r.memory_mb),
                r.camera_mrays,
                r.incoherent_mrays,
                r.shadow_mrays,
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

/// Three significant digits: build times and sizes span 0.01 ms to seconds.
fn three_digits(x: f64) -> String {
    let decimals = if x == 0.0 {
        0
    } else {
        (2 - x.abs().log10().floor() as i32).clamp(0, 6) as usize
    };
    format!("{x:.decimals$}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn three_significant_digits() {
        assert_eq!(three_digits(1305.5), "1306");
        assert_eq!(three_digits(25.81), "25.8");
        assert_eq!(three_digits(0.01234), "0.0123");
        assert_eq!(three_digits(0.0), "0");
    }

    #[test]
    fn markdown_ratio_is_native_over_embree() {
        let row = |backend: &str, is_embree, mrays| AccelBenchRow {
            scene: "s".into(),
            prims: 1,
            backend: backend.into(),
            is_embree,
            threads: 1,
            build_ms: 1.0,
            memory_mb: 1.0,
            camera_mrays: mrays,
            incoherent_mrays: mrays,
            shadow_mrays: mrays,
        };
        let report = AccelBenchReport {
            rows: vec![row("native SAH", false, 5.0), row("Embree", true, 10.0)],
        };
        let md = report.to_markdown();
        assert!(md.contains("| 0.50 / 0.50 / 0.50 |"), "{md}");
        assert_eq!(md.lines().count(), 4);
    }
}
