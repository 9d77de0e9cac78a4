//! Argument parsing and the glue from flags to library calls. Nothing in the
//! library depends on this module.

use anyhow::{bail, Context, Result};
use clap::{Args, Parser, Subcommand, ValueEnum};
use ember::accel::{self, AccelKind, BvhBuilder, EmbreeQuality};
use ember::camera::Camera;
use ember::integrators::{DirectStrategy, Estimator, Roulette};
use ember::render::{self, Adaptive, RenderSettings, Shading};
use ember::scene::{collada, Scene};
use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// ember — a physically based CPU path tracer for the CS184 COLLADA scenes.
///
/// Accepts the CS184 pathtracer command line verbatim, e.g.
///   ember -t 8 -s 64 -l 16 -m 5 -r 480 360 -f out.png scene.dae
#[derive(Parser, Debug)]
#[command(name = "ember", version, about, long_about = None, args_conflicts_with_subcommands = true)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Option<Command>,
    #[command(flatten)]
    pub render: RenderArgs,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Print what a scene contains (geometry, lights, materials, camera, bounds) and the backends of this build.
    Info {
        /// The .dae scene file.
        scene: PathBuf,
        /// Resolution at which to report the camera's field of view.
        #[arg(short = 'r', num_args = 2, value_names = ["WIDTH", "HEIGHT"], default_values_t = [480, 360])]
        resolution: Vec<u32>,
    },
    /// Measure speed: `ember bench render` (samples/s of full renders).
    Bench {
        #[command(subcommand)]
        which: BenchCommand,
    },
}

#[derive(Subcommand, Debug)]
pub enum BenchCommand {
    /// Where methods fail: a row per case (delta lights, tiny lights, glossy vs rough, caustics, scale, grazing rays,
    /// adaptive sampling, roulette) with what each method does there. Writes stability.csv, stability.md and a chart.
    Stability {
        /// Output folder.
        #[arg(long, default_value = "bench-out/stability")]
        out: PathBuf,
        /// Multiplies every case's samples per pixel.
        #[arg(long, default_value_t = 1.0)]
        spp_scale: f32,
        /// Random seed.
        #[arg(long, default_value_t = 0)]
        seed: u64,
    },
    /// Build time, memory and Mrays/s (camera, incoherent, shadow rays) of every backend this build has,
    /// at each thread count, with the native/Embree ratio. Default scenes: CBbunny, CBspheres_lambertian, a ~1M-triangle displaced sphere.
    Accel {
        /// Scenes to measure instead of the defaults.
        scenes: Vec<PathBuf>,
        /// Incoherent and shadow rays per measurement (camera rays are 480x360).
        #[arg(long, default_value_t = 500_000)]
        rays: usize,
        /// Thread counts to measure.
        #[arg(long, value_delimiter = ',', default_values_t = [1, 2])]
        threads: Vec<usize>,
        /// Each figure is the median of this many runs.
        #[arg(long, default_value_t = 5)]
        repeats: usize,
        /// Embree's build quality.
        #[arg(long, value_enum, default_value_t = QualityArg::Medium)]
        quality: QualityArg,
        /// Triangle count of the generated displaced sphere (0 leaves it out).
        #[arg(long, default_value_t = 1_000_000)]
        mesh_triangles: usize,
        /// Instead: generated meshes (displaced sphere, random soup) from 1k to 4M triangles, every native builder and
        /// Embree quality, charted against triangle count (log-log) with fitted growth. Writes CSV, Markdown and charts to --out.
        #[arg(long)]
        scaling: bool,
        /// Output folder of --scaling.
        #[arg(long, default_value = "bench-out/scaling")]
        out: PathBuf,
    },
    /// Error against render time for each method (direct: hemisphere / light / MIS; GI: roulette, -l, adaptive, backends).
    /// Writes <out>/<scene>_m<M>.csv and error-vs-time charts (PNG and SVG), prints the time each method needs to reach an error.
    Converge {
        /// The .dae scene.
        scene: PathBuf,
        /// Reference image (linear EXR at the render resolution). Default: ember's own high-spp render, cached under <out>/cache.
        #[arg(long)]
        reference: Option<PathBuf>,
        /// Per-pixel RMS noise of --reference, if known (e.g. noise_rmse_per_pixel from the references' manifest); subtracted from every MSE.
        #[arg(long)]
        reference_noise: Option<f64>,
        /// Max ray depth.
        #[arg(short = 'm', default_value_t = 1)]
        max_depth: u32,
        /// Resolution.
        #[arg(short = 'r', num_args = 2, value_names = ["WIDTH", "HEIGHT"], default_values_t = [160, 120])]
        resolution: Vec<u32>,
        /// Largest spp of the doubling sequence 1, 2, 4, ...
        #[arg(long, default_value_t = 1024)]
        max_spp: u32,
        /// Stop doubling a method once one render takes longer than this (seconds).
        #[arg(long, default_value_t = 8.0)]
        max_seconds: f64,
        /// spp of ember's own reference.
        #[arg(long, default_value_t = 8192)]
        reference_spp: u32,
        /// RMSE whose time-to-reach is tabulated (default: the median of the methods' final RMSEs).
        #[arg(long)]
        target_rmse: Option<f64>,
        /// Output folder.
        #[arg(long, default_value = "bench-out")]
        out: PathBuf,
        /// Random seed.
        #[arg(long, default_value_t = 0)]
        seed: u64,
    },
    /// Samples per second for CBspheres_lambertian and CBbunny at 480x360, 64 spp, -m 5.
    Render {
        /// Scenes to render (default: the two CS184 scenes from ../shared).
        scenes: Vec<PathBuf>,
        /// Samples per pixel.
        #[arg(short = 's', default_value_t = 64)]
        spp: u32,
        /// Max ray depth.
        #[arg(short = 'm', default_value_t = 5)]
        max_depth: u32,
        /// Repetitions per scene (the median is reported).
        #[arg(long, default_value_t = 3)]
        repeat: u32,
        /// Backend.
        #[arg(long, value_enum, default_value_t = AccelArg::Native)]
        accel: AccelArg,
    },
}

