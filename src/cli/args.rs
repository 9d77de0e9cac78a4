//! The flags: clap definitions only. `convert` turns them into library settings.

use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};
use clap::{Args, Parser, Subcommand, ValueEnum};
use ember::accel::{Backend, BvhBuilder, EmbreeQuality};
#[cfg(feature = "bench")]
use ember::export::MitsubaRoulette;
use ember::export::MitsubaSampler;
use ember::integrators::{DirectStrategy, Estimator, Roulette};
use ember::names::Named;
use ember::render::{Engine, RenderSettings, Shading};
use ember::sampling::SamplerKind;
use std::path::PathBuf;

/// What `--help` adds after the options: stopping a render, and where ember differs
/// from the course's binary on purpose (the README says the same).
const AFTER_HELP: &str = "\
Examples:
  ember -s 64 -l 4 -m 5 -r 480 360 -f bunny.png scenes/cs184/sky/CBbunny.dae
  ember info scenes/cs184/sky/CBbunny.dae       what a scene holds, and the backends
  ember report --out write-up                   the CS184 write-up's figures as a page
  ember bench render | accel | converge SCENE | stability | estimators    (see ember bench --help)

Stopping a render:
  Ctrl-C (or SIGTERM) stops within one pixel's time, writes the pixels finished so far
  (the rest black; samples per pixel and `ember.stopped: interrupted` in the metadata,
  see `ember info IMAGE`) through a temporary file renamed into place, never a partial
  file, and exits with status 130. A second Ctrl-C quits at once, writing nothing.
  --time S renders passes of 1, 1, 2, 4, 8, 16, 16, ... spp until S seconds are spent
  (or -s is reached), then writes, keeping the pixels its last pass finished (so pixels
  may differ in samples); --checkpoint S writes the image so far every S seconds.

Where ember differs from the CS184 binary on purpose:
  - the field of view does not depend on the resolution (the course's shrinks below 800x600);
  - vertex normals come from the file (the course recomputes them);
  - the sky (ambient light) is seen by rays that escape, not only by light sampling;
  - -a does not stop a pixel after one batch of identical samples (a pixel of zeros
    beside a small light), it takes more batches first;
  - -t defaults to all cores, and the image does not depend on it;
  - <out>_rate.png is written only with -a, with a legend below the map: blue = 0, red = -s
    samples per pixel (with -f X.exr, <out>_rate.exr instead, with the raw counts).
  The full list is in docs/scene-semantics.md, section 9.";

/// What `ember -h` and `--help` say first.
const ABOUT: &str = "\
ember: a physically based CPU path tracer for the CS184 COLLADA (.dae) scenes.
Without a command it renders SCENE, and takes the CS184 pathtracer's command line verbatim:
  ember -t 8 -s 64 -l 16 -m 5 -r 480 360 -f out.png scene.dae";

/// The whole command line: the render's flags, or a subcommand.
#[derive(Parser, Debug)]
#[command(after_help = AFTER_HELP)]
#[command(name = "ember", version, about = ABOUT, long_about = None, args_conflicts_with_subcommands = true, args_override_self = true, allow_negative_numbers = true)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Option<Command>,
    /// ember's data folder (a clone of the repository: its scenes/ and tests/data/), where
    /// the benchmarks find their default scenes and references. Default: $EMBER_DATA, else
    /// the clone around the current directory or the executable.
    #[arg(long, global = true, value_name = "DIR")]
    pub data: Option<PathBuf>,
    /// The instruction set the packets of sixteen paths (and the BVH's node tests) run with, for
    /// comparing their speed: the image is the same bit for bit with every one. An error if this
    /// CPU lacks it.
    #[arg(long, global = true, value_enum, default_value_t = SimdChoice::Auto)]
    pub simd: SimdChoice,
    #[command(flatten)]
    pub render: RenderArgs,
}

