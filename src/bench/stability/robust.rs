//! Cases 5 and 6: geometric robustness. The same scene at another scale or far from
//! the origin must give the same image (self-intersection offsets are relative), and
//! rays along edges, through shared vertices or at grazing angles must not slip
//! through a closed mesh; degenerate triangles must not produce NaN.

use super::measure::{lum, Budget, Halves, NATIVE};
use super::scenes::{degenerate_room, embedded, grid_plane, transformed, GRID_CELLS, GRID_HALF};
use super::Row;
use crate::camera::Camera;
use crate::geometry::Ray;
use crate::integrators::{DirectStrategy, Roulette};
use crate::render::{RenderJob, RenderSettings, Shading};
use crate::sampling::Sampler;
use crate::Vec3;
use anyhow::Result;

/// Per-pixel comparison of a transformed copy against the original, same seed.
#[derive(Clone, Debug)]
pub struct ScaledRun {
    pub name: String,
    pub scale: f32,
    pub offset: f32,
    pub mean: f64,
    /// Paired standard error of the mean difference (from the per-pixel differences).
    pub diff_se: f64,
    /// Mean difference over surface pixels (no emitter in any corner's view), relative
    /// to the original's surface mean, and its paired standard error, also relative.
    /// Acne would darken surfaces, leaks brighten them; emitters seen directly are
    /// excluded because their edges move with floating-point rounding of the geometry.
    pub surface_rel_diff: f64,
    pub surface_rel_se: f64,
    /// Fraction of pixels differing by more than 1e-3 relative (the paths diverged).
    pub frac_changed: f64,
    /// Fraction of pixels differing by more than 4 per-pixel noise σ (σ from the halves).
    pub frac_beyond_noise: f64,
    /// Largest difference of an 8×8 block of surface pixels, in units of that block's
    /// noise σ·√2 for two independent renders (see `SurfaceBlocks`).
    pub max_block_z: f64,
    pub nonfinite: u64,
}

pub struct ScaleCase {
    pub base_mean: f64,
    /// Per-pixel RMS noise σ of one render (from two independent halves).
    pub pixel_noise: f64,
    pub runs: Vec<ScaledRun>,
}

pub const SCALE_VARIANTS: [(&str, f32, f32); 5] = [
    ("scale 1e-3", 1e-3, 0.0),
    ("scale 1e3", 1e3, 0.0),
    ("translate 1e4", 1.0, 1e4),
    ("translate 1e5", 1.0, 1e5),
    ("scale 1e-3, translate 1", 1e-3, 1.0),
];

fn scale_settings() -> RenderSettings {
    RenderSettings {
        max_depth: 4,
        strategy: Some(DirectStrategy::Mis),
        roulette: Roulette::Off,
        ..Default::default()
    }
}

pub fn scale(b: &Budget) -> Result<ScaleCase> {
    let base_scene = embedded("cornell.dae")?;
    let s = b.settings(scale_settings());
    let base = b.job(base_scene.clone())?;
    let reference = base.render(&s);
    // Noise of one render of `spp` samples: halves of 2·spp have exactly that size.
    let halves = base.halves(&RenderSettings {
        spp: 2 * b.spp,
        ..s.clone()
    });
    let sigma = halves.noise_per_pixel();
    let surface = surface_pixels(&base);
    let blocks = SurfaceBlocks::new(&halves, &surface, 8);
    let mut runs = Vec::new();
    for (name, k, off) in SCALE_VARIANTS {
        let setup = b.job(transformed(&base_scene, k, Vec3::splat(off)))?;
        let o = setup.render(&s);
        let mut run = compare(name, k, off, &reference.image, &o, sigma, &blocks);
        (run.surface_rel_diff, run.surface_rel_se) =
            paired_relative_diff(&reference.image, &o.image, &surface);
        runs.push(run);
    }
    let n = reference.image.pixels.len();
    let base_mean = (0..n).map(|i| lum(&reference.image, i)).sum::<f64>() / n as f64;
    Ok(ScaleCase {
        base_mean,
        pixel_noise: sigma,
        runs,
    })
}

/// Pixels none of whose corners or centre sees an emitter directly.
fn surface_pixels(setup: &RenderJob) -> Vec<usize> {
    let cam = &setup.camera;
    let sees_emitter = |x: u32, y: u32| {
        [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0), (0.5, 0.5)]
            .iter()
            .any(|&(u, v)| {
                let r = cam.generate_ray(x, y, glam::Vec2::new(u, v));
                setup.accel.intersect(&r).is_some_and(|h| {
                    let si = setup.scene.interaction(&r, &h);
                    setup.scene.materials[si.material as usize].is_black()
                })
            })
    };
    (0..cam.height)
        .flat_map(|y| (0..cam.width).map(move |x| (x, y)))
        .filter(|&(x, y)| !sees_emitter(x, y))
        .map(|(x, y)| (y * cam.width + x) as usize)
        .collect()
}