#[derive(Args, Debug)]
pub struct RenderArgs {
    /// The .dae scene to render.
    pub scene: Option<PathBuf>,

    /// Worker threads (default: all cores). The image does not depend on it.
    #[arg(short = 't', value_name = "THREADS")]
    pub threads: Option<usize>,

    /// Camera rays (samples) per pixel; with -a, the cap per pixel.
    #[arg(short = 's', value_name = "SPP", default_value_t = 1)]
    pub spp: u32,

    /// Light samples per area light at every shading point (delta lights take one).
    #[arg(short = 'l', value_name = "SAMPLES", default_value_t = 1)]
    pub light_samples: u32,

    /// Max ray depth: the most bounces (scattering events) a counted path may have. 0 = emitters only, 1 = direct lighting.
    #[arg(short = 'm', value_name = "DEPTH", default_value_t = 1)]
    pub max_depth: u32,

    /// Accumulate bounces: 1 (default) sums all paths of up to -m bounces, 0 keeps only paths of exactly -m bounces.
    #[arg(short = 'o', value_name = "0|1", default_value_t = 1, value_parser = clap::value_parser!(u8).range(0..=1))]
    pub accumulate: u8,

    /// Adaptive sampling: after every BATCH samples stop a pixel once 1.96·σ/√n ≤ TOL·μ (or at -s). A pixel whose samples are all zero stops only if every pixel within 5 px saw constant values in its first batch, so light found rarely is not missed (README). `-a` alone means 32 0.05.
    #[arg(short = 'a', num_args = 0..=2, value_names = ["BATCH", "TOL"])]
    pub adaptive: Option<Vec<String>>,

