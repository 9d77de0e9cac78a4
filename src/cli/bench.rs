//! `ember bench ...`: each benchmark runs, writes its report, prints its summary.

use super::args::BenchCommand;
use super::convert::{check_resolution, threads_invalid};
use anyhow::{bail, Context, Result};
use ember::bench::{self, Report};
use std::path::{Path, PathBuf};

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
        } => bench_scaling(out.unwrap_or_else(|| "bench-out/scaling".into()), repeats),
        BenchCommand::Accel {
            scenes,
            rays,
            threads,
            repeats,
            quality,
            no_embree_modes,
            append,
            out,
            ..
        } => {
            if threads_invalid(&threads) {
                bail!("--threads: each count must be at least 1");
            }
            let defaults = bench::accel::AccelBenchOptions::default();
            let opts = bench::accel::AccelBenchOptions {
                scenes: if scenes.is_empty() {
                    bench::accel::AccelBenchOptions::default_scenes()?
                } else {
                    scenes
                },
                rays,
                threads,
                repeats: repeats.max(1),
                embree_quality: quality,
                embree_modes: !no_embree_modes,
                ..defaults
            };
            bench_accel(
                &opts,
                &out.unwrap_or_else(|| "bench-out/accel".into()),
                append,
            )
        }
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
            embree_steps,
            engines,
            out,
            ..
        } => bench_render(
            bench::render::RenderBenchOptions {
                scenes: if scenes.is_empty() {
                    bench::render::RenderBenchOptions::default_scenes()?
                } else {
                    scenes
                },
                spp,
                max_depth,
                repeat: repeats.max(1),
                accels: bench::render::RenderBenchOptions::accels_for(a, embree_steps),
                engines,
            },
            out,
        ),
    }
}

fn bench_stability(out: PathBuf, spp_scale: f32, seed: u64) -> Result<()> {
    if !(spp_scale.is_finite() && spp_scale > 0.0) {
        bail!("--spp-scale must be a positive number");
    }
    let opts = bench::stability::StabilityOptions { spp_scale, seed };
    finish(&bench::stability::run_stability(&opts)?, &out)
}

fn bench_scaling(out: PathBuf, repeats: usize) -> Result<()> {
    let opts = bench::scaling::ScalingOptions {
        repeats: repeats.max(1),
        ..Default::default()
    };
    let report = bench::scaling::run_scaling(&opts, |line| ember::errln!("ember: {line}"))?;
    finish(&report, &out)
}

fn bench_accel(opts: &bench::accel::AccelBenchOptions, out: &Path, append: bool) -> Result<()> {
    use bench::accel::{run, AccelBenchReport};
    // Read what to append to before the long run, so a missing file fails at once.
    let earlier = if append {
        Some(AccelBenchReport::read(out).context("--append")?)
    } else {
        None
    };
    let report = run(opts, |line| ember::errln!("ember: {line}"))?;
    let report = match earlier {
        Some(e) => e.merge(report),
        None => report,
    };
    finish(&report, out)
}

fn bench_converge(opts: bench::converge::ConvergeOptions) -> Result<()> {
    let report = bench::converge::run(&opts, &mut |m| ember::errln!("ember: {m}"))?;
    finish(&report, &opts.out_dir)
}

fn bench_render(opts: bench::render::RenderBenchOptions, out: PathBuf) -> Result<()> {
    finish(&bench::render::run(&opts)?, &out)
}

/// The end of every benchmark: write its report into `out`, print its summary and the files.
fn finish(report: &impl Report, out: &Path) -> Result<()> {
    let files = report.write(out)?;
    ember::outln!("{}", report.summary().trim_end())?;
    let files: Vec<String> = files.iter().map(|f| f.display().to_string()).collect();
    ember::outln!("wrote {}", files.join(", "))?;
    Ok(())
}