/// Mean of `o − r` over `pixels` relative to the mean of `r`, and its paired standard error.
fn paired_relative_diff(
    r: &crate::film::Image,
    o: &crate::film::Image,
    pixels: &[usize],
) -> (f64, f64) {
    let n = pixels.len().max(2) as f64;
    let base = pixels.iter().map(|&i| lum(r, i)).sum::<f64>() / n;
    let d: Vec<f64> = pixels.iter().map(|&i| lum(o, i) - lum(r, i)).collect();
    let md = d.iter().sum::<f64>() / n;
    let var = d.iter().map(|x| (x - md).powi(2)).sum::<f64>() / (n - 1.0);
    (md / base, (var / n).sqrt() / base)
}

/// The `b × b` blocks made only of surface pixels, each with the noise of its mean in
/// one render, from the per-pixel differences of two independent halves (`b²` degrees
/// of freedom per block). Per block, because the noise is far from uniform: a block of
/// caustic or of the mirror's view of the light is many times noisier than a wall, and a
/// global σ made those look like failures. Blocks showing an emitter are left out, as
/// for the surface mean: their edges move with the rounding of the geometry itself.
struct SurfaceBlocks {
    b: u32,
    /// (block index in `block_average(b)`, noise σ of the block mean of one render).
    noise: Vec<(usize, f64)>,
}

impl SurfaceBlocks {
    fn new(h: &Halves, surface: &[usize], b: u32) -> Self {
        let img = &h.a.image;
        let (w, bw, bh) = (img.width, img.width / b, img.height / b);
        let mut is_surface = vec![false; img.pixels.len()];
        surface.iter().for_each(|&i| is_surface[i] = true);
        let mut noise = Vec::new();
        for by in 0..bh {
            for bx in 0..bw {
                let px: Vec<usize> = (0..b * b)
                    .map(|k| ((by * b + k / b) * w + bx * b + k % b) as usize)
                    .collect();
                if px.iter().all(|&i| is_surface[i]) {
                    // E[(a − c)²] = 2σ²_pixel for one half, whose spp is one render's.
                    let var: f64 = px
                        .iter()
                        .map(|&i| 0.5 * (lum(img, i) - lum(&h.b.image, i)).powi(2))
                        .sum();
                    noise.push(((by * bw + bx) as usize, var.sqrt() / (b * b) as f64));
                }
            }
        }
        SurfaceBlocks { b, noise }
    }

    /// Largest |difference of block means| of two renders in units of its noise, `σ·√2`.
    fn worst_z(&self, r: &crate::film::Image, o: &crate::film::Image) -> f64 {
        let (ra, oa) = (r.block_average(self.b), o.block_average(self.b));
        self.noise
            .iter()
            .map(|&(i, s)| (lum(&oa, i) - lum(&ra, i)).abs() / (s * 2f64.sqrt()).max(1e-12))
            .fold(0.0, f64::max)
    }
}

fn compare(
    name: &str,
    scale: f32,
    offset: f32,
    reference: &crate::film::Image,
    o: &crate::render::RenderOutput,
    sigma: f64,
    blocks: &SurfaceBlocks,
) -> ScaledRun {
    let n = reference.pixels.len();
    let d: Vec<f64> = (0..n)
        .map(|i| lum(&o.image, i) - lum(reference, i))
        .collect();
    let mean_d = d.iter().sum::<f64>() / n as f64;
    let var_d = d.iter().map(|x| (x - mean_d).powi(2)).sum::<f64>() / (n as f64 - 1.0).max(1.0);
    let changed = (0..n)
        .filter(|&i| d[i].abs() > 1e-3 * lum(reference, i).max(1e-3))
        .count();
    let beyond = d.iter().filter(|x| x.abs() > 4.0 * sigma).count();
    let max_block_z = blocks.worst_z(reference, &o.image);
    ScaledRun {
        name: name.into(),
        scale,
        offset,
        mean: (0..n).map(|i| lum(&o.image, i)).sum::<f64>() / n as f64,
        diff_se: (var_d / n as f64).sqrt(),
        surface_rel_diff: 0.0,
        surface_rel_se: 0.0,
        frac_changed: changed as f64 / n as f64,
        frac_beyond_noise: beyond as f64 / n as f64,
        max_block_z,
        nonfinite: o.nonfinite_samples,
    }
}