    /// Direct lighting by uniform hemisphere sampling instead of light sampling (cannot see point/directional lights).
    #[arg(short = 'H')]
    pub hemisphere: bool,

    /// Output image; .png (8-bit sRGB) or .exr (linear float). Default: <scene stem>.png.
    #[arg(short = 'f', value_name = "FILE")]
    pub output: Option<PathBuf>,

    /// Resolution of the image.
    #[arg(short = 'r', num_args = 2, value_names = ["WIDTH", "HEIGHT"], default_values_t = [480, 360])]
    pub resolution: Vec<u32>,

    /// Intersection backend.
    #[arg(long, value_enum, default_value_t = AccelArg::Native)]
    pub accel: AccelArg,

    /// How the native BVH is built.
    #[arg(long, value_enum, default_value_t = BvhArg::Sah)]
    pub bvh: BvhArg,

    /// Embree's build quality (with --accel embree).
    #[arg(long, value_enum, default_value_t = QualityArg::Medium)]
    pub embree_quality: QualityArg,

    /// What each pixel shows.
    #[arg(long, value_enum, default_value_t = ShadingArg::Radiance)]
    pub shading: ShadingArg,

    /// Estimator. auto: light tracing when every light is a point light and nothing is specular or self-emitting (CBempty: see BENCHMARKS.md, stability case 9); otherwise path tracing with MIS (light + BSDF sampling) when the scene has glossy surfaces or an ambient light, light sampling otherwise. -H forces hemisphere.
    #[arg(long, value_enum, default_value_t = IntegratorArg::Auto)]
    pub integrator: IntegratorArg,

    /// Russian roulette: off, throughput (continue with probability max(throughput), at least 0.05), or a fixed probability like 0.5.
    #[arg(long, default_value = "throughput", value_name = "off|throughput|PROB")]
    pub rr: String,

    /// First bounce at which Russian roulette may end a path.
    #[arg(long, default_value_t = 3, value_name = "BOUNCE")]
    pub rr_start: u32,

    /// Random seed; the same seed gives the same image whatever -t is.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,

    /// No progress bar and no summary.
    #[arg(short = 'q', long)]
    pub quiet: bool,
}

#[derive(Clone, Copy, Debug, ValueEnum, PartialEq, Eq)]
pub enum AccelArg {
    /// ember's own BVH.
    Native,
    /// Intel Embree (builds with --features embree only).
    Embree,
}

#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum BvhArg {
    /// Binned surface-area heuristic.
    Sah,
    /// The course's split at the centroid midpoint of the longest axis.
    Midpoint,
}

#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum QualityArg {
    Low,
    Medium,
    High,
}

#[derive(Clone, Copy, Debug, ValueEnum, PartialEq, Eq)]
pub enum ShadingArg {
    /// The physically based image.
    Radiance,
    /// 0.5·n + 0.5 of the shading normal (course parts 1-2).
    Normals,
    /// Heat map of BVH nodes + primitives tested per camera ray.
    BvhCost,
}

#[derive(Clone, Copy, Debug, ValueEnum, PartialEq, Eq)]
pub enum IntegratorArg {
    Auto,
    /// Light sampling only.
    Light,
    /// Light and BSDF sampling, power heuristic.
    Mis,
    /// Uniform hemisphere sampling (same as -H).
    Hemisphere,
    /// BSDF sampling alone, no light sampling (cannot see point/directional lights).
    Bsdf,
    /// Light tracing: paths start on the lights and connect to the camera (not for mirrors/glass).
    LightTracing,
}

pub fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Some(Command::Info { scene, resolution }) => info(&scene, resolution[0], resolution[1]),
        Some(Command::Bench { which }) => bench(which),
        None => render_command(cli.render),
    }
}

fn load_scene(path: &Path) -> Result<Scene> {
    let scene = collada::load(path)?;
    for w in &scene.warnings {
        eprintln!("ember: warning: {w}");
    }
    Ok(scene)
}

