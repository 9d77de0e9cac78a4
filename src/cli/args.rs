//! The flags: clap definitions only. `convert` turns them into library settings.

use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};
use clap::{Args, Parser, Subcommand, ValueEnum};
use ember::accel::{Backend, BvhBuilder, EmbreeQuality};
use ember::integrators::{DirectStrategy, Estimator};
use ember::names::Named;
use ember::render::{Engine, Shading};
use std::path::PathBuf;

/// What `--help` adds after the options: stopping a render, and where ember differs
/// from the course's binary on purpose (the README says the same).
const AFTER_HELP: &str = "\
Stopping a render:
  Ctrl-C (or SIGTERM) stops within one pixel's time, writes the pixels finished so far
  (the rest black; samples per pixel and `stopped: interrupted` in the file's metadata,
  see `ember info IMAGE`) through a temporary file renamed into place, never a partial
  file, and exits with status 130. A second Ctrl-C quits at once, writing nothing.
  --time S renders passes of 1, 1, 2, 4, 8, 16, 16, ... spp until S seconds are spent
  (or -s is reached), then writes; --checkpoint S writes the image so far every S seconds.

Where ember differs from the CS184 binary on purpose:
  - the field of view does not depend on the resolution (the course's shrinks below 800x600);
  - vertex normals come from the file (the course recomputes them);
  - the sky (ambient light) is seen by rays that escape, not only by light sampling;
  - -a does not stop a pixel after one batch of identical samples (a pixel of zeros
    beside a small light), it takes more batches first;
  - -t defaults to all cores, and the image does not depend on it;
  - <out>_rate.png is written only with -a.
  The full list is in docs/scene-semantics.md, section 9.";

/// ember — a physically based CPU path tracer for the CS184 COLLADA scenes.
///
/// Accepts the CS184 pathtracer command line verbatim, e.g.
///   ember -t 8 -s 64 -l 16 -m 5 -r 480 360 -f out.png scene.dae
#[derive(Parser, Debug)]
#[command(after_help = AFTER_HELP)]
#[command(name = "ember", version, about, long_about = None, args_conflicts_with_subcommands = true, args_override_self = true, allow_negative_numbers = true)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Option<Command>,
    /// ember's data folder (a clone of the repository: its scenes/ and tests/data/), where
    /// the benchmarks find their default scenes and references. Default: $EMBER_DATA, else
    /// the clone around the current directory or the executable.
    #[arg(long, global = true, value_name = "DIR")]
    pub data: Option<PathBuf>,
    #[command(flatten)]
    pub render: RenderArgs,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Assemble the parts of a render made on many machines (`--shard`, `--spp-offset`):
    /// bands are copied, sample ranges averaged by their sample counts. Refuses parts of
    /// different renders, gaps, overlaps and duplicates.
    Merge {
        /// The merged image; .png or .exr.
        out: PathBuf,
        /// The parts (.exr files written with --shard K/N and/or --spp-offset S).
        #[arg(required = true)]
        parts: Vec<PathBuf>,
    },
    /// Print what a scene contains (meshes with their object and material names, lights, materials, camera, bounds),
    /// the native BVH's shape and build time, and the backends of this build; for a .png/.exr ember wrote, how it was made.
    #[command(allow_negative_numbers = true)]
    Info {
        /// The .dae scene file, or an image ember wrote.
        scene: PathBuf,
        /// Resolution at which to report the camera's field of view.
        #[arg(short = 'r', num_args = 2, action = clap::ArgAction::Set, value_names = ["WIDTH", "HEIGHT"], default_values_t = [480, 360])]
        resolution: Vec<u32>,
    },
    /// Write the course's camera settings file (what -c reads) for a scene's own camera at
    /// resolution -r: `ember camera --save view.cam SCENE.dae`. Without --save, print it.
    Camera(CameraArgs),
    /// Write the scene for another renderer, meaning exactly what ember renders
    /// (spec semantics): `ember export --format mitsuba SCENE.dae -r W H -s SPP -m M --out DIR`.
    #[command(allow_negative_numbers = true)]
    Export(ExportArgs),
    /// Measure speed: `ember bench render` (samples/s of full renders).
    #[cfg(feature = "bench")]
    Bench {
        #[command(subcommand)]
        which: BenchCommand,
    },
}