impl ScaleCase {
    pub fn rows(&self) -> Vec<Row> {
        let mut rows = vec![Row {
            case: "5 scale/translate".into(),
            method: "original".into(),
            mean: self.base_mean,
            stderr: 0.0,
            expected: None,
            noise: self.pixel_noise,
            nonfinite: 0,
            note: "cornell.dae, same seed for every copy".into(),
        }];
        rows.extend(self.runs.iter().map(|r| Row {
            case: "5 scale/translate".into(),
            method: r.name.clone(),
            mean: r.mean,
            stderr: r.diff_se,
            expected: Some(self.base_mean),
            noise: self.pixel_noise,
            nonfinite: r.nonfinite,
            note: format!(
                "{:.1}% of pixels changed, {:.2}% beyond 4σ; surfaces {:+.3}% ± {:.3}%; worst 8×8 surface block {:.1} σ",
                100.0 * r.frac_changed,
                100.0 * r.frac_beyond_noise,
                100.0 * r.surface_rel_diff,
                100.0 * r.surface_rel_se,
                r.max_block_z
            ),
        }));
        rows
    }
}

/// Ray queries against a fine grid: how many should hit, and how many did not.
#[derive(Clone, Debug, Default)]
pub struct GridCase {
    /// Rays at elevations ≥ `GRAZING_LIMIT` that must hit, and those that missed.
    pub rays: u64,
    pub holes: u64,
    /// The same below `GRAZING_LIMIT` (1e-5 to 1e-4 rad). These once missed: pbrt-v4's
    /// conservative bound δt on the hit distance's rounding error grows like 1/det and
    /// at such angles exceeded t itself, so hits were rejected. The triangle test no
    /// longer applies it (rays leaving a surface skip their primitive instead).
    pub extreme_rays: u64,
    pub extreme_holes: u64,
    /// Largest |hit y| and relative |t − t_exact| among hits.
    pub max_abs_y: f64,
    pub max_rel_t: f64,
    /// Pixels of a grazing normals render whose every sample must see the grid, and those that did not.
    pub covered_pixels: u64,
    pub hole_pixels: u64,
    /// Non-finite samples of radiance renders of the degenerate-triangle room, all strategies.
    pub degenerate_nonfinite: u64,
    pub degenerate_all_finite: bool,
    pub degenerate_mean: f64,
}

pub fn grid(b: &Budget) -> Result<GridCase> {
    let scene = grid_plane();
    let mut camera = Camera::new(&scene.camera, &scene.bounds, b.width, b.height);
    camera.eye = Vec3::new(0.0, 0.02, -GRID_HALF - 0.5);
    let setup = RenderJob::with_camera(scene, NATIVE, camera)?;
    let mut c = GridCase::default();
    grid_queries(&setup, &mut c, b.seed);
    grazing_render(&setup, b, &mut c);
    degenerate(b, &mut c)?;
    Ok(c)
}

/// Rays at grazing elevations aimed at every inner vertex, at the midpoints of shared
/// (axis and diagonal) edges, at random points, and rays lying in the vertical plane
/// of a grid line (they run along an edge's line), from outside and above the grid.
fn grid_queries(setup: &RenderJob, c: &mut GridCase, seed: u64) {
    let step = 2.0 * GRID_HALF / GRID_CELLS as f32;
    let mut sampler = Sampler::from_seed(seed);
    let mut targets = Vec::new();
    for j in 1..GRID_CELLS {
        for i in 1..GRID_CELLS {
            let p = Vec3::new(
                -GRID_HALF + i as f32 * step,
                0.0,
                -GRID_HALF + j as f32 * step,
            );
            targets.extend([
                p,
                p + Vec3::new(0.5 * step, 0.0, 0.0),
                p + Vec3::new(0.0, 0.0, 0.5 * step),
                p + Vec3::new(0.5 * step, 0.0, 0.5 * step),
            ]);
        }
    }
    for _ in 0..4000 {
        let u = sampler.next_2d();
        targets.push(Vec3::new(
            (2.0 * u.x - 1.0) * 0.98 * GRID_HALF,
            0.0,
            (2.0 * u.y - 1.0) * 0.98 * GRID_HALF,
        ));
    }
    for (k, &target) in targets.iter().enumerate() {
        // Elevations from 1e-5 to 0.1 rad in half decades; eyes outside the grid, in
        // line with the target.
        let elevation = 10f32.powf(-5.0 + 0.5 * (k % 9) as f32);
        let horiz = [
            Vec3::Z,
            Vec3::X,
            Vec3::new(1.0, 0.0, 1.0).normalize(),
            Vec3::new(-0.3, 0.0, 1.0).normalize(),
        ][k % 4];
        let dist = 2.5 * GRID_HALF;
        let o = target - dist * horiz + Vec3::new(0.0, dist * elevation.tan(), 0.0);
        check_ray(setup, c, o, target, elevation);
    }
}

/// Elevation (rad) below which grazing rays are counted separately.
pub const GRAZING_LIMIT: f32 = 2e-4;