fn info(path: &Path, w: u32, h: u32) -> Result<()> {
    check_resolution(w, h)?;
    let scene = load_scene(path)?;
    println!("{}", path.display());
    print!("{}", ember::info::scene_info(&scene, w, h));
    println!("{}", accel::backends_info());
    Ok(())
}

fn check_resolution(w: u32, h: u32) -> Result<()> {
    if w == 0 || h == 0 || (w as u64) * (h as u64) > 1 << 28 {
        bail!("resolution {w}x{h} is out of range (each side ≥ 1, at most 2^28 pixels)");
    }
    Ok(())
}

fn accel_kind(a: AccelArg, b: BvhArg, q: QualityArg) -> AccelKind {
    match a {
        AccelArg::Native => AccelKind::Native(match b {
            BvhArg::Sah => BvhBuilder::Sah,
            BvhArg::Midpoint => BvhBuilder::Midpoint,
        }),
        AccelArg::Embree => AccelKind::Embree(match q {
            QualityArg::Low => EmbreeQuality::Low,
            QualityArg::Medium => EmbreeQuality::Medium,
            QualityArg::High => EmbreeQuality::High,
        }),
    }
}

fn parse_adaptive(a: &Option<Vec<String>>) -> Result<Option<Adaptive>> {
    let Some(v) = a else { return Ok(None) };
    let batch: u32 = match v.first() {
        Some(s) => s
            .parse()
            .ok()
            .filter(|&b| b > 0)
            .with_context(|| format!("-a: BATCH must be a positive integer, got {s:?}"))?,
        None => 32,
    };
    let tol: f32 = match v.get(1) {
        Some(s) => s
            .parse()
            .ok()
            .filter(|t: &f32| t.is_finite() && *t > 0.0)
            .with_context(|| format!("-a: TOL must be a positive number, got {s:?}"))?,
        None => 0.05,
    };
    Ok(Some(Adaptive::new(batch, tol)))
}

fn parse_roulette(s: &str, start: u32) -> Result<Roulette> {
    Ok(match s {
        "off" => Roulette::Off,
        "throughput" => Roulette::Throughput {
            start,
            min_prob: 0.05,
        },
        p => {
            let prob: f32 = p
                .parse()
                .ok()
                .filter(|q: &f32| *q > 0.0 && *q <= 1.0)
                .with_context(|| {
                    format!("--rr: expected off, throughput or a probability in (0, 1], got {p:?}")
                })?;
            Roulette::Fixed { start, prob }
        }
    })
}

/// The requested estimator; `None` for auto, which depends on the scene.
fn strategy(args: &RenderArgs) -> Option<DirectStrategy> {
    if args.hemisphere {
        return Some(DirectStrategy::Hemisphere);
    }
    match args.integrator {
        IntegratorArg::Light => Some(DirectStrategy::Light),
        IntegratorArg::Mis => Some(DirectStrategy::Mis),
        IntegratorArg::Hemisphere => Some(DirectStrategy::Hemisphere),
        IntegratorArg::Bsdf => Some(DirectStrategy::Bsdf),
        IntegratorArg::LightTracing => Some(DirectStrategy::Light),
        IntegratorArg::Auto => None,
    }
}

fn settings_from(args: &RenderArgs) -> Result<RenderSettings> {
    let (w, h) = (args.resolution[0], args.resolution[1]);
    check_resolution(w, h)?;
    if args.spp == 0 {
        bail!("-s: samples per pixel must be at least 1");
    }
    Ok(RenderSettings {
        width: w,
        height: h,
        spp: args.spp,
        light_samples: args.light_samples.max(1),
        max_depth: args.max_depth,
        accumulate: args.accumulate == 1,
        estimator: match args.integrator {
            IntegratorArg::LightTracing => Estimator::LightTracing,
            _ => Estimator::Path,
        },
        strategy: strategy(args).unwrap_or(DirectStrategy::Light),
        roulette: parse_roulette(&args.rr, args.rr_start)?,
        adaptive: parse_adaptive(&args.adaptive)?,
        shading: match args.shading {
            ShadingArg::Radiance => Shading::Radiance,
            ShadingArg::Normals => Shading::Normals,
            ShadingArg::BvhCost => Shading::BvhCost,
        },
        seed: args.seed,
    })
}