#[derive(Args, Debug)]
pub struct CameraArgs {
    /// The .dae scene file.
    pub scene: PathBuf,
    /// Write the settings to FILE instead of standard output.
    #[arg(long, value_name = "FILE")]
    pub save: Option<PathBuf>,
    /// Resolution whose field of view and screen size the file records.
    #[arg(short = 'r', num_args = 2, action = clap::ArgAction::Set, value_names = ["WIDTH", "HEIGHT"], default_values_t = [480, 360])]
    pub resolution: Vec<u32>,
    #[command(flatten)]
    pub lens: LensArgs,
}

/// The thin lens (course project 3-2 part 4).
#[derive(Args, Debug)]
pub struct LensArgs {
    /// Thin-lens radius, in scene units: depth of field, the lens sampled uniformly over its disk.
    /// 0 (default) is the pinhole. Replaces the -c file's lensRadius (in the course, -b or its default 0
    /// always does). Stricter than the course: must be at least 0.
    #[arg(short = 'b', value_name = "RADIUS", allow_negative_numbers = true)]
    pub lens_radius: Option<f32>,

    /// Focal distance of the lens, in scene units, measured along the view direction: the plane at this
    /// depth is sharp. Default: the -c file's focalDistance, else the course's 4.7. Stricter than the
    /// course: must be positive.
    #[arg(short = 'd', value_name = "DISTANCE", allow_negative_numbers = true)]
    pub focal_distance: Option<f32>,
}

#[derive(Args, Debug)]
pub struct ExportArgs {
    /// The .dae scene file.
    pub scene: PathBuf,
    /// Target renderer.
    #[arg(long, value_enum, default_value_t = ExportFormat::Mitsuba)]
    pub format: ExportFormat,
    /// Image resolution.
    #[arg(short = 'r', num_args = 2, action = clap::ArgAction::Set, value_names = ["WIDTH", "HEIGHT"], default_values_t = [480, 360])]
    pub resolution: Vec<u32>,
    /// Samples per pixel.
    #[arg(short = 's', default_value_t = 64)]
    pub spp: u32,
    /// Max ray depth (bounces), as ember's -m; Mitsuba's max_depth is m + 1.
    #[arg(short = 'm', default_value_t = 5)]
    pub max_depth: u32,
    /// Output folder (created if missing); files are named after the scene.
    #[arg(long = "out", default_value = ".")]
    pub out: PathBuf,
    /// Environment map replacing the scene's ambient light, as the renderer's -e (exported in Mitsuba's orientation).
    #[arg(short = 'e', value_name = "FILE.exr")]
    pub env_map: Option<PathBuf>,
}

#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum ExportFormat {
    /// Mitsuba 3 XML with PLY meshes.
    Mitsuba,
}

