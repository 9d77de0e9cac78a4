//! What `ember bench accel` and its `--scaling` run share: the backends, the
//! three ray sets of a scene, and timing one backend's build and traversal, so
//! both benchmarks measure exactly the same thing.

use super::median;
use crate::accel::{self, Accel, AccelError, AccelKind, BvhBuilder, EmbreeQuality};
use crate::camera::Camera;
use crate::geometry::{offset_ray_origin, Ray};
use crate::sampling::{uniform_sphere, Sampler};
use crate::scene::Scene;
use glam::{Vec2, Vec3};
use rayon::prelude::*;
use std::time::Instant;

/// One acceleration structure with its build setting.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Backend {
    Native(BvhBuilder),
    #[cfg_attr(not(any(feature = "embree", feature = "embree4")), allow(dead_code))]
    Embree(EmbreeQuality),
}

impl Backend {
    /// The name without Embree's quality (one Embree row per scene in `bench accel`).
    pub fn label(self) -> &'static str {
        match self {
            Backend::Native(BvhBuilder::Midpoint) => "native midpoint",
            Backend::Native(BvhBuilder::Sah) => "native SAH",
            Backend::Embree(_) => "Embree",
        }
    }

    /// The name with Embree's quality, for runs that compare the qualities.
    pub fn label_with_quality(self) -> String {
        match self {
            Backend::Embree(q) => format!("Embree {}", quality_name(q)),
            _ => self.label().to_string(),
        }
    }

    pub fn is_embree(self) -> bool {
        matches!(self, Backend::Embree(_))
    }
}

pub(crate) fn quality_name(q: EmbreeQuality) -> &'static str {
    match q {
        EmbreeQuality::Low => "low",
        EmbreeQuality::Medium => "medium",
        EmbreeQuality::High => "high",
    }
}

/// A rayon pool of `threads` tracing threads with flush-to-zero set, as renders use.
pub(crate) fn tracing_pool(
    threads: usize,
) -> Result<rayon::ThreadPool, rayon::ThreadPoolBuildError> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .start_handler(|_| accel::set_flush_denormals())
        .build()
}

/// Builds backends for one thread count. Embree builds on its own TBB pool, so it
/// gets a device limited to the same number of threads, created before any timing.
pub(crate) struct Builder {
    #[cfg(any(feature = "embree", feature = "embree4"))]
    device: std::sync::Arc<accel::embree::EmbreeDevice>,
}

impl Builder {
    #[cfg_attr(
        not(any(feature = "embree", feature = "embree4")),
        allow(unused_variables)
    )]
    pub fn new(threads: usize) -> Result<Builder, AccelError> {
        Ok(Builder {
            #[cfg(any(feature = "embree", feature = "embree4"))]
            device: std::sync::Arc::new(accel::embree::EmbreeDevice::new(threads)?),
        })
    }

    fn build(&self, scene: &Scene, backend: Backend) -> Result<Box<dyn Accel>, AccelError> {
        match backend {
            Backend::Native(b) => accel::build(scene, AccelKind::Native(b)),
            #[cfg(any(feature = "embree", feature = "embree4"))]
            Backend::Embree(q) => Ok(Box::new(accel::embree::EmbreeAccel::build_on(
                self.device.clone(),
                scene,
                q,
            )?)),
            #[cfg(not(any(feature = "embree", feature = "embree4")))]
            Backend::Embree(q) => accel::build(scene, AccelKind::Embree(q)),
        }
    }
}

/// The three ray sets of one scene, made once so every backend traces the same rays.
pub(crate) struct RaySets {
    pub camera: Vec<Ray>,
    pub incoherent: Vec<Ray>,
    pub shadow: Vec<Ray>,
}

/// Camera rays through the pixel centres of a `width × height` image; `rays`
/// incoherent rays from random points of the bounds in uniform directions; and as
/// many shadow rays from where those hit (found with the SAH BVH) to random points
/// of the bounds (from the miss's origin when a ray hits nothing).
pub(crate) fn make_rays(scene: &Scene, width: u32, height: u32, rays: usize, seed: u64) -> RaySets {
    let mut rng = Sampler::from_seed(seed);
    let cam = Camera::new(&scene.camera, &scene.bounds, width, height);
    let camera = (0..height)
        .flat_map(|j| (0..width).map(move |i| (i, j)))
        .map(|(i, j)| cam.generate_ray(i, j, Vec2::splat(0.5)))
        .collect();
    let incoherent: Vec<Ray> = (0..rays)
        .map(|_| {
            Ray::new(
                point_in_bounds(scene, &mut rng),
                uniform_sphere(rng.next_2d()),
            )
        })
        .collect();
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

/// How often to repeat each figure; the median is reported.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Repeats {
    pub count: usize,
    /// Stop repeating a figure (a build, or a traversal of one ray set) once its runs
    /// have taken this long in total; at least one always runs. A 4M-triangle build
    /// or soup traversal repeated five times would dominate a scaling run, while the
    /// run-to-run spread of such long runs is small anyway.
    pub budget_s: f64,
}