fn output_path(args: &RenderArgs, scene: &Path) -> Result<PathBuf> {
    let out = match &args.output {
        Some(p) => p.clone(),
        None => PathBuf::from(format!(
            "{}.png",
            scene
                .file_stem()
                .map(|s| s.to_string_lossy())
                .unwrap_or("ember".into())
        )),
    };
    ember::image_io::OutputFormat::from_path(&out)?;
    Ok(out)
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

fn render_command(mut args: RenderArgs) -> Result<()> {
    adopt_scene_from_adaptive(&mut args);
    if args.accel == AccelArg::Embree && !cfg!(feature = "embree") {
        bail!("{}", accel::AccelError::EmbreeUnavailable);
    }
    let Some(scene_path) = args.scene.clone() else {
        bail!("no scene given; usage: ember [OPTIONS] SCENE.dae (see ember --help)");
    };
    let settings = settings_from(&args)?;
    let out = output_path(&args, &scene_path)?;
    let kind = accel_kind(args.accel, args.bvh, args.embree_quality);
    let pool = thread_pool(args.threads)?;
    let t0 = Instant::now();
    let scene = load_scene(&scene_path)?;
    let t_load = t0.elapsed();
    let settings = RenderSettings {
        strategy: strategy(&args).unwrap_or_else(|| DirectStrategy::auto_for(&scene)),
        estimator: match args.integrator {
            IntegratorArg::Auto if !args.hemisphere => Estimator::auto_for(&scene),
            _ => settings.estimator,
        },
        ..settings
    };
    let t1 = Instant::now();
    let accel = pool.install(|| accel::build(&scene, kind))?;
    let t_build = t1.elapsed();
    let camera = Camera::new(
        &scene.camera,
        &scene.bounds,
        settings.width,
        settings.height,
    );
    for w in render::render_warnings(&scene, &settings) {
        eprintln!("ember: warning: {w}");
    }
    let pb = progress_bar((settings.width * settings.height) as u64, args.quiet);
    let t2 = Instant::now();
    let output =
        pool.install(|| render::render(&scene, accel.as_ref(), &camera, &settings, &|n| pb.inc(n)));
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
            accel.name(),
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

/// `-a` takes up to two values, so `ember -a scene.dae` hands the scene to `-a`;
/// give it back when it is clearly not a number.
fn adopt_scene_from_adaptive(args: &mut RenderArgs) {
    if args.scene.is_some() {
        return;
    }
    if let Some(v) = args.adaptive.as_mut() {
        if v.last().is_some_and(|s| s.parse::<f64>().is_err()) {
            args.scene = v.pop().map(PathBuf::from);
        }
    }
}

fn threads_invalid(t: &[usize]) -> bool {
    t.is_empty() || t.contains(&0)
}

fn rate_path(out: &Path) -> PathBuf {
    let stem = out
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    out.with_file_name(format!("{stem}_rate.png"))
}

fn bench(which: BenchCommand) -> Result<()> {
    match which {
        BenchCommand::Stability {
            out,
            spp_scale,
            seed,
        } => {
            if !(spp_scale.is_finite() && spp_scale > 0.0) {
                bail!("--spp-scale must be a positive number");
            }
            let opts = ember::bench::stability::StabilityOptions {
                out_dir: out.clone(),
                spp_scale,
                seed,
            };
            let report = ember::bench::stability::run_stability(&opts)?;
            println!("{}", report.to_markdown());
            println!(
                "wrote {}/stability.csv, stability.md and stability_noise.png/.svg",
                out.display()
            );
            Ok(())
        }
        BenchCommand::Accel {
            scaling: true,
            out,
            repeats,
            ..
        } => {
            let opts = ember::bench::scaling::ScalingOptions {
                out_dir: out.clone(),
                repeats: repeats.max(1),
                ..Default::default()
            };
            let report =
                ember::bench::scaling::run_scaling(&opts, |line| eprintln!("ember: {line}"))?;
            println!("{}", report.to_markdown());
            println!("wrote {}/scaling.csv, scaling.md and charts", out.display());
            Ok(())
        }
        BenchCommand::Accel {
            scenes,
            rays,
            threads,
            repeats,
            quality,
            mesh_triangles,
            ..
        } => {
            use ember::bench::accel::{run, AccelBenchOptions, BenchScene};
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
            std::fs::create_dir_all(&out)
                .with_context(|| format!("{}: cannot create", out.display()))?;
            let opts = ember::bench::converge::ConvergeOptions {
                scene: scene.clone(),
                reference,
                reference_noise,
                width: resolution[0],
                height: resolution[1],
                max_depth,
                max_spp,
                max_seconds_per_point: max_seconds,
                reference_spp,
                out_dir: out.clone(),
                target_rmse,
                seed,
                compare_backends: true,
            };
            let report = ember::bench::converge::run(&opts, &mut |m| eprintln!("ember: {m}"))?;
            let stem_name = scene
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default();
            let stem = out.join(format!("{stem_name}_m{max_depth}"));
            let title = format!(
                "{stem_name}, -m {max_depth}, {}x{}: error vs time",
                resolution[0], resolution[1]
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
        BenchCommand::Render {
            scenes,
            spp,
            max_depth,
            repeat,
            accel: a,
        } => {
            let scenes = if scenes.is_empty() {
                let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/scenes/cs184/sky");
                vec![
                    root.join("CBspheres_lambertian.dae"),
                    root.join("CBbunny.dae"),
                ]
            } else {
                scenes
            };
            println!("| scene | spp | -m | render-only M samples/s | incl. load+build M samples/s | render s | load ms | build ms |");
            println!("|---|---|---|---|---|---|---|---|");
            for path in scenes {
                let row = bench_render_one(&path, spp, max_depth, repeat.max(1), a)?;
                println!("{row}");
            }
            Ok(())
        }
    }
}

fn bench_render_one(path: &Path, spp: u32, m: u32, repeat: u32, a: AccelArg) -> Result<String> {
    let settings = RenderSettings {
        width: 480,
        height: 360,
        spp,
        max_depth: m,
        strategy: if m > 1 {
            DirectStrategy::Mis
        } else {
            DirectStrategy::Light
        },
        ..Default::default()
    };
    let mut runs = Vec::new();
    for _ in 0..repeat {
        let t0 = Instant::now();
        let scene = collada::load(path)?;
        let t_load = t0.elapsed().as_secs_f64();
        let t1 = Instant::now();
        let acc = accel::build(&scene, accel_kind(a, BvhArg::Sah, QualityArg::Medium))?;
        let t_build = t1.elapsed().as_secs_f64();
        let cam = Camera::new(&scene.camera, &scene.bounds, 480, 360);
        let settings = RenderSettings {
            strategy: DirectStrategy::auto_for(&scene),
            ..settings.clone()
        };
        let t2 = Instant::now();
        let out = render::render(&scene, acc.as_ref(), &cam, &settings, &|_| {});
        let t_render = t2.elapsed().as_secs_f64();
        runs.push((t_render, t_load, t_build, out.total_samples()));
    }
    runs.sort_by(|a, b| a.0.total_cmp(&b.0));
    let (tr, tl, tb, n) = runs[runs.len() / 2];
    let name = path
        .file_name()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    Ok(format!(
        "| {name} | {spp} | {m} | {:.2} | {:.2} | {:.3} | {:.1} | {:.1} |",
        n as f64 / tr / 1e6,
        n as f64 / (tr + tl + tb) / 1e6,
        tr,
        tl * 1e3,
        tb * 1e3
    ))
}