/// The subcommands; `--help` lists each with the first line of its comment.
#[derive(Subcommand, Debug)]
pub enum Command {
    /// Print what a scene contains, or how an image was made and what it holds.
    ///
    /// For a .dae scene: meshes with their object and material names, lights, materials,
    /// camera, bounds, the native BVH's shape and build time, and the backends of this
    /// build. For a .png or .exr: its size, channels and per-channel statistics, and the
    /// settings ember wrote into it, if ember wrote it.
    #[command(allow_negative_numbers = true)]
    Info {
        /// The .dae scene file, or a .png/.exr image.
        #[arg(value_name = "SCENE_OR_IMAGE")]
        path: PathBuf,
        /// Resolution at which to report the camera's field of view.
        #[arg(short = 'r', num_args = 2, action = clap::ArgAction::Set, value_names = ["WIDTH", "HEIGHT"], default_values_t = [480, 360])]
        resolution: Vec<u32>,
        #[command(flatten)]
        placement: PlacementArgs,
    },
    /// Assemble the parts of a render made on many machines into one image.
    ///
    /// The parts are .exr files written with --shard K/N and/or --spp-offset S: bands are
    /// copied, sample ranges averaged by their sample counts. Refuses parts of different
    /// renders, gaps, overlaps and duplicates.
    Merge {
        /// The merged image; .png or .exr.
        out: PathBuf,
        /// The parts (.exr files written with --shard K/N and/or --spp-offset S).
        #[arg(required = true)]
        parts: Vec<PathBuf>,
    },
    /// Write the course's camera settings file (what -c reads) for a scene's camera.
    ///
    /// `ember camera --save view.cam SCENE.dae` records the scene's own camera at
    /// resolution -r (with -b/-d, a lens). Without --save, prints it.
    Camera(CameraArgs),
    /// Write the scene for Mitsuba 3, meaning exactly what ember renders.
    ///
    /// `ember export --format mitsuba SCENE.dae -r W H -s SPP -m M --out DIR`: spec
    /// semantics, for side-by-side measurements.
    #[command(allow_negative_numbers = true)]
    Export(ExportArgs),
    /// Measure speed and accuracy: render, accel, converge, stability, estimators.
    #[cfg(feature = "bench")]
    Bench {
        #[command(subcommand)]
        which: BenchCommand,
    },
    /// Render the CS184 write-up's figures and write them as a page (index.html, README.md).
    ///
    /// The course's five parts (normal shading; large meshes and render times with ember's
    /// BVH, Embree and no acceleration; hemisphere against light sampling at -l 1, 4, 16,
    /// 64; direct and indirect light, -m 0 to 5, 1 to 1024 spp; adaptive sampling with its
    /// rate maps) and the speed-against-accuracy charts of `ember bench converge`. Under
    /// every figure: the ember command that renders it bit for bit. About 6 minutes on
    /// two busy cores (4 minutes of CPU time); --quick, seconds.
    #[cfg(feature = "bench")]
    Report(ReportArgs),
}

/// `ember report`'s flags.
#[cfg(feature = "bench")]
#[derive(Args, Debug)]
pub struct ReportArgs {
    /// Scenes to use in every part instead of the course's (part 4's rows and the
    /// charts use the first).
    pub scenes: Vec<PathBuf>,
    /// Folder of the page: index.html, README.md, figures/ and converge/ (created if missing).
    #[arg(long, default_value = "report")]
    pub out: PathBuf,
    /// Small sizes and sample counts (every part still present), for a first look or a test.
    #[arg(long)]
    pub quick: bool,
    /// Random seed of every render (each figure's command repeats it).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Python that imports Mitsuba 3, to chart it beside ember [default: the one
    /// scripts/mitsuba-env installed in the data folder's .cache/mitsuba, if any, except
    /// with --quick].
    #[arg(long, value_name = "PYTHON")]
    pub mitsuba: Option<PathBuf>,
    /// Worker threads (default: all cores). The figures do not depend on it.
    #[arg(short = 't', value_name = "THREADS", value_parser = thread_count)]
    pub threads: Option<usize>,
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

