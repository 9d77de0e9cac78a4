//! One short function per subcommand: convert the flags, call the library, report.

use super::args::{AccelArg, BenchCommand, BvhArg, QualityArg, RenderArgs};
use super::convert::{
    accel_kind, adopt_scene_from_adaptive, check_resolution, output_path, settings_from,
    threads_invalid,
};
use anyhow::{bail, Context, Result};
use ember::accel::{self, AccelKind};
use ember::bench;
use ember::render::RenderJob;
use ember::scene::{collada, Scene};
use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// `ember [OPTIONS] SCENE`: one render to an image file.
pub(super) fn render(mut args: RenderArgs) -> Result<()> {
    adopt_scene_from_adaptive(&mut args);
    if args.accel == AccelArg::Embree && !cfg!(feature = "embree") {
        bail!("{}", accel::AccelError::EmbreeUnavailable);
    }
    let Some(scene_path) = args.scene.clone() else {
        bail!("no scene given; usage: ember [OPTIONS] SCENE.dae (see ember --help)");
    };
    let (width, height) = (args.resolution[0], args.resolution[1]);
    check_resolution(width, height)?;
    let settings = settings_from(&args)?;
    let out = output_path(&args, &scene_path)?;
    let kind = accel_kind(args.accel, args.bvh, args.embree_quality);
    let pool = thread_pool(args.threads)?;
    let t0 = Instant::now();
    let scene = load_scene(&scene_path)?;
    let t_load = t0.elapsed();
    let t1 = Instant::now();
    let job = pool.install(|| RenderJob::new(scene, kind, width, height))?;
    let t_build = t1.elapsed();
    for w in job.warnings(&settings) {
        eprintln!("ember: warning: {w}");
    }
    let frame = job.full_frame();
    let pb = progress_bar(frame.area(), args.quiet);
    let t2 = Instant::now();
    let output = pool.install(|| job.render_rect(&settings, frame, &|n| pb.inc(n)));
    let t_render = t2.elapsed();
    pb.finish_and_clear();
    ember::image_io::write_image(&output.image, &out)?;
    if settings.adaptive.is_some() {
        let rate = rate_path(&out);
        ember::image_io::write_image(&output.rate_image(settings.spp), &rate)?;
        if !args.quiet {
            eprintln!("ember: sample rate map written to {}", rate.display());
        }
    }
    if output.nonfinite_samples > 0 {
        eprintln!(
            "ember: warning: {} samples were NaN or infinite and were counted as black",
            output.nonfinite_samples
        );
    }
    if !args.quiet {
        let samples = output.total_samples();
        eprintln!(
            "ember: {}: loaded in {:.1} ms, {} built in {:.1} ms, {} samples in {:.3} s ({:.2} M samples/s), wrote {}",
            scene_path.display(),
            t_load.as_secs_f64() * 1e3,
            job.accel.name(),
            t_build.as_secs_f64() * 1e3,
            samples,
            t_render.as_secs_f64(),
            samples as f64 / t_render.as_secs_f64() / 1e6,
            out.display()
        );
        if let Some(s) = output.cost_scale {
            eprintln!("ember: bvh-cost scale: blue = 0, red = {s:.0} nodes + primitives tested per camera ray (99th percentile)");
        }
    }
    Ok(())
}

/// `ember info SCENE`: what the scene holds and the backends of this build.
pub(super) fn info(path: &Path, w: u32, h: u32) -> Result<()> {
    check_resolution(w, h)?;
    let scene = load_scene(path)?;
    println!("{}", path.display());
    print!("{}", ember::info::scene_info(&scene, w, h));
    println!("{}", accel::backends_info());
    Ok(())
}