#[cfg(feature = "bench")]
#[derive(Subcommand, Debug)]
pub enum BenchCommand {
    /// Where methods fail: a row per case (delta lights, tiny lights, glossy vs rough, caustics, scale, grazing rays,
    /// adaptive sampling, roulette) with what each method does there. Writes stability.csv, stability.md and a chart.
    #[command(allow_negative_numbers = true)]
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
        /// Worker threads (default: all cores).
        #[arg(short = 't', value_name = "THREADS")]
        threads: Option<usize>,
    },
    /// Build time, memory, tree shape (nodes, leaves, depth, SAH cost) and Mrays/s (camera, incoherent, shadow rays)
    /// of every backend this build has (native midpoint and SAH; Embree robust and fast), at each thread count, with the
    /// native/Embree ratios; with Embree, also every Embree mode (scene flags × build quality × rtcIntersect1/4/8/16) on
    /// camera rays. Writes accel.csv/.md and embree_modes.csv/.md to --out. Default scenes: CBbunny, CBspheres_lambertian,
    /// mesh:1M. Merge an Embree 3 and an Embree 4 build's tables by running the second with --append.
    #[command(allow_negative_numbers = true)]
    Accel {
        /// Scenes to measure instead of the defaults: .dae files, or mesh:N for a generated displaced sphere of about
        /// N triangles (mesh:250k, mesh:1M).
        #[arg(value_parser = parse_bench_scene)]
        scenes: Vec<ember::bench::accel::BenchScene>,
        /// Incoherent and shadow rays per measurement (camera rays: one per pixel of a 480x360 render).
        #[arg(long, default_value_t = 500_000)]
        rays: usize,
        /// Thread counts to measure: `-t 1 2` or `-t 1,2` (scenes go before the options, or after `--`).
        #[arg(short = 't', long, num_args = 1.., value_delimiter = ',', default_values_t = [1, 2])]
        threads: Vec<usize>,
        /// Each figure is the median of this many runs.
        #[arg(long, default_value_t = 5)]
        repeats: usize,
        /// Embree's build quality in the main table (the Embree modes table has all three).
        #[arg(long, value_parser = named::<EmbreeQuality>(), default_value_t = EmbreeQuality::default())]
        quality: EmbreeQuality,
        /// Leave out the Embree modes table.
        #[arg(long)]
        no_embree_modes: bool,
        /// Add this run's rows to the tables already in --out (e.g. an Embree 4 build's after an Embree 3 build's)
        /// instead of replacing them.
        #[arg(long, conflicts_with = "scaling")]
        append: bool,
        /// Instead: generated meshes (displaced sphere, random soup) from 1k to 4M triangles, every native builder and
        /// Embree quality, charted against triangle count (log-log) with fitted growth. Writes CSV, Markdown and charts to --out.
        #[arg(long)]
        scaling: bool,
        /// Output folder (default: bench-out/accel, or bench-out/scaling with --scaling).
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// Error against render time for each method (direct: hemisphere / light / MIS; GI: roulette, -l, adaptive, backends).
    /// Writes <out>/<scene>_m<M>.csv and error-vs-time charts (PNG and SVG), prints the time each method needs to reach an error.
    #[command(allow_negative_numbers = true)]
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
        #[arg(short = 'r', num_args = 2, action = clap::ArgAction::Set, value_names = ["WIDTH", "HEIGHT"], default_values_t = [160, 120])]
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
        /// Also run Mitsuba 3 as a method, through this Python (one that imports `mitsuba`; scripts/mitsuba-env creates one and prints its path). Each point is the warm, render-only time of its own process.
        #[arg(long, value_name = "PYTHON")]
        mitsuba: Option<PathBuf>,
        /// Mitsuba variants to run with --mitsuba, comma-separated.
        #[arg(long, value_delimiter = ',', default_value = "llvm_ad_rgb")]
        mitsuba_variants: Vec<String>,
        /// Worker threads (default: all cores).
        #[arg(short = 't', value_name = "THREADS")]
        threads: Option<usize>,
    },
    /// Samples per second for CBspheres_lambertian and CBbunny at 480x360, 64 spp, -m 5.
    #[command(allow_negative_numbers = true)]
    Render {
        /// Scenes to render (default: the course's CBspheres_lambertian and CBbunny from the
        /// repository's scenes/, or $EMBER_DATA's).
        scenes: Vec<PathBuf>,
        /// Samples per pixel.
        #[arg(short = 's', default_value_t = 64)]
        spp: u32,
        /// Max ray depth.
        #[arg(short = 'm', default_value_t = 5)]
        max_depth: u32,
        /// Repetitions per scene (the median is reported).
        #[arg(long, default_value_t = 3)]
        repeats: u32,
        /// Worker threads (default: all cores).
        #[arg(short = 't', value_name = "THREADS")]
        threads: Option<usize>,
        /// Backend (auto: the native BVH and, in builds with Embree, Embree as `--accel
        /// embree` renders, in one table).
        #[arg(long, value_parser = named::<Backend>(), default_value_t = Backend::Auto)]
        accel: Backend,
        /// Also render through each step of how ember drives Embree (builds with Embree;
        /// the steps of `ember bench accel`'s Embree variants table), a row each.
        #[arg(long)]
        embree_steps: bool,
        /// Engines to compare, in turn within each repetition (a row per backend each).
        #[arg(long, value_parser = named::<Engine>(), value_delimiter = ',', default_value = "auto,scalar")]
        engines: Vec<Engine>,
        /// Output folder (render.csv, render.md).
        #[arg(long, default_value = "bench-out/render")]
        out: PathBuf,
    },
}