    #[command(flatten)]
    pub placement: PlacementArgs,
}

/// `--camera-placement`, for the commands that place the scene's camera (renders,
/// `ember camera`, `ember info`, `ember export`).
#[derive(Args, Debug)]
pub struct PlacementArgs {
    /// Where the camera's eye goes. auto: the course's rule for the course's files (they use its
    /// CGL/CMU462 extension, were written by its Blender 2.72/2.74, or name no authoring tool), the
    /// camera node's own position for files other tools wrote (`ember info` says which and why);
    /// course: the course's rule (the scene's centre, 1.5 diagonals back along the view); file:
    /// the camera node's position (the course's rule when the file has no camera).
    #[arg(long = "camera-placement", value_enum, value_name = "PLACEMENT", default_value_t = CameraPlacement::Auto)]
    pub camera_placement: CameraPlacement,
}

/// `--simd`.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum SimdChoice {
    /// The widest this CPU has.
    Auto,
    /// AVX-512 (F, DQ, BW and VL, with AVX2's): one instruction per sixteen lanes.
    Avx512,
    /// AVX2 (with BMI1, BMI2, LZCNT and POPCNT): two instructions per sixteen lanes.
    Avx2,
    /// Plain Rust over arrays of sixteen, for any CPU.
    Portable,
}

/// `--camera-placement`.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum CameraPlacement {
    Auto,
    Course,
    File,
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
    #[arg(short = 's', default_value_t = 64, value_parser = at_least_one::<u32>)]
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
    /// Mitsuba's sampler. Default multijitter: the lowest error of Mitsuba's samplers in ember's measurements, and it
    /// takes nearly any count. A count the sampler does not take is rounded up as Mitsuba would, with a warning.
    #[arg(long, value_parser = named::<MitsubaSampler>(), default_value_t = MitsubaSampler::default())]
    pub sampler: MitsubaSampler,
    #[command(flatten)]
    pub placement: PlacementArgs,
}

#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum ExportFormat {
    /// Mitsuba 3 XML with PLY meshes.
    Mitsuba,
}

/// `ember bench ...`: each benchmark's flags in their own struct, which its command reads.
#[cfg(feature = "bench")]
#[derive(Subcommand, Debug)]
pub enum BenchCommand {
    /// Samples per second of full renders (default: CBspheres_lambertian and CBbunny, 480x360, 64 spp, -m 5).
    #[command(allow_negative_numbers = true)]
    Render(BenchRenderArgs),
    /// Acceleration structures: build time, memory, tree shape and Mrays/s of every backend.
    ///
    /// Build time, memory, tree shape (nodes, leaves, depth, SAH cost) and Mrays/s (camera, incoherent, shadow rays)
    /// of every backend this build has (native midpoint and SAH; Embree robust and fast), at each thread count, with the
    /// native/Embree ratios; with Embree, also every Embree mode (scene flags × build quality × rtcIntersect1/4/8/16) on
    /// camera rays. Writes accel.csv/.md and embree_modes.csv/.md to --out. Default scenes: CBbunny, CBspheres_lambertian,
    /// mesh:1M. Merge an Embree 3 and an Embree 4 build's tables by running the second with --append.
    #[command(allow_negative_numbers = true)]
    Accel(BenchAccelArgs),
    /// Error against render time for each method, charted.
    ///
    /// Methods: direct lighting by hemisphere, light or MIS sampling; for global illumination, roulette, -l, adaptive
    /// sampling and the backends; peers: Mitsuba 3 with each sampler, Blender Cycles. Writes <out>/<scene>_m<M>.csv and
    /// error-vs-time charts (PNG and SVG); prints each method's RMSE at the render times and spp of ember's default at
    /// 16, 64 and 256 spp.
    #[command(allow_negative_numbers = true)]
    Converge(BenchConvergeArgs),
    /// Where methods fail: a row per hard case with what each method does there.
    ///
    /// The cases: delta lights, tiny lights, glossy vs rough, caustics, scale, grazing rays, adaptive sampling,
    /// roulette, CBempty's point light (light tracing), an environment map's sun. Writes stability.csv,
    /// stability.md and a chart.
    #[command(allow_negative_numbers = true)]
    Stability(BenchStabilityArgs),
    /// Whether --integrator auto picks the more efficient of path tracing and light tracing, scene by scene.
    ///
    /// Each estimator renders each scene in pairs of seeds; noise² (of a pair's averaged pixel, from the two renders'
    /// difference) times the pair's render time is its inefficiency. A row gives both, what auto runs (by the scene's
    /// rule or its pilot) and the pick's inefficiency over the better one's. Default scenes: every scene ember ships.
    /// Writes estimators.csv and estimators.md.
    #[command(allow_negative_numbers = true)]
    Estimators(BenchEstimatorsArgs),
}

