//! What `ember bench accel` and its `--scaling` run share: the three ray sets of a
//! scene, and timing the build and traversal of several backends, interleaved, so
//! both benchmarks measure exactly the same thing. Backends are the core's
//! [`AccelKind`]s, built by the core's [`AccelBuilder`] on the core's tracing pool.

use super::median;
use crate::accel::{Accel, AccelBuilder, AccelError, AccelKind, BvhBuilder, BvhStats};
use crate::camera::Camera;
use crate::geometry::Ray;
use crate::sampling::{uniform_sphere, Rng};
use crate::scene::Scene;
use glam::{Vec2, Vec3};
use rayon::prelude::*;
use std::time::Instant;

/// The three ray sets of one scene, made once so every backend traces the same rays.
pub(crate) struct RaySets {
    pub camera: Vec<Ray>,
    pub incoherent: Vec<Ray>,
    pub shadow: Vec<Ray>,
}

/// Camera rays of the scene's own camera (what a render at `width × height` traces
/// first) through the pixel centres, in [`tiled_camera_rays`] order; `rays`
/// incoherent rays from random points of the bounds in uniform directions; and as
/// many shadow rays from where those hit (found with the SAH BVH) to random points
/// of the bounds (from the miss's origin when a ray hits nothing).
pub(crate) fn make_rays(scene: &Scene, width: u32, height: u32, rays: usize, seed: u64) -> RaySets {
    let mut rng = Rng::from_seed(seed);
    let camera = tiled_camera_rays(scene, width, height);
    let incoherent: Vec<Ray> = (0..rays)
        .map(|_| {
            Ray::new(
                point_in_bounds(scene, &mut rng),
                uniform_sphere(rng.next_2d()),
            )
        })
        .collect();
    let reference = crate::accel::bvh::Bvh::build(scene, BvhBuilder::Sah);
    let shadow = incoherent
        .iter()
        .map(|r| {
            let target = point_in_bounds(scene, &mut rng);
            match reference.intersect(r) {
                // Spawned like a render's shadow ray: off the surface, skipping it.
                Some(h) => scene.interaction(r, &h).spawn_segment(target, 1.0),
                None => Ray::segment(r.o, target - r.o, 1.0),
            }
        })
        .collect();
    RaySets {
        camera,
        incoherent,
        shadow,
    }
}

/// Camera rays through the pixel centres, ordered by 4×4 pixel tiles and inside a
/// tile in Morton order, so every run of 4, 8 or 16 rays covers a 2×2, 4×2 or 4×4
/// block: the coherent packets Embree's packet kernels are made for, and the order a
/// tiled render traces its first rays in.
pub fn tiled_camera_rays(scene: &Scene, width: u32, height: u32) -> Vec<Ray> {
    let cam = Camera::new(&scene.camera, &scene.bounds, width, height);
    let mut rays = Vec::with_capacity(width as usize * height as usize);
    for ty in (0..height).step_by(4) {
        for tx in (0..width).step_by(4) {
            for k in 0..16u32 {
                // Bits 0 and 2 of k give x, bits 1 and 3 give y.
                let (x, y) = (
                    tx + (k & 1) + ((k >> 1) & 2),
                    ty + ((k >> 1) & 1) + ((k >> 2) & 2),
                );
                if x < width && y < height {
                    rays.push(cam.generate_ray(x, y, Vec2::splat(0.5)));
                }
            }
        }
    }
    rays
}

fn point_in_bounds(scene: &Scene, rng: &mut Rng) -> Vec3 {
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

impl Repeats {
    fn wants_more(self, times: &[f64]) -> bool {
        times.is_empty() || (times.len() < self.count && times.iter().sum::<f64>() < self.budget_s)
    }
}

/// One backend's figures on one scene; throughputs in Mrays/s.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Measurement {
    pub build_ms: f64,
    /// What traversal keeps: the native tree's nodes, leaf blocks and spheres; Embree's
    /// growth of its device's memory over the build (with its own copy of the geometry).
    pub memory_mb: f64,
    pub camera_mrays: f64,
    pub incoherent_mrays: f64,
    pub shadow_mrays: f64,
    /// The native tree's shape (`None` for Embree).
    pub tree: Option<TreeShape>,
}

/// What a benchmark table shows of a tree's [`BvhStats`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TreeShape {
    /// Inner (wide) nodes.
    pub nodes: usize,
    pub leaves: usize,
    /// Longest root-to-leaf path, in nodes.
    pub depth: usize,
    /// Expected cost of a random ray that hits the root box.
    pub sah_cost: f64,
}

impl From<BvhStats> for TreeShape {
    fn from(s: BvhStats) -> Self {
        TreeShape {
            nodes: s.nodes,
            leaves: s.leaves,
            depth: s.max_depth,
            sah_cost: s.sah_cost as f64,
        }
    }
}