#[cfg(feature = "bench")]
fn parse_bench_scene(s: &str) -> Result<ember::bench::accel::BenchScene, String> {
    ember::bench::accel::BenchScene::parse(s)
}

#[derive(Args, Debug)]
pub struct RenderArgs {
    /// The .dae scene to render.
    pub scene: Option<PathBuf>,

    /// Worker threads (default: all cores). The image does not depend on it.
    #[arg(short = 't', value_name = "THREADS")]
    pub threads: Option<usize>,

    /// Camera rays (samples) per pixel; with -a, the cap per pixel [default: 1; with --time, no cap].
    #[arg(short = 's', value_name = "SPP")]
    pub spp: Option<u32>,

    /// Light samples per area light at every shading point (delta lights take one).
    #[arg(short = 'l', value_name = "SAMPLES", default_value_t = 1)]
    pub light_samples: u32,

    /// Max ray depth: the most bounces (scattering events) a counted path may have. 0 = emitters only, 1 = direct lighting.
    #[arg(short = 'm', value_name = "DEPTH", default_value_t = 1)]
    pub max_depth: u32,

    /// Accumulate bounces: 1 (default) sums all paths of up to -m bounces, 0 keeps only paths of exactly -m bounces.
    #[arg(short = 'o', value_name = "0|1", default_value_t = 1, value_parser = clap::value_parser!(u8).range(0..=1))]
    pub accumulate: u8,

    /// Adaptive sampling: after every BATCH samples stop a pixel once 1.96·σ/√n ≤ TOL·μ (or at -s). A pixel whose samples are all zero stops only once n zeros would have a chance of at most 1% if light reached it a quarter as often as it reaches the pixels within 5 px in their first batch, so light found rarely is not missed (README). `-a` alone means 32 0.05.
    #[arg(short = 'a', num_args = 0..=2, action = clap::ArgAction::Set, value_names = ["BATCH", "TOL"])]
    pub adaptive: Option<Vec<String>>,

    /// Direct lighting by uniform hemisphere sampling instead of light sampling (cannot see point/directional lights).
    #[arg(short = 'H')]
    pub hemisphere: bool,

    /// Environment light: a latitude-longitude .exr map (row 0 = +Y, u = 0 at -X, u = 1/4 at +Z, as the course's) around the scene, importance-sampled by luminance x sin(theta). Replaces the scene's ambient light.
    #[arg(short = 'e', value_name = "FILE.exr")]
    pub env_map: Option<PathBuf>,

    /// Output image; .png (8-bit sRGB) or .exr (linear float). Default: <scene stem>.png.
    #[arg(short = 'f', value_name = "FILE")]
    pub output: Option<PathBuf>,

    /// Resolution of the image.
    #[arg(short = 'r', num_args = 2, action = clap::ArgAction::Set, value_names = ["WIDTH", "HEIGHT"], default_values_t = [480, 360])]
    pub resolution: Vec<u32>,

    /// Camera settings file as the course's viewer saves it (`ember camera --save` writes one): its eye,
    /// orientation, field of view and lens replace the scene's camera. A field of view of another aspect
    /// than -r is widened to it (the course stretches the image). Stricter than the course: every field
    /// must be a number in range, c2w a rotation, nothing may follow the 30 numbers.
    #[arg(short = 'c', value_name = "FILE")]
    pub camera_file: Option<PathBuf>,