/// One backend's figures on one scene; throughputs in Mrays/s.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Measurement {
    pub build_ms: f64,
    pub memory_mb: f64,
    pub camera_mrays: f64,
    pub incoherent_mrays: f64,
    pub shadow_mrays: f64,
    /// The native tree's shape (`None` for Embree).
    pub tree: Option<crate::accel::BvhStats>,
}

impl Measurement {
    /// The five Markdown table cells `| build | memory | camera | incoherent | shadow`
    /// shared by the accel and scaling tables.
    /// `| nodes | leaves | SAH cost` of the native tree, dashes for Embree.
    pub fn tree_cells(&self) -> String {
        self.tree.map_or_else(
            || "| — | — | —".to_string(),
            |t| format!("| {} | {} | {:.2}", t.nodes, t.leaves, t.sah_cost),
        )
    }

    pub fn markdown_cells(&self) -> String {
        format!(
            "| {} | {} | {:.2} | {:.2} | {:.2}",
            three_digits(self.build_ms),
            three_digits(self.memory_mb),
            self.camera_mrays,
            self.incoherent_mrays,
            self.shadow_mrays
        )
    }
}

/// Times `repeats` builds (the last one is kept) and then `repeats` traversals of
/// each ray set, all inside `pool`.
pub(crate) fn measure(
    scene: &Scene,
    rays: &RaySets,
    pool: &rayon::ThreadPool,
    builder: &Builder,
    backend: Backend,
    repeats: Repeats,
) -> Result<Measurement, AccelError> {
    let mut accel = None;
    let mut build_ms = repeated(repeats, || {
        drop(accel.take());
        let start = Instant::now();
        let built = pool.install(|| builder.build(scene, backend))?;
        accel = Some(built);
        Ok(start.elapsed().as_secs_f64())
    })?
    .into_iter()
    .map(|s| s * 1e3)
    .collect::<Vec<_>>();
    let accel = accel.expect("at least one build runs");
    let throughput = |rays: &[Ray], shadow: bool| -> Result<f64, AccelError> {
        let mut samples = repeated(repeats, || {
            Ok(time_rays(pool, accel.as_ref(), rays, shadow))
        })?
        .into_iter()
        .map(|s| rays.len() as f64 / s.max(1e-9) / 1e6)
        .collect::<Vec<_>>();
        Ok(median(&mut samples))
    };
    Ok(Measurement {
        build_ms: median(&mut build_ms),
        memory_mb: accel.memory_bytes() as f64 / (1024.0 * 1024.0),
        camera_mrays: throughput(&rays.camera, false)?,
        incoherent_mrays: throughput(&rays.incoherent, false)?,
        shadow_mrays: throughput(&rays.shadow, true)?,
        tree: accel.bvh_stats(),
    })
}

/// Runs `timed` (which returns seconds) up to `repeats.count` times, stopping early
/// once the budget is spent; returns the times.
fn repeated(
    repeats: Repeats,
    mut timed: impl FnMut() -> Result<f64, AccelError>,
) -> Result<Vec<f64>, AccelError> {
    let mut times = Vec::with_capacity(repeats.count.max(1));
    while times.is_empty()
        || (times.len() < repeats.count && times.iter().sum::<f64>() < repeats.budget_s)
    {
        times.push(timed()?);
    }
    Ok(times)
}

/// Seconds to trace `rays` on `pool`.
fn time_rays(pool: &rayon::ThreadPool, accel: &dyn Accel, rays: &[Ray], shadow: bool) -> f64 {
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
    start.elapsed().as_secs_f64()
}

/// Three significant digits: build times and sizes span 0.01 ms to seconds.
pub(crate) fn three_digits(x: f64) -> String {
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
    fn embree_labels_carry_the_quality_only_when_asked() {
        let b = Backend::Embree(EmbreeQuality::High);
        assert_eq!(b.label(), "Embree");
        assert_eq!(b.label_with_quality(), "Embree high");
        assert_eq!(
            Backend::Native(BvhBuilder::Sah).label_with_quality(),
            "native SAH"
        );
    }
}