#[cfg(feature = "bench")]
#[derive(Args, Debug)]
pub struct BenchRenderArgs {
    /// Scenes to render (default: the course's CBspheres_lambertian and CBbunny from the
    /// repository's scenes/, or $EMBER_DATA's).
    pub scenes: Vec<PathBuf>,
    /// Samples per pixel.
    #[arg(short = 's', default_value_t = 64, value_parser = at_least_one::<u32>)]
    pub spp: u32,
    /// Max ray depth.
    #[arg(short = 'm', default_value_t = 5)]
    pub max_depth: u32,
    /// Repetitions per scene (the median is reported).
    #[arg(long, default_value_t = 3, value_parser = at_least_one::<u32>)]
    pub repeats: u32,
    /// Worker threads (default: all cores).
    #[arg(short = 't', value_name = "THREADS", value_parser = thread_count)]
    pub threads: Option<usize>,
    /// Backend (auto: the native BVH and, in builds with Embree, Embree as `--accel embree`
    /// renders, in one table).
    #[arg(long, value_parser = named::<Backend>(), default_value_t = Backend::Auto)]
    pub accel: Backend,
    /// Also render through each step of how ember drives Embree (builds with Embree; the
    /// steps of `ember bench accel`'s Embree variants table), a row each.
    #[arg(long)]
    pub embree_steps: bool,
    /// Engines to compare, in turn within each repetition (a row per backend each).
    #[arg(long, value_parser = named::<Engine>(), value_delimiter = ',', default_value = "auto,scalar")]
    pub engines: Vec<Engine>,
    /// Instruction sets to compare (as --simd: auto, avx512, avx2, portable), in turn within each
    /// repetition, a row per engine and backend each. Default: --simd's.
    #[arg(long, value_enum, value_delimiter = ',', default_value = "auto")]
    pub simds: Vec<SimdChoice>,
    /// Output folder (render.csv, render.md).
    #[arg(long, default_value = "bench-out/render")]
    pub out: PathBuf,
}

#[cfg(feature = "bench")]
#[derive(Args, Debug)]
pub struct BenchAccelArgs {
    /// Scenes to measure instead of the defaults: .dae files, or mesh:N for a generated displaced sphere of about
    /// N triangles (mesh:250k, mesh:1M).
    #[arg(value_parser = parse_bench_scene)]
    pub scenes: Vec<ember::bench::accel::BenchScene>,
    /// Incoherent and shadow rays per measurement (camera rays: one per pixel of a 480x360 render).
    #[arg(long, default_value_t = 500_000, value_parser = at_least_one::<usize>)]
    pub rays: usize,
    /// Thread counts to measure: `-t 1 2` or `-t 1,2` (scenes go before the options, or after `--`).
    #[arg(short = 't', long, num_args = 1.., value_delimiter = ',', default_values_t = [1, 2])]
    pub threads: Vec<usize>,
    /// Each figure is the median of this many runs.
    #[arg(long, default_value_t = 5, value_parser = at_least_one::<usize>)]
    pub repeats: usize,
    /// Embree's build quality in the main table (the Embree modes table has all three).
    #[arg(long, value_parser = named::<EmbreeQuality>(), default_value_t = EmbreeQuality::default())]
    pub quality: EmbreeQuality,
    /// Leave out the Embree modes table.
    #[arg(long)]
    pub no_embree_modes: bool,
    /// Add this run's rows to the tables already in --out (e.g. an Embree 4 build's after an Embree 3 build's)
    /// instead of replacing them.
    #[arg(long, conflicts_with = "scaling")]
    pub append: bool,
    /// Instead: generated meshes (displaced sphere, random soup) from 1k to 4M triangles, every native builder and
    /// Embree quality, charted against triangle count (log-log) with fitted growth. Writes CSV, Markdown and charts to --out.
    #[arg(long)]
    pub scaling: bool,
    /// Output folder (default: bench-out/accel, or bench-out/scaling with --scaling).
    #[arg(long)]
    pub out: Option<PathBuf>,
}

