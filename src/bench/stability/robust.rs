//! Cases 5 and 6: geometric robustness. The same scene at another scale or far from
//! the origin must give the same image (self-intersection offsets are relative), and
//! rays along edges, through shared vertices or at grazing angles must not slip
//! through a closed mesh; degenerate triangles must not produce NaN.

use super::light_paths::student_t_two_sided;
use super::measure::{lum, Budget, NATIVE};
use super::scenes::{degenerate_room, embedded, grid_plane, transformed, GRID_CELLS, GRID_HALF};
use super::Row;
use crate::accel::AccelKind;
use crate::camera::Camera;
use crate::geometry::Ray;
use crate::integrators::{DirectStrategy, Roulette};
use crate::render::{RenderJob, RenderSettings, Shading};
use crate::sampling::Rng;
use crate::scene::Scene;
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
    /// Fraction of surface pixels differing by more than 4 per-pixel noise σ (σ from
    /// the halves). Only surfaces: a pixel on a light's edge jumps by its coverage when
    /// one camera sample lands on the light's other side, as a scaled light's corners
    /// round differently.
    pub frac_beyond_noise: f64,
    pub nonfinite: u64,
    /// Translations only: surfaces and every surface block against the rounded
    /// original over `TEST_SEEDS` seeds.
    pub seeds: Option<SeedsTest>,
    /// Translations only: the surface mean of the original rounded as the translation
    /// rounds it (`rounded_original`, what this run is compared with) against the
    /// original itself, relative, with its paired standard error: the input's own
    /// rounding, which no renderer can undo.
    pub input_rounding: Option<(f64, f64)>,
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
    let blocks = SurfaceBlocks::new(b.width, b.height, &surface, 8);
    let mut runs = Vec::new();
    for (name, k, off) in SCALE_VARIANTS {
        let setup = b.job(transformed(&base_scene, k, Vec3::splat(off)))?;
        let o = setup.render(&s);
        if off == 0.0 {
            // A scaled copy must render the original.
            let mut run = compare(name, k, off, &reference.image, &o, sigma, &surface);
            (run.surface_rel_diff, run.surface_rel_se) =
                paired_relative_diff(&reference.image, &o.image, &surface);
            runs.push(run);
            continue;
        }
        // A translated one, the original with the translation's rounding (the scene
        // itself moves on the f32 grid there).
        let near = rounded_original(&base_scene, &setup, k, off)?;
        let r = near.render(&s);
        let mut run = compare(name, k, off, &r.image, &o, sigma, &surface);
        (run.surface_rel_diff, run.surface_rel_se) =
            paired_relative_diff(&r.image, &o.image, &surface);
        run.input_rounding = Some(paired_relative_diff(&reference.image, &r.image, &surface));
        let mut pairs = vec![(o.image, r.image)];
        for seed in (1..TEST_SEEDS).map(|i| b.seed.wrapping_add(i)) {
            let s = RenderSettings { seed, ..s.clone() };
            pairs.push((setup.render(&s).image, near.render(&s).image));
        }
        run.seeds = Some(SeedsTest::new(&blocks, &surface, &pairs));
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

/// The original scaled by `k` and rounded as its translation by `off` (`far`) rounds
/// it, back at the origin: translated there and back, which is exact (Sterbenz), seen
/// by `far`'s camera moved back with it, so that only the renderer's arithmetic far
/// from the origin differs.
fn rounded_original(original: &Scene, far: &RenderJob, k: f32, off: f32) -> Result<RenderJob> {
    let back = Vec3::splat(-off);
    let scene = transformed(&transformed(original, k, -back), 1.0, back);
    let mut camera = far.camera;
    camera.eye += back;
    Ok(RenderJob::with_camera(scene, NATIVE, camera)?)
}

/// Pixels whose corners and centre all see a surface that is not an emitter (no
/// background either: a silhouette's noise is its coverage's, badly estimated from a block).
fn surface_pixels(setup: &RenderJob) -> Vec<usize> {
    let cam = &setup.camera;
    let not_surface = |x: u32, y: u32| {
        [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0), (0.5, 0.5)]
            .iter()
            .any(|&(u, v)| {
                let r = cam.generate_ray(x, y, glam::Vec2::new(u, v));
                setup.accel.intersect(&r).is_none_or(|h| {
                    let si = setup.scene.interaction(&r, &h);
                    !setup.scene.materials[si.material as usize].scatters()
                })
            })
    };
    (0..cam.height)
        .flat_map(|y| (0..cam.width).map(move |x| (x, y)))
        .filter(|&(x, y)| !not_surface(x, y))
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

/// The `b × b` blocks made only of surface pixels (indices in `Image::block_average(b)`).
/// Blocks showing an emitter or the background are left out, as for the surface mean:
/// their edges move with the rounding of the geometry itself.
struct SurfaceBlocks {
    b: u32,
    blocks: Vec<usize>,
}

impl SurfaceBlocks {
    fn new(w: u32, h: u32, surface: &[usize], b: u32) -> Self {
        let mut is_surface = vec![false; (w * h) as usize];
        surface.iter().for_each(|&i| is_surface[i] = true);
        let (bw, bh) = (w / b, h / b);
        let blocks = (0..bw * bh)
            .filter(|&k| {
                let (bx, by) = (k % bw, k / bw);
                (0..b * b).all(|j| is_surface[((by * b + j / b) * w + bx * b + j % b) as usize])
            })
            .map(|k| k as usize)
            .collect();
        SurfaceBlocks { b, blocks }
    }
}

/// Seeds (`Budget::seed` and the next ones) of a translated copy's `SeedsTest`.
pub const TEST_SEEDS: u64 = 12;

/// A translated copy against the rounded original over `TEST_SEEDS` seeds (the two
/// renders of a pair share theirs), so that every noise below is measured, not
/// estimated from one render: the spread across pairs is the difference's own noise.
/// (One pair's block noise estimated from 64 pixels of two halves is not enough: two
/// independent renders of the same scene put their worst block 3–16 σ apart that way.)
///
/// "Within noise" per 8×8 surface block: its systematic difference `μ` is below the
/// noise `σ` of one render's block mean. Same-seed pairs differ deterministically
/// wherever the arithmetic does (a 1e4 copy rounds to 1e-3), so `μ = 0` is not the
/// question; `|μ| ≤ σ` is, tested one-sided by `t = (|d̄| − σ)/se(d̄)` at Šidák's level
/// for 1 % family-wise.
#[derive(Clone, Debug)]
pub struct SeedsTest {
    pub seeds: usize,
    /// Surface mean difference relative to the rounded original's, over the pairs,
    /// and its standard error (from their spread).
    pub surface_rel_diff: f64,
    pub surface_rel_se: f64,
    pub blocks: usize,
    /// The block with the largest `t`: `t`, its one-sided p-value, `d̄/σ` and its
    /// top-left pixel.
    pub worst_t: f64,
    pub worst_p: f64,
    pub worst_shift: f64,
    pub worst_at: (u32, u32),
    /// Šidák's per-block level for 1 % family-wise over `blocks`.
    pub level: f64,
}

impl SeedsTest {
    /// From `(translated, rounded original)` image pairs.
    fn new(
        blocks: &SurfaceBlocks,
        surface: &[usize],
        pairs: &[(crate::film::Image, crate::film::Image)],
    ) -> Self {
        let k = pairs.len();
        let mean_se = |x: &[f64]| {
            let m = x.iter().sum::<f64>() / k as f64;
            let var = x.iter().map(|v| (v - m).powi(2)).sum::<f64>() / (k as f64 - 1.0);
            (m, (var / k as f64).sqrt())
        };
        let surface_diffs: Vec<f64> = pairs
            .iter()
            .map(|(far, near)| paired_relative_diff(near, far, surface).0)
            .collect();
        let (surface_rel_diff, surface_rel_se) = mean_se(&surface_diffs);
        // Per pair, per block: (difference, rounded original) of the block means.
        let per_pair: Vec<Vec<(f64, f64)>> = pairs
            .iter()
            .map(|(far, near)| {
                let (fa, na) = (far.block_average(blocks.b), near.block_average(blocks.b));
                blocks
                    .blocks
                    .iter()
                    .map(|&i| (lum(&fa, i) - lum(&na, i), lum(&na, i)))
                    .collect()
            })
            .collect();
        let bw = pairs[0].0.width / blocks.b;
        let mut test = SeedsTest {
            seeds: k,
            surface_rel_diff,
            surface_rel_se,
            blocks: blocks.blocks.len(),
            worst_t: f64::NEG_INFINITY,
            worst_p: 1.0,
            worst_shift: 0.0,
            worst_at: (0, 0),
            level: 1.0 - 0.99f64.powf(1.0 / blocks.blocks.len().max(1) as f64),
        };
        for (j, &i) in blocks.blocks.iter().enumerate() {
            let d: Vec<f64> = per_pair.iter().map(|b| b[j].0).collect();
            let near: Vec<f64> = per_pair.iter().map(|b| b[j].1).collect();
            let (d_mean, d_se) = mean_se(&d);
            // One render's block noise: the spread of the rounded original's block means.
            let sigma = mean_se(&near).1 * (k as f64).sqrt();
            let excess = d_mean.abs() - sigma;
            let t = if d_se > 0.0 {
                excess / d_se
            } else if excess > 0.0 {
                f64::INFINITY
            } else {
                f64::NEG_INFINITY
            };
            if t > test.worst_t {
                test.worst_t = t;
                test.worst_p = if t > 0.0 {
                    0.5 * student_t_two_sided(t, k as f64 - 1.0)
                } else {
                    1.0
                };
                test.worst_shift = if sigma > 0.0 { d_mean / sigma } else { 0.0 };
                test.worst_at = (i as u32 % bw * blocks.b, i as u32 / bw * blocks.b);
            }
        }
        test
    }

    /// No block beyond its noise, at 1 % family-wise.
    pub fn blocks_within_noise(&self) -> bool {
        self.worst_p >= self.level
    }
}

fn compare(
    name: &str,
    scale: f32,
    offset: f32,
    reference: &crate::film::Image,
    o: &crate::render::RenderOutput,
    sigma: f64,
    surface: &[usize],
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
    let beyond = surface
        .iter()
        .filter(|&&i| d[i].abs() > 4.0 * sigma)
        .count();
    ScaledRun {
        name: name.into(),
        scale,
        offset,
        mean: (0..n).map(|i| lum(&o.image, i)).sum::<f64>() / n as f64,
        diff_se: (var_d / n as f64).sqrt(),
        surface_rel_diff: 0.0,
        surface_rel_se: 0.0,
        frac_changed: changed as f64 / n as f64,
        frac_beyond_noise: beyond as f64 / surface.len().max(1) as f64,
        nonfinite: o.nonfinite_samples,
        seeds: None,
        input_rounding: None,
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
                "{}{:.1}% of pixels changed, {:.2}% of surfaces beyond 4σ; surfaces {:+.3}% ± {:.3}%{}",
                r.input_rounding.map_or(String::new(), |(d, se)| format!(
                    "against the original rounded as here (that rounding itself: surfaces {:+.3}% ± {:.3}%): ",
                    100.0 * d,
                    100.0 * se
                )),
                100.0 * r.frac_changed,
                100.0 * r.frac_beyond_noise,
                100.0 * r.surface_rel_diff,
                100.0 * r.surface_rel_se,
                r.seeds.as_ref().map_or(String::new(), |t| format!(
                    "; over {} seeds: surfaces {:+.3}% ± {:.3}%, largest 8×8 block shift {:+.2} σ of one render (t = {:.1} beyond 1 σ, p = {:.1e} against Šidák's {:.1e} for {} blocks) at {:?}",
                    t.seeds,
                    100.0 * t.surface_rel_diff,
                    100.0 * t.surface_rel_se,
                    t.worst_shift,
                    t.worst_t,
                    t.worst_p,
                    t.level,
                    t.blocks,
                    t.worst_at
                )),
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
    grid_with(b, NATIVE)
}

/// Case 6 through a backend of `kind` (the Embree tests run it through Embree).
pub fn grid_with(b: &Budget, kind: AccelKind) -> Result<GridCase> {
    let mut c = GridCase::default();
    let setup = grid_job(b, kind)?;
    grid_queries(&setup, &mut c, b.seed);
    grazing_render(&setup, b, &mut c);
    degenerate(b, kind, &mut c)?;
    Ok(c)
}

/// Only case 6's ray queries, through a backend of `kind`: the holes of `GridCase`.
pub fn grid_queries_with(kind: AccelKind, seed: u64) -> Result<GridCase> {
    let mut c = GridCase::default();
    let b = Budget {
        width: 1,
        height: 1,
        spp: 1,
        seed,
    };
    grid_queries(&grid_job(&b, kind)?, &mut c, seed);
    Ok(c)
}

fn grid_job(b: &Budget, kind: AccelKind) -> Result<RenderJob> {
    let scene = grid_plane();
    let mut camera = Camera::new(&scene.camera, &scene.bounds, b.width, b.height);
    camera.eye = Vec3::new(0.0, 0.02, -GRID_HALF - 0.5);
    Ok(RenderJob::with_camera(scene, kind, camera)?)
}

/// Rays at grazing elevations aimed at every inner vertex, at the midpoints of shared
/// (axis and diagonal) edges, at random points, and rays lying in the vertical plane
/// of a grid line (they run along an edge's line), from outside and above the grid.
fn grid_queries(setup: &RenderJob, c: &mut GridCase, seed: u64) {
    let step = 2.0 * GRID_HALF / GRID_CELLS as f32;
    let mut sampler = Rng::from_seed(seed);
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
fn degenerate(b: &Budget, kind: AccelKind, c: &mut GridCase) -> Result<()> {
    let scene = degenerate_room();
    let mut camera = Camera::new(&scene.camera, &scene.bounds, b.width, b.height);
    camera.eye = Vec3::new(0.05, -0.1, -0.95);
    let setup = RenderJob::with_camera(scene, kind, camera)?;
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
