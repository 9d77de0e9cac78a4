//! `ember bench ...`: each benchmark runs, writes its report, prints its summary.

use super::args::BenchCommand;
use super::convert::{check_resolution, threads_invalid};
use anyhow::{bail, Context, Result};
use ember::accel::{AccelKind, BvhBuilder, EmbreeQuality};
use ember::bench;
use std::path::PathBuf;

/// `ember bench ...`: each benchmark runs, writes its report, prints its summary.
pub(super) fn run(which: BenchCommand) -> Result<()> {
    // `-t` of the benchmarks that run on one rayon pool (accel measures its own list).
    let threads = match &which {
        BenchCommand::Stability { threads, .. }
        | BenchCommand::Converge { threads, .. }
        | BenchCommand::Render { threads, .. } => *threads,
        BenchCommand::Accel { .. } => None,
    };
    super::commands::thread_pool(threads)?.install(|| run_on_pool(which))
}

fn run_on_pool(which: BenchCommand) -> Result<()> {
    match which {
        BenchCommand::Stability {
            out,
            spp_scale,
            seed,
            ..
        } => bench_stability(out, spp_scale, seed),
        BenchCommand::Accel {
            scaling: true,
            out,
            repeats,
            ..
        } => bench_scaling(out, repeats),
        BenchCommand::Accel {
            scenes,
            rays,
            threads,
            repeats,
            quality,
            mesh_triangles,
            ..
        } => bench_accel(scenes, rays, threads, repeats, quality, mesh_triangles),
        BenchCommand::Converge {
            scene,
            reference,
            reference_noise,
            max_depth,
            resolution,
            max_spp,
            max_seconds,
            reference_spp,
            target_rmse,
            out,
            seed,
            mitsuba,
            mitsuba_variants,
            ..
        } => {
            check_resolution(resolution[0], resolution[1])?;
            bench_converge(bench::converge::ConvergeOptions {
                scene,
                reference,
                reference_noise,
                width: resolution[0],
                height: resolution[1],
                max_depth,
                max_spp,
                max_seconds_per_point: max_seconds,
                reference_spp,
                out_dir: out,
                target_rmse,
                seed,
                compare_backends: true,
                mitsuba: mitsuba.map(|python| bench::converge::MitsubaPeer {
                    python,
                    variants: mitsuba_variants,
                }),
            })
        }
        BenchCommand::Render {
            scenes,
            spp,
            max_depth,
            repeats,
            accel: a,
            out,
            ..
        } => bench_render(bench::render::RenderBenchOptions {
            scenes: if scenes.is_empty() {
                bench::render::RenderBenchOptions::default_scenes()
            } else {
                scenes
            },
            spp,
            max_depth,
            repeat: repeats.max(1),
            accel: AccelKind::new(a, BvhBuilder::default(), EmbreeQuality::default()),
            out_dir: out,
        }),
    }
}

fn bench_stability(out: PathBuf, spp_scale: f32, seed: u64) -> Result<()> {
    if !(spp_scale.is_finite() && spp_scale > 0.0) {
        bail!("--spp-scale must be a positive number");
    }
    let opts = bench::stability::StabilityOptions {
        out_dir: out.clone(),
        spp_scale,
        seed,
    };
    // run_stability writes its report.
    let report = bench::stability::run_stability(&opts)?;
    ember::outln!("{}", report.to_markdown())?;
    ember::outln!(
        "wrote {}/stability.csv, stability.md and stability_noise.png/.svg",
        out.display()
    )?;
    Ok(())
}

fn bench_scaling(out: PathBuf, repeats: usize) -> Result<()> {
    let opts = bench::scaling::ScalingOptions {
        out_dir: out.clone(),
        repeats: repeats.max(1),
        ..Default::default()
    };
    // run_scaling writes its report.
    let report = bench::scaling::run_scaling(&opts, |line| ember::errln!("ember: {line}"))?;
    ember::outln!("{}", report.to_markdown())?;
    ember::outln!("wrote {}/scaling.csv, scaling.md and charts", out.display())?;
    Ok(())
}

fn bench_accel(
    scenes: Vec<PathBuf>,
    rays: usize,
    threads: Vec<usize>,
    repeats: usize,
    quality: EmbreeQuality,
    mesh_triangles: usize,
) -> Result<()> {
    use bench::accel::{run, AccelBenchOptions, BenchScene};
    let mut opts = AccelBenchOptions {
        rays,
        threads,
        repeats: repeats.max(1),
        ..Default::default()
    };
    if threads_invalid(&opts.threads) {
        bail!("--threads: each count must be at least 1");
    }
    if !scenes.is_empty() {
        opts.scenes = scenes.into_iter().map(BenchScene::File).collect();
    }
    opts.scenes
        .retain(|s| !matches!(s, BenchScene::DisplacedSphere(_)));
    if mesh_triangles > 0 {
        opts.scenes
            .push(BenchScene::DisplacedSphere(mesh_triangles));
    }
    opts.embree_quality = quality;
    let report = run(&opts, |line| ember::errln!("ember: {line}"))?;
    ember::outln!("{}", report.to_markdown())?;
    Ok(())
}

fn bench_converge(opts: bench::converge::ConvergeOptions) -> Result<()> {
    let out = &opts.out_dir;
    std::fs::create_dir_all(out).with_context(|| format!("{}: cannot create", out.display()))?;
    let report = bench::converge::run(&opts, &mut |m| ember::errln!("ember: {m}"))?;
    let stem_name = opts
        .scene
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let stem = out.join(format!("{stem_name}_m{}", opts.max_depth));
    let title = format!(
        "{stem_name}, -m {}, {}x{}: error vs time",
        opts.max_depth, opts.width, opts.height
    );
    report.write(&stem, &stem_name, &title)?;
    ember::outln!("{}", report.reference_note)?;
    ember::outln!("{}", report.efficiency_table())?;
    ember::outln!(
        "wrote {}.csv and {}_rmse.png/.svg, {}_relmse.png/.svg",
        stem.display(),
        stem.display(),
        stem.display()
    )?;
    Ok(())
}

fn bench_render(opts: bench::render::RenderBenchOptions) -> Result<()> {
    let report = bench::render::run(&opts)?;
    report.write(&opts.out_dir)?;
    ember::out!("{}", report.to_markdown())?;
    ember::outln!("wrote {}/render.csv and render.md", opts.out_dir.display())?;
    Ok(())
}