    /// Render only the cell of DX x DY pixels starting at pixel (X, Y), X from the left and Y from the
    /// bottom as in the course; its pixels equal the full render's bit for bit. Writes the cell alone
    /// (as the course does) unless --full-frame. Stricter than the course: the cell must lie in the image.
    #[arg(short = 'p', num_args = 4, action = clap::ArgAction::Set, value_names = ["X", "Y", "DX", "DY"])]
    pub cell: Option<Vec<u32>>,

    /// With -p: write the full-size image, black outside the cell.
    #[arg(long, requires = "cell")]
    pub full_frame: bool,

    #[command(flatten)]
    pub lens: LensArgs,

    /// Intersection backend. auto: the native BVH below a measured primitive count, Embree from it (in builds
    /// with Embree; `ember info SCENE` says which and why).
    #[arg(long, value_parser = named::<Backend>(), default_value_t = Backend::Auto)]
    pub accel: Backend,

    /// How the native BVH is built [default: sah] (not with --accel embree).
    #[arg(long, value_parser = named::<BvhBuilder>())]
    pub bvh: Option<BvhBuilder>,

    /// Embree's build quality [default: medium] (only with --accel embree).
    #[arg(long, value_parser = named::<EmbreeQuality>())]
    pub embree_quality: Option<EmbreeQuality>,

    /// What each pixel shows.
    #[arg(long, value_parser = named::<Shading>(), default_value_t = Shading::Radiance)]
    pub shading: Shading,

    /// With --shading bvh-cost: the count (nodes + primitives tested per camera ray) shown red in a PNG,
    /// so images of two builders compare [default: the image's 99th percentile]. An EXR holds the raw counts.
    #[arg(long, value_name = "COUNT")]
    pub cost_scale: Option<f32>,

    /// How paths run on the CPU: sixteen per SIMD pass (AVX-512, AVX2 or portable code) or one at a time.
    /// The image is the same bit for bit; only the speed differs.
    #[arg(long, value_parser = named::<Engine>(), default_value_t = Engine::Auto)]
    pub engine: Engine,

    /// Estimator. auto: light tracing when every light is a point light and nothing is specular or self-emitting (CBempty: see BENCHMARKS.md, stability case 9); otherwise path tracing with MIS (light + BSDF sampling) when the scene has glossy surfaces or an ambient or environment (-e) light, light sampling otherwise. A direct-lighting strategy name means path tracing with it. -H forces hemisphere.
    #[arg(long, value_parser = integrator(), default_value = AUTO)]
    pub integrator: IntegratorChoice,

    /// Russian roulette: off, throughput (continue with probability max(throughput), at least 0.05), or a fixed probability like 0.5.
    #[arg(long, default_value = "throughput", value_name = "off|throughput|PROB")]
    pub rr: String,

    /// First bounce at which Russian roulette may end a path.
    #[arg(long, default_value_t = 3, value_name = "BOUNCE")]
    pub rr_start: u32,

    /// Render for at most SECONDS (after loading), in passes of 1, 1, 2, 4, 8, 16, 16, ... samples per
    /// pixel, then write what was rendered; -s, if given, still caps the samples.
    #[arg(long = "time", value_name = "SECONDS")]
    pub time: Option<f64>,

    /// Write the image so far every SECONDS (after the pass that ends the interval), so a long render
    /// that is killed leaves its latest checkpoint. Renders in passes, as --time does.
    #[arg(long, value_name = "SECONDS")]
    pub checkpoint: Option<f64>,

    /// Random seed; the same seed gives the same image whatever -t is.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,

    /// Render only band K of N bands of rows (floor(K·H/N) to floor((K+1)·H/N)) into an
    /// .exr part for `ember merge`; the bands merge into exactly the whole render.
    #[arg(long, value_name = "K/N")]
    pub shard: Option<String>,