#[cfg(feature = "bench")]
#[derive(Args, Debug)]
pub struct BenchConvergeArgs {
    /// The .dae scene.
    pub scene: PathBuf,
    /// Reference image (linear EXR at the render resolution). Default: ember's own high-spp render, cached under <out>/cache.
    #[arg(long)]
    pub reference: Option<PathBuf>,
    /// Per-pixel RMS noise of --reference, subtracted from every MSE. Default: from the manifest.json beside --reference
    /// (as tests/data/references has), else taken as negligible.
    #[arg(long, value_parser = non_negative_number)]
    pub reference_noise: Option<f64>,
    /// Max ray depth.
    #[arg(short = 'm', default_value_t = 1)]
    pub max_depth: u32,
    /// Resolution.
    #[arg(short = 'r', num_args = 2, action = clap::ArgAction::Set, value_names = ["WIDTH", "HEIGHT"], default_values_t = [160, 120])]
    pub resolution: Vec<u32>,
    /// Largest spp of ember's doubling sequence 1, 2, 4, ... (peers go one count further, so that ember's time at it falls within their curves)
    #[arg(long, default_value_t = 1024, value_parser = at_least_one::<u32>)]
    pub max_spp: u32,
    /// Stop doubling a method once one render takes longer than this (seconds).
    #[arg(long, default_value_t = 8.0, value_parser = positive_seconds)]
    pub max_seconds: f64,
    /// spp of ember's own reference.
    #[arg(long, default_value_t = 8192, value_parser = at_least_one::<u32>)]
    pub reference_spp: u32,
    /// Output folder.
    #[arg(long, default_value = "bench-out/converge")]
    pub out: PathBuf,
    /// Random seed.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Renders per point, each with its own seed: a point's RMSE is that of their mean MSE, its time their median (for every method, peers included).
    #[arg(long, default_value_t = 1, value_parser = at_least_one::<u32>)]
    pub seeds: u32,
    /// Also run Mitsuba 3 as a method, through this Python (one that imports `mitsuba`; scripts/mitsuba-env creates one and prints its path). Each point is the warm, render-only time of its own process.
    #[arg(long, value_name = "PYTHON")]
    pub mitsuba: Option<PathBuf>,
    /// Mitsuba variants to run with --mitsuba, comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "llvm_ad_rgb")]
    pub mitsuba_variants: Vec<String>,
    /// Mitsuba samplers to run with --mitsuba, comma-separated: each variant with each sampler is one method.
    /// Each renders the doubling sequence rounded up to the counts it takes (ldsampler: 4, 16, 64, ...).
    #[arg(long, value_delimiter = ',', value_parser = named::<MitsubaSampler>(),
          default_value = "independent,stratified,multijitter,ldsampler,orthogonal")]
    pub mitsuba_samplers: Vec<MitsubaSampler>,
    /// Where Mitsuba's Russian roulette starts, comma-separated: each sampler runs once per entry.
    /// `ember`: at ember's own start (the same work per sample); a number: Mitsuba's `rr_depth` (its own
    /// default is 5, which has the lower error at equal time when samples are many; a number equal to ember's
    /// start runs once). The peer's best at each time is the lowest of them all.
    #[arg(long, value_delimiter = ',', default_value = "ember,5")]
    pub mitsuba_rr: Vec<MitsubaRoulette>,
    /// Also run Blender Cycles as a method, through this Python (one that imports `bpy`; scripts/cycles-env
    /// creates one and prints its path). Scenes of Lambertian surfaces and rectangular area lights only; its
    /// image mean is checked against --reference's manifest.
    #[arg(long, value_name = "PYTHON")]
    pub cycles: Option<PathBuf>,
    /// Worker threads (default: all cores).
    #[arg(short = 't', value_name = "THREADS", value_parser = thread_count)]
    pub threads: Option<usize>,
}