fn check_ray(setup: &RenderJob, c: &mut GridCase, o: Vec3, target: Vec3, elevation: f32) {
    let ray = Ray::new(o, (target - o).normalize());
    let t_exact = (-(o.y as f64)) / ray.d.y as f64;
    let p = ray.o.as_dvec3() + t_exact * ray.d.as_dvec3();
    if !(p.x.abs() < GRID_HALF as f64 * 0.999 && p.z.abs() < GRID_HALF as f64 * 0.999) {
        return;
    }
    let extreme = elevation < GRAZING_LIMIT;
    if extreme {
        c.extreme_rays += 1;
    } else {
        c.rays += 1;
    }
    match setup.accel.intersect(&ray) {
        None if extreme => c.extreme_holes += 1,
        None => c.holes += 1,
        Some(h) => {
            c.max_abs_y = c.max_abs_y.max(ray.at(h.t).y.abs() as f64);
            c.max_rel_t = c.max_rel_t.max((h.t as f64 - t_exact).abs() / t_exact);
        }
    }
}

/// A normals render from 2 cm above the grid: a pixel all of whose corners' rays hit
/// the grid must be the up normal's colour in every sample (a hole would show black).
fn grazing_render(setup: &RenderJob, b: &Budget, c: &mut GridCase) {
    let s = b.settings(RenderSettings {
        shading: Shading::Normals,
        spp: b.spp.max(4),
        ..Default::default()
    });
    let img = setup.render(&s).image;
    let cam = &setup.camera;
    let hits = |x: u32, y: u32| {
        [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)]
            .iter()
            .all(|&(u, v)| {
                let r = cam.generate_ray(x, y, glam::Vec2::new(u, v));
                if r.d.y >= 0.0 {
                    return false;
                }
                let t = -r.o.y / r.d.y;
                let p = r.at(t);
                p.x.abs() < GRID_HALF * 0.999 && p.z.abs() < GRID_HALF * 0.999
            })
    };
    let up = Vec3::new(0.5, 1.0, 0.5);
    for y in 0..cam.height {
        for x in 0..cam.width {
            if hits(x, y) {
                c.covered_pixels += 1;
                if (img.get(x, y) - up).abs().max_element() > 1e-3 {
                    c.hole_pixels += 1;
                }
            }
        }
    }
}

/// Radiance renders of the degenerate-triangle room with every strategy, camera inside.
fn degenerate(b: &Budget, c: &mut GridCase) -> Result<()> {
    let scene = degenerate_room();
    let mut camera = Camera::new(&scene.camera, &scene.bounds, b.width, b.height);
    camera.eye = Vec3::new(0.05, -0.1, -0.95);
    let setup = RenderJob::with_camera(scene, NATIVE, camera)?;
    c.degenerate_all_finite = true;
    for strategy in [
        DirectStrategy::Mis,
        DirectStrategy::Light,
        DirectStrategy::Bsdf,
        DirectStrategy::Hemisphere,
    ] {
        let o = setup.render(&b.settings(RenderSettings {
            max_depth: 5,
            strategy: Some(strategy),
            roulette: Roulette::default(),
            ..Default::default()
        }));
        c.degenerate_nonfinite += o.nonfinite_samples;
        c.degenerate_all_finite &= o.image.all_finite();
        if strategy == DirectStrategy::Mis {
            c.degenerate_mean = o.image.mean_luminance() as f64;
        }
    }
    Ok(())
}

impl GridCase {
    pub fn rows(&self) -> Vec<Row> {
        let row = |method: &str, mean: f64, nonfinite: u64, note: String| Row {
            case: "6 edges/grazing/degenerate".into(),
            method: method.into(),
            mean,
            stderr: 0.0,
            expected: None,
            noise: 0.0,
            nonfinite,
            note,
        };
        vec![
            row("ray queries ≥ 2e-4 rad", self.holes as f64 / self.rays.max(1) as f64, 0, format!("{} of {} rays at vertices/edges/random points, elevation 3e-4..0.1 rad, missed; max |y| {:.1e}, max rel Δt {:.1e}", self.holes, self.rays, self.max_abs_y, self.max_rel_t)),
            row("ray queries 1e-5..1e-4 rad", self.extreme_holes as f64 / self.extreme_rays.max(1) as f64, 0, format!("{} of {} rays at elevations 1e-5, 3e-5 and 1e-4 rad missed", self.extreme_holes, self.extreme_rays)),
            row("grazing normals render", self.hole_pixels as f64 / self.covered_pixels.max(1) as f64, 0, format!("{} of {} fully covered pixels show a hole", self.hole_pixels, self.covered_pixels)),
            row("degenerate triangles", self.degenerate_mean, self.degenerate_nonfinite, format!("all strategies; image finite: {}", self.degenerate_all_finite)),
        ]
    }
}
