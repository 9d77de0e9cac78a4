//! Part 2's table: how long a normal-shaded render of each large mesh takes with
//! ember's BVH, with Embree (in builds that have it) and with no acceleration at all.

use super::page::{Block, TableBlock};
use super::plan::{stem, timed_backends, timing_recipe as recipe, Budget};
use super::recipe::Recipe;
use super::Progress;
use crate::accel::{brute, Backend};
use crate::render::RenderJob;
use anyhow::Result;
use std::path::PathBuf;
use std::time::Instant;

/// A brute-force render estimated to take longer than this is left out of the table.
const LONGEST_BRUTE_FORCE_SECONDS: f64 = 120.0;

/// One timed backend on one scene.
#[derive(Clone, Copy, Debug)]
struct Timing {
    build_ms: f64,
    render_ms: f64,
}

/// Work units of the table: its camera rays per backend and repeat.
pub(super) fn work(scenes: &[PathBuf], b: &Budget) -> u64 {
    let pixels = b.timing.0 as u64 * b.timing.1 as u64;
    let runs: u64 = timed_backends()
        .iter()
        .map(|&k| {
            if k == Backend::None {
                1
            } else {
                b.timing_repeats as u64
            }
        })
        .sum();
    scenes.len() as u64 * pixels * runs
}

/// The table (and the command each column times).
pub(super) fn blocks(
    scenes: &[PathBuf],
    b: &Budget,
    seed: u64,
    progress: &dyn Progress,
) -> Result<Vec<Block>> {
    let backends = timed_backends();
    let mut header = vec!["scene".to_string(), "triangles".to_string()];
    header.extend(backends.iter().map(|&k| column(k)));
    header.push("BVH speed-up (no acceleration ÷ BVH render)".into());
    let mut rows = Vec::new();
    for scene_path in scenes {
        let scene = crate::scene::collada::load(scene_path)?;
        let prims = scene.num_prims();
        let mut cells = vec![stem(scene_path), prims.to_string()];
        let mut times = Vec::new();
        for &backend in &backends {
            let r = recipe(scene_path, b, backend, seed);
            let t = time(&scene, &r, b, progress)?;
            cells.push(match t {
                Some(t) => format!("{} + {}", ms(t.build_ms), ms(t.render_ms)),
                None => format!(
                    "not run (about {:.0} s)",
                    brute_seconds(prims, b.timing.0 as f64 * b.timing.1 as f64)
                ),
            });
            times.push((backend, t));
        }
        let render_of = |k: Backend| times.iter().find(|t| t.0 == k).and_then(|t| t.1);
        cells.push(
            match (render_of(Backend::None), render_of(Backend::Native)) {
                (Some(none), Some(bvh)) => format!("{:.0}×", none.render_ms / bvh.render_ms),
                _ => "—".into(),
            },
        );
        rows.push(cells);
    }
    Ok(vec![
        Block::Table(TableBlock {
            caption: caption(b),
            header,
            rows,
        }),
        Block::Text(commands(b)),
    ])
}

fn column(k: Backend) -> String {
    match k {
        Backend::Native => "BVH (ember's): build + render".into(),
        Backend::Embree => "Embree: build + render".into(),
        Backend::None => "no acceleration: build + render".into(),
        Backend::Auto => "auto".into(),
    }
}

fn caption(b: &Budget) -> String {
    let threads = crate::names::thread_count(rayon::current_num_threads());
    let embree = match Backend::Embree.available() {
        true => " Embree's build includes creating its device, as a render's does.",
        false => " This build has no Embree (build ember with `--features embree` for its column).",
    };
    let runs = match b.timing_repeats {
        0 | 1 => "one run each".to_string(),
        n => format!("the BVH and Embree renders are the median of {n} runs"),
    };
    format!(
        "Render times of one normal-shaded image at {}×{}, 1 sample per pixel, on {} with {threads} \
         (loading excluded; {runs}).{embree}",
        b.timing.0,
        b.timing.1,
        crate::image_metadata::cpu_model(),
    )
}

fn commands(b: &Budget) -> String {
    let r = recipe(std::path::Path::new("SCENE.dae"), b, Backend::Native, 0);
    let command = r
        .command("SCENE.dae", "times.png")
        .replace("--accel native", "--accel BACKEND");
    format!(
        "Each cell times `{command}` with BACKEND `{}`: ember prints the same build and render times on its summary line.",
        timed_backends()
            .iter()
            .map(|k| k.to_string())
            .collect::<Vec<_>>()
            .join("`, `")
    )
}

/// Build and (median) render time of `r` on `scene`; `None` for a brute-force render
/// that would take too long.
fn time(
    scene: &crate::scene::Scene,
    r: &Recipe,
    b: &Budget,
    progress: &dyn Progress,
) -> Result<Option<Timing>> {
    let pixels = r.width as u64 * r.height as u64;
    let repeats = match r.accel {
        Backend::None => {
            if brute_seconds(scene.num_prims(), pixels as f64) > LONGEST_BRUTE_FORCE_SECONDS {
                progress.advance(pixels);
                return Ok(None);
            }
            1
        }
        _ => b.timing_repeats.max(1),
    };
    let t0 = Instant::now();
    let job = RenderJob::new(scene.clone(), r.accel_kind(), r.width, r.height)?;
    let build_ms = t0.elapsed().as_secs_f64() * 1e3;
    let settings = r.settings();
    let mut renders: Vec<f64> = (0..repeats)
        .map(|_| {
            let t = Instant::now();
            job.render_rect(&settings, job.full_frame(), &|n| progress.advance(n));
            t.elapsed().as_secs_f64() * 1e3
        })
        .collect();
    Ok(Some(Timing {
        build_ms,
        render_ms: crate::bench::median(&mut renders),
    }))
}

fn brute_seconds(prims: usize, rays: f64) -> f64 {
    brute::estimated_seconds(prims, rays, rayon::current_num_threads())
}

/// Milliseconds with three significant digits.
fn ms(v: f64) -> String {
    format!("{} ms", crate::bench::measure::three_digits(v))
}