#[cfg(feature = "bench")]
#[derive(Args, Debug)]
pub struct BenchEstimatorsArgs {
    /// The .dae scenes (default: every scene under the data folder's scenes/).
    pub scenes: Vec<PathBuf>,
    /// Max ray depth.
    #[arg(short = 'm', default_value_t = 5)]
    pub max_depth: u32,
    /// Resolution.
    #[arg(short = 'r', num_args = 2, action = clap::ArgAction::Set, value_names = ["WIDTH", "HEIGHT"], default_values_t = [160, 120])]
    pub resolution: Vec<u32>,
    /// Samples per pixel of each render.
    #[arg(short = 's', default_value_t = 64, value_parser = at_least_one::<u32>)]
    pub spp: u32,
    /// Pairs of renders per estimator and scene (the medians are reported).
    #[arg(long, default_value_t = 2, value_parser = at_least_one::<u32>)]
    pub pairs: u32,
    /// Random seed.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Output folder.
    #[arg(long, default_value = "bench-out/estimators")]
    pub out: PathBuf,
    /// Worker threads (default: all cores).
    #[arg(short = 't', value_name = "THREADS", value_parser = thread_count)]
    pub threads: Option<usize>,
}

#[cfg(feature = "bench")]
#[derive(Args, Debug)]
pub struct BenchStabilityArgs {
    /// Output folder.
    #[arg(long, default_value = "bench-out/stability")]
    pub out: PathBuf,
    /// Multiplies every case's samples per pixel.
    #[arg(long, default_value_t = 1.0)]
    pub spp_scale: f32,
    /// Random seed.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Worker threads (default: all cores).
    #[arg(short = 't', value_name = "THREADS", value_parser = thread_count)]
    pub threads: Option<usize>,
}

#[cfg(feature = "bench")]
fn parse_bench_scene(s: &str) -> Result<ember::bench::accel::BenchScene, String> {
    ember::bench::accel::BenchScene::parse(s)
}

#[derive(Args, Debug)]
pub struct RenderArgs {
    /// The .dae (COLLADA) scene to render.
    pub scene: Option<PathBuf>,

    /// Worker threads (default: all cores). The image does not depend on it.
    #[arg(short = 't', value_name = "THREADS", value_parser = thread_count)]
    pub threads: Option<usize>,

    /// Camera rays (samples) per pixel; with -a, the most a pixel takes [default: 1; with --time, no cap].
    #[arg(short = 's', value_name = "SPP", value_parser = at_least_one::<u32>)]
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

    /// Adaptive sampling: after every BATCH samples stop a pixel once 1.96·σ/√n ≤ TOL·μ (or at -s). A pixel whose samples are all zero stops only once n zeros would have a chance of at most 1% if light reached it a quarter as often as it reaches the pixels within 5 px in their first batch, so light found rarely is not missed (README). `-a` alone means 32 0.05. As in the course, -s is the most samples a pixel takes (its default is 1: give it, e.g. -s 1024 -a).
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

    /// Intersection backend. auto: the native BVH (auto would switch to Embree above a measured primitive count,
    /// but the last measurement found no size where Embree is faster; `ember info SCENE` says which and why).
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