    /// Render samples S..S+SPP of every pixel (with -s SPP) into an .exr part for
    /// `ember merge`, which averages sample ranges into a render of more samples. Not with -a.
    #[arg(long, value_name = "S")]
    pub spp_offset: Option<u32>,

    /// No progress bar and no summary.
    #[arg(short = 'q', long)]
    pub quiet: bool,
}

/// A flag parsed straight into a library enum through its name table; `--help`
/// lists every name with its description.
fn named<T: Named + Send + Sync>() -> impl TypedValueParser<Value = T> {
    PossibleValuesParser::new(T::TABLE.iter().map(|&(_, name, help)| possible(name, help)))
        .try_map(|s| T::from_name(&s))
}

fn possible(name: &'static str, help: &'static str) -> PossibleValue {
    let v = PossibleValue::new(name);
    if help.is_empty() {
        v
    } else {
        v.help(help)
    }
}

/// `--integrator`'s word for "let the scene choose" (`DirectStrategy::auto_for`).
const AUTO: &str = "auto";

/// What `--integrator` names: an estimator and, for path tracing, its direct-lighting
/// strategy; a `None` is chosen from the scene.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct IntegratorChoice {
    pub estimator: Option<Estimator>,
    pub strategy: Option<DirectStrategy>,
}

/// `--integrator`: `auto`, an estimator (`path`, `light-tracing`), or a path-tracing
/// strategy, each from the library's name tables.
fn integrator() -> impl TypedValueParser<Value = IntegratorChoice> {
    let auto = PossibleValue::new(AUTO).help("Chosen from the scene (see above)");
    let estimators = Estimator::TABLE.iter().map(|&(_, n, h)| possible(n, h));
    let strategies = DirectStrategy::TABLE
        .iter()
        .map(|&(_, n, h)| possible(n, h));
    let values = std::iter::once(auto).chain(estimators).chain(strategies);
    PossibleValuesParser::new(values).try_map(|s| {
        if s == AUTO {
            return Ok(IntegratorChoice::default());
        }
        if let Ok(e) = Estimator::from_name(&s) {
            return Ok(IntegratorChoice {
                estimator: Some(e),
                strategy: None,
            });
        }
        DirectStrategy::from_name(&s).map(|d| IntegratorChoice {
            estimator: Some(Estimator::Path),
            strategy: Some(d),
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::CommandFactory;

    /// The values `--help` lists for the render flag `--long`.
    fn listed(long: &str) -> Vec<String> {
        let cmd = Cli::command();
        let arg = cmd
            .get_arguments()
            .find(|a| a.get_long() == Some(long))
            .unwrap_or_else(|| panic!("no --{long}"));
        arg.get_possible_values()
            .iter()
            .map(|v| v.get_name().to_string())
            .collect()
    }

    /// Every name of the library's table is listed by `--help` and parses into its value.
    fn check<T: Named + std::fmt::Debug>(long: &str, get: impl Fn(&RenderArgs) -> T) {
        let listed = listed(long);
        for &(value, name, _) in T::TABLE {
            assert!(
                listed.iter().any(|l| l == name),
                "--{long} does not list {name}"
            );
            let flag = format!("--{long}");
            let cli = Cli::try_parse_from(["ember", flag.as_str(), name, "scene.dae"])
                .unwrap_or_else(|e| panic!("--{long} {name}: {e}"));
            assert_eq!(get(&cli.render), value, "--{long} {name}");
        }
    }

    #[test]
    fn flags_take_every_name_of_the_library_tables() {
        check("accel", |a| a.accel);
        check("bvh", |a| a.bvh.unwrap_or_default());
        check("embree-quality", |a| a.embree_quality.unwrap_or_default());
        check("shading", |a| a.shading);
        check("engine", |a| a.engine);
        let integrators = listed("integrator");
        for &(_, name, _) in DirectStrategy::TABLE {
            assert!(integrators.iter().any(|l| l == name), "--integrator {name}");
        }
        assert!(Cli::try_parse_from(["ember", "--bvh", "octree", "scene.dae"]).is_err());
    }
}