/// `ember bench ...`: each benchmark runs, writes its report, prints its summary.
pub(super) fn bench(which: BenchCommand) -> Result<()> {
    match which {
        BenchCommand::Stability {
            out,
            spp_scale,
            seed,
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
            })
        }
        BenchCommand::Render {
            scenes,
            spp,
            max_depth,
            repeat,
            accel: a,
            out,
        } => bench_render(bench::render::RenderBenchOptions {
            scenes: if scenes.is_empty() {
                bench::render::RenderBenchOptions::default_scenes()
            } else {
                scenes
            },
            spp,
            max_depth,
            repeat: repeat.max(1),
            accel: accel_kind(a, BvhArg::Sah, QualityArg::Medium),
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
    println!("{}", report.to_markdown());
    println!(
        "wrote {}/stability.csv, stability.md and stability_noise.png/.svg",
        out.display()
    );
    Ok(())
}

fn bench_scaling(out: PathBuf, repeats: usize) -> Result<()> {
    let opts = bench::scaling::ScalingOptions {
        out_dir: out.clone(),
        repeats: repeats.max(1),
        ..Default::default()
    };
    // run_scaling writes its report.
    let report = bench::scaling::run_scaling(&opts, |line| eprintln!("ember: {line}"))?;
    println!("{}", report.to_markdown());
    println!("wrote {}/scaling.csv, scaling.md and charts", out.display());
    Ok(())
}

fn bench_accel(
    scenes: Vec<PathBuf>,
    rays: usize,
    threads: Vec<usize>,
    repeats: usize,
    quality: QualityArg,
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
    if let AccelKind::Embree(q) = accel_kind(AccelArg::Embree, BvhArg::Sah, quality) {
        opts.embree_quality = q;
    }
    let report = run(&opts, |line| eprintln!("ember: {line}"))?;
    println!("{}", report.to_markdown());
    Ok(())
}

fn bench_converge(opts: bench::converge::ConvergeOptions) -> Result<()> {
    let out = &opts.out_dir;
    std::fs::create_dir_all(out).with_context(|| format!("{}: cannot create", out.display()))?;
    let report = bench::converge::run(&opts, &mut |m| eprintln!("ember: {m}"))?;
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
    println!("{}", report.reference_note);
    println!("{}", report.efficiency_table());
    println!(
        "wrote {}.csv and {}_rmse.png/.svg, {}_relmse.png/.svg",
        stem.display(),
        stem.display(),
        stem.display()
    );
    Ok(())
}

fn bench_render(opts: bench::render::RenderBenchOptions) -> Result<()> {
    let report = bench::render::run(&opts)?;
    report.write(&opts.out_dir)?;
    print!("{}", report.to_markdown());
    println!("wrote {}/render.csv and render.md", opts.out_dir.display());
    Ok(())
}

fn load_scene(path: &Path) -> Result<Scene> {
    let scene = collada::load(path)?;
    for w in &scene.warnings {
        eprintln!("ember: warning: {w}");
    }
    Ok(scene)
}

fn thread_pool(threads: Option<usize>) -> Result<rayon::ThreadPool> {
    // Flush-to-zero on every tracing thread, as Embree recommends; the native BVH
    // gives the same image either way (tested).
    let mut b = rayon::ThreadPoolBuilder::new().start_handler(|_| accel::set_flush_denormals());
    if let Some(t) = threads {
        if t == 0 {
            bail!("-t: thread count must be at least 1");
        }
        b = b.num_threads(t);
    }
    Ok(b.build()?)
}

fn progress_bar(total: u64, quiet: bool) -> ProgressBar {
    if quiet || !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let pb = ProgressBar::new(total);
    pb.set_style(
        ProgressStyle::with_template(
            "{spinner} [{elapsed_precise}] {wide_bar} {percent:>3}% ETA {eta}",
        )
        .expect("valid template"),
    );
    pb
}

/// `out.png` → `out_rate.png`: the adaptive sample-rate map beside the image.
fn rate_path(out: &Path) -> PathBuf {
    let stem = out
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    out.with_file_name(format!("{stem}_rate.png"))
}