/// Times every backend of `kinds` on `scene`, interleaved so that a slow drift of the
/// machine's speed weighs on all of them alike: each round builds every backend once
/// (dropping its previous build first), then each round traces every ray set with
/// every backend once. All inside `pool`; medians over the rounds.
pub(crate) fn measure_all(
    scene: &Scene,
    rays: &RaySets,
    pool: &rayon::ThreadPool,
    builder: &AccelBuilder,
    kinds: &[AccelKind],
    repeats: Repeats,
) -> Result<Vec<Measurement>, AccelError> {
    let n = kinds.len();
    let mut accels: Vec<Option<Box<dyn Accel>>> = (0..n).map(|_| None).collect();
    let mut build_s: Vec<Vec<f64>> = vec![Vec::new(); n];
    while build_s.iter().any(|t| repeats.wants_more(t)) {
        for i in 0..n {
            if !repeats.wants_more(&build_s[i]) {
                continue;
            }
            drop(accels[i].take());
            let start = Instant::now();
            let built = pool.install(|| builder.build(scene, kinds[i]))?;
            build_s[i].push(start.elapsed().as_secs_f64());
            accels[i] = Some(built);
        }
    }
    let accels: Vec<Box<dyn Accel>> = accels.into_iter().flatten().collect();
    let sets: [(&[Ray], bool); 3] = [
        (&rays.camera, false),
        (&rays.incoherent, false),
        (&rays.shadow, true),
    ];
    // times[set][backend]: seconds per run.
    let mut times: Vec<Vec<Vec<f64>>> = vec![vec![Vec::new(); n]; 3];
    while times.iter().flatten().any(|t| repeats.wants_more(t)) {
        for (s, &(set, shadow)) in sets.iter().enumerate() {
            for (i, accel) in accels.iter().enumerate() {
                if repeats.wants_more(&times[s][i]) {
                    times[s][i].push(time_rays(pool, accel.as_ref(), set, shadow));
                }
            }
        }
    }
    let mrays = |s: usize, i: usize| {
        let mut rates: Vec<f64> = times[s][i]
            .iter()
            .map(|t| sets[s].0.len() as f64 / t.max(1e-9) / 1e6)
            .collect();
        median(&mut rates)
    };
    Ok((0..n)
        .map(|i| Measurement {
            build_ms: 1e3 * median(&mut build_s[i].clone()),
            memory_mb: accels[i].memory_bytes() as f64 / (1024.0 * 1024.0),
            camera_mrays: mrays(0, i),
            incoherent_mrays: mrays(1, i),
            shadow_mrays: mrays(2, i),
            tree: accels[i].bvh_stats().map(TreeShape::from),
        })
        .collect())
}

/// Seconds to trace `rays` on `pool`, in chunks of 1024 (whole 4×4 tiles of camera rays).
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
    let decimals = if x == 0.0 || !x.is_finite() {
        0
    } else {
        (2 - x.abs().log10().floor() as i32).clamp(0, 6) as usize
    };
    format!("{x:.decimals$}")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bench::meshes;

    #[test]
    fn three_significant_digits() {
        assert_eq!(three_digits(1305.5), "1306");
        assert_eq!(three_digits(25.81), "25.8");
        assert_eq!(three_digits(0.01234), "0.0123");
        assert_eq!(three_digits(0.0), "0");
    }

    #[test]
    fn tiles_put_every_pixel_once_and_packets_on_compact_blocks() {
        let scene = meshes::displaced_sphere(200);
        let (w, h) = (10, 6);
        let rays = tiled_camera_rays(&scene, w, h);
        let cam = Camera::new(&scene.camera, &scene.bounds, w, h);
        let mut pixels: Vec<(u32, u32)> = Vec::new();
        for r in &rays {
            let p = (0..h)
                .flat_map(|y| (0..w).map(move |x| (x, y)))
                .find(|&(x, y)| cam.generate_ray(x, y, Vec2::splat(0.5)) == *r)
                .expect("a pixel centre's ray");
            pixels.push(p);
        }
        let mut sorted = pixels.clone();
        sorted.sort();
        sorted.dedup();
        assert_eq!(sorted.len(), (w * h) as usize);
        // The first packet of 8 is the 4×2 block at the origin.
        let mut first8 = pixels[..8].to_vec();
        first8.sort();
        let block: Vec<(u32, u32)> = (0..4).flat_map(|x| (0..2).map(move |y| (x, y))).collect();
        assert_eq!(first8, block);
    }

    #[test]
    fn interleaved_measurement_gives_one_figure_per_backend() {
        let scene = meshes::displaced_sphere(2_000);
        let rays = make_rays(&scene, 16, 12, 500, 3);
        let pool = crate::accel::tracing_pool(Some(1)).expect("pool");
        let kinds = [
            AccelKind::Native(BvhBuilder::Midpoint),
            AccelKind::Native(BvhBuilder::Sah),
        ];
        let repeats = Repeats {
            count: 2,
            budget_s: f64::INFINITY,
        };
        let m = measure_all(&scene, &rays, &pool, &AccelBuilder::new(1), &kinds, repeats)
            .expect("native builds");
        assert_eq!(m.len(), 2);
        for x in &m {
            assert!(x.camera_mrays > 0.0 && x.incoherent_mrays > 0.0 && x.shadow_mrays > 0.0);
            let tree = x.tree.expect("native trees have stats");
            assert!(tree.leaves > 0 && tree.sah_cost > 0.0);
            assert!(x.memory_mb > 0.0);
        }
    }
}