    /// Which numbers pixel samples draw: sobol stratifies every pair of numbers of every bounce
    /// over a pixel's samples (Owen-scrambled Sobol points); independent draws uniform numbers
    /// (for comparison).
    #[arg(long, value_parser = named::<SamplerKind>(), default_value_t = SamplerKind::Sobol)]
    pub sampler: SamplerKind,

    /// Samples of light of at most one bounce (emitters seen directly, direct light at the first surface) per pixel sample, in the pixels where that light is noisy: lights' outlines, glossy reflections of lights. A one-sample pilot finds them; there the paths count only light of more bounces. Those pixels converge far faster (in linear radiance; clamped to 1 in a PNG an outline hardly shows), for 2-12 % more time on the course's Cornell boxes. 0: off; at most 1024. (Formerly --emitter-edges.)
    #[arg(long, alias = "emitter-edges", value_name = "FACTOR",
          default_value_t = RenderSettings::DEFAULT_DIRECT_SPLIT,
          value_parser = clap::value_parser!(u32).range(0..=1024))]
    pub direct_split: u32,

    /// Estimator. auto: where a light (other than ambient or environment) shines on a mirror, glass or smooth metal (microfacet alpha at most 0.3) surface, another surface can receive the caustic, -m is at least 2 and no emissive surface is not a light, caustics (path tracing with light-traced caustics; path tracing with -a); where every light is a point or spot light, nothing is specular or self-emitting and -m is at least 2, light tracing or path tracing, whichever a small pilot render of each finds less noisy per ray traced (light tracing on CBempty, path tracing on CMU462's basic scenes); otherwise path tracing with MIS (light + BSDF sampling) when the scene has an ambient or environment (-e) light, MIS at glossy surfaces and light sampling at diffuse ones (mis-glossy) when it has glossy surfaces, light sampling otherwise. A direct-lighting strategy name means path tracing with it. -H forces hemisphere.
    #[arg(long, value_parser = integrator(), default_value = AUTO)]
    pub integrator: IntegratorChoice,

    /// Russian roulette: off, throughput (continue with probability max(throughput), at least 0.05, with refraction's (ηi/ηt)² factors left out), or a fixed probability like 0.5.
    #[arg(long, default_value = "throughput", value_name = "off|throughput|PROB")]
    pub rr: String,

    #[arg(long, value_name = "BOUNCE", help = format!(
        "First bounce at which Russian roulette may end a path [default: {}]. It never plays \
         at the -m cap, where the last ray only looks for emission.",
        Roulette::DEFAULT_START
    ))]
    pub rr_start: Option<u32>,

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

/// The most worker threads `-t` takes: far beyond any machine's cores (more only
/// slow a render), and short of what the system refuses to start.
pub(super) const MAX_THREADS: usize = 1024;

/// `-t`: 1 to [`MAX_THREADS`].
fn thread_count(s: &str) -> Result<usize, String> {
    let n = at_least_one::<usize>(s)?;
    if n > MAX_THREADS {
        return Err(format!(
            "at most {MAX_THREADS} worker threads (this machine has {})",
            std::thread::available_parallelism().map_or(1, |c| c.get())
        ));
    }
    Ok(n)
}

/// A finite number of at least 0.
#[cfg(feature = "bench")]
fn non_negative_number(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if v.is_finite() && v >= 0.0 => Ok(v),
        _ => Err("expected a finite number of at least 0".into()),
    }
}

/// A finite number of seconds above 0.
#[cfg(feature = "bench")]
fn positive_seconds(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        _ => Err("expected a finite number of seconds above 0".into()),
    }
}

/// A count of at least 1 (`-s`, `-t`): "-s 0" and "-s -1" get the same message.
fn at_least_one<T: TryFrom<u64>>(s: &str) -> Result<T, String> {
    let n: i128 = s
        .parse()
        .map_err(|_| "expected a whole number of at least 1".to_string())?;
    if n < 1 {
        return Err("must be at least 1".into());
    }
    u64::try_from(n)
        .ok()
        .and_then(|n| T::try_from(n).ok())
        .ok_or_else(|| "too large".to_string())
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
