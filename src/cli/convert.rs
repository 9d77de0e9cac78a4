//! Flags into library settings: every check and translation of a flag's value lives here.

#[cfg(feature = "bench")]
use super::args::{
    BenchAccelArgs, BenchConvergeArgs, BenchEstimatorsArgs, BenchRenderArgs, BenchStabilityArgs,
    ReportArgs,
};
use super::args::{
    CameraPlacement, IntegratorChoice, LensArgs, PlacementArgs, RenderArgs, SimdChoice,
};
use anyhow::{bail, Context, Result};
use clap::ValueEnum;
use ember::accel::Backend;
#[cfg(feature = "bench")]
use ember::bench;
use ember::camera::course_file::CourseCameraFile;
use ember::camera::Camera;
use ember::integrators::{DirectStrategy, Estimator, Roulette};
use ember::render::{Adaptive, PixelRect, RenderSettings, Shading};
use ember::scene::Scene;
use ember::shard::Shard;
use std::path::{Path, PathBuf};
use std::time::Duration;

/// How a render runs: in one pass, or in passes under a time budget and/or with checkpoints.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct RunPlan {
    pub time: Option<Duration>,
    pub checkpoint: Option<Duration>,
}

impl RunPlan {
    /// Whether the render is a sequence of passes ([`ember::render::render_passes`]).
    pub fn in_passes(&self) -> bool {
        self.time.is_some() || self.checkpoint.is_some()
    }
}

/// `--time` and `--checkpoint`, checked against the settings they run.
pub(super) fn run_plan(args: &RenderArgs, settings: &RenderSettings) -> Result<RunPlan> {
    let seconds = |flag: &str, v: Option<f64>| -> Result<Option<Duration>> {
        v.map(|s| {
            Duration::try_from_secs_f64(s)
                .ok()
                .filter(|d| !d.is_zero())
                .with_context(|| {
                    format!("{flag}: expected a positive number of seconds, got {s:?}")
                })
        })
        .transpose()
    };
    let plan = RunPlan {
        time: seconds("--time", args.time)?,
        checkpoint: seconds("--checkpoint", args.checkpoint)?,
    };
    if plan.in_passes() && settings.adaptive.is_some() {
        bail!("--time and --checkpoint render in passes, which -a (adaptive sampling) does not: use one or the other");
    }
    if plan.in_passes() && settings.shading == Shading::BvhCost {
        bail!("--time and --checkpoint render in passes, which --shading bvh-cost (one heat map) does not");
    }
    Ok(plan)
}

pub(super) fn check_resolution(w: u32, h: u32) -> Result<()> {
    if w == 0 || h == 0 || (w as u64) * (h as u64) > 1 << 28 {
        bail!("resolution {w}x{h} is out of range (each side ≥ 1, at most 2^28 pixels)");
    }
    Ok(())
}

/// Flags that would do nothing, or something meaningless, in the chosen configuration.
pub(super) fn check_flags(args: &RenderArgs) -> Result<()> {
    let embree = args.accel == Backend::Embree;
    if (embree || args.accel == Backend::None) && args.bvh.is_some() {
        bail!(
            "--bvh chooses the native BVH's builder; it does nothing with --accel {}",
            args.accel
        );
    }
    if args.embree_quality.is_some() && !Backend::Embree.available() {
        bail!(
            "--embree-quality: this build has no Embree backend (rebuild with --features embree)"
        );
    }
    if args.embree_quality.is_some() && matches!(args.accel, Backend::Native | Backend::None) {
        bail!("--embree-quality applies only with --accel embree or auto");
    }
    if embree && args.shading == Shading::BvhCost {
        bail!("--shading bvh-cost counts the native BVH's node and primitive tests, which Embree does not expose; use --accel native");
    }
    if let Some(c) = args.cost_scale {
        if args.shading != Shading::BvhCost {
            bail!("--cost-scale applies only with --shading bvh-cost");
        }
        if !(c.is_finite() && c > 0.0) {
            bail!("--cost-scale: expected a positive count, got {c}");
        }
    }
    Ok(())
}

/// Flags that ember accepts but that do less than they seem to: `-l 0`, and `-a` whose
/// first batch already reaches the `-s` cap (the course's semantics: -s is the most).
pub(super) fn flag_warnings(args: &RenderArgs, settings: &RenderSettings) -> Vec<String> {
    let mut w = Vec::new();
    if args.light_samples == 0 {
        w.push("-l 0 takes one light sample per area light, as -l 1 does".to_string());
    }
    if let Some(a) = settings.adaptive {
        if args.spp.is_none() && args.time.is_none() {
            w.push(format!(
                "-a: -s is the most samples a pixel takes, and without -s that is 1, so every \
                 pixel gets one sample and none stops early; give the cap, e.g. -s {}",
                32 * a.batch
            ));
        } else if settings.spp <= a.batch {
            w.push(format!(
                "-a {}: the first batch already reaches -s {}, the most samples a pixel takes, \
                 so no pixel stops early; raise -s, e.g. -s {}",
                a.batch,
                settings.spp,
                32 * a.batch
            ));
        }
    }
    w
}

/// `-a [BATCH [TOL]]`: by default 32 and 0.05.
pub(super) fn parse_adaptive(a: &Option<Vec<String>>) -> Result<Option<Adaptive>> {
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

pub(super) fn parse_roulette(s: &str, start: Option<u32>) -> Result<Roulette> {
    if s == "off" && start.is_some() {
        bail!("--rr-start: Russian roulette is off (--rr off); give one of the two");
    }
    let start = start.unwrap_or(Roulette::DEFAULT_START);
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
pub(super) fn strategy(args: &RenderArgs) -> Option<DirectStrategy> {
    if args.hemisphere {
        return Some(DirectStrategy::Hemisphere);
    }
    args.integrator.strategy
}

/// Which way paths are built; `None` for auto (`Estimator::auto_for` the scene).
/// `-H` means path tracing unless an estimator was named.
pub(super) fn estimator(args: &RenderArgs) -> Option<Estimator> {
    args.integrator
        .estimator
        .or(args.hemisphere.then_some(Estimator::Path))
}

pub(super) fn settings_from(args: &RenderArgs) -> Result<RenderSettings> {
    // With --time and no -s, the clock decides how many samples a pixel gets.
    let spp = match (args.spp, args.time) {
        (Some(s), _) => s,
        (None, Some(_)) => u32::MAX,
        (None, None) => 1,
    };
    if args.env_map.is_some() && estimator(args) == Some(Estimator::LightTracing) {
        bail!("-e: light tracing does not support environment maps; use path tracing (--integrator auto, light or mis)");
    }
    if args.hemisphere {
        if let Some(named) = args
            .integrator
            .strategy
            .filter(|&s| s != DirectStrategy::Hemisphere)
        {
            bail!("-H (hemisphere sampling) and --integrator name two ways of sampling direct light ({named}); give one");
        }
        if estimator(args) == Some(Estimator::LightTracing) {
            bail!("-H (hemisphere sampling) has no meaning for light tracing, whose paths start at the lights; use --integrator path");
        }
    }
    let adaptive = parse_adaptive(&args.adaptive)?;
    no_radiance_flags(args, adaptive.is_some())?;
    if estimator(args) == Some(Estimator::Caustics) {
        caustics_allowed(adaptive.is_some())?;
    }
    if let Some(offset) = args.spp_offset {
        if adaptive.is_some() {
            bail!("--spp-offset cannot be used with adaptive sampling (-a): an adaptive pixel's sample count depends on all its samples, so its samples cannot be split into ranges; split by --shard instead");
        }
        if offset.checked_add(spp).is_none() {
            bail!("--spp-offset {offset} -s {spp}: the last sample index exceeds 2^32");
        }
    }
    Ok(RenderSettings {
        spp,
        light_samples: args.light_samples.max(1),
        max_depth: args.max_depth,
        accumulate: args.accumulate == 1,
        estimator: estimator(args),
        strategy: strategy(args),
        roulette: parse_roulette(&args.rr, args.rr_start)?,
        adaptive,
        shading: args.shading,
        seed: args.seed,
        spp_offset: args.spp_offset.unwrap_or(0),
        engine: args.engine,
        sampler: args.sampler,
        direct_split: args.direct_split,
    })
}

/// Refuses flags that steer how radiance is estimated when the image shows none
/// (`--shading normals` or `bvh-cost`): they would be ignored without a word.
fn no_radiance_flags(args: &RenderArgs, adaptive: bool) -> Result<()> {
    if args.shading == Shading::Radiance {
        return Ok(());
    }
    let shading = ember::names::Named::name(args.shading);
    if adaptive {
        bail!("-a: adaptive sampling stops on the noise of radiance, which --shading {shading} does not show; drop one");
    }
    if args.hemisphere || args.integrator != IntegratorChoice::default() {
        bail!("--integrator and -H choose how radiance is estimated, which --shading {shading} does not show; drop one");
    }
    Ok(())
}

/// `--simd`: caps the instruction set `ember::lanes::dispatch` runs with, process-wide;
/// an error where this CPU lacks the one asked for.
pub(super) fn limit_simd(choice: SimdChoice) -> Result<()> {
    if choice != SimdChoice::Auto {
        ember::lanes::limit_instruction_set(instruction_set_for(choice, "--simd")?);
    }
    Ok(())
}

/// The instruction set `choice` names (auto: the one `--simd` leaves); an error,
/// naming `flag`, where this CPU lacks it.
fn instruction_set_for(choice: SimdChoice, flag: &str) -> Result<ember::lanes::InstructionSet> {
    use ember::lanes::{instruction_set, widest_instruction_set, InstructionSet};
    let want = match choice {
        SimdChoice::Auto => return Ok(instruction_set()),
        SimdChoice::Avx512 => InstructionSet::Avx512,
        SimdChoice::Avx2 => InstructionSet::Avx2,
        SimdChoice::Portable => InstructionSet::Portable,
    };
    let widest = widest_instruction_set();
    if want > widest {
        let name = choice.to_possible_value().map(|v| v.get_name().to_string());
        bail!(
            "{flag} {}: this CPU has no {want} (the widest instruction set it has is {widest})",
            name.unwrap_or_default()
        );
    }
    Ok(want)
}

/// `--integrator caustics` traces a fixed number of light paths per sample index,
/// landing anywhere in the image: a pixel cannot stop on its own.
fn caustics_allowed(adaptive: bool) -> Result<()> {
    if adaptive {
        bail!("--integrator caustics cannot be used with -a (adaptive sampling): its light paths are counted per sample index over the whole image, not per pixel; use --integrator auto (path tracing when -a is given), light or mis");
    }
    Ok(())
}

/// The pixels a part (`--shard`, `--spp-offset`) renders and its shard; `None` for a
/// whole render. Parts are .exr files; a BVH-cost heat map is scaled by its own
/// pixels, so it cannot be split.
pub(super) fn part_plan(
    args: &RenderArgs,
    out: &Path,
    width: u32,
    height: u32,
) -> Result<Option<(PixelRect, Option<Shard>)>> {
    if args.shard.is_none() && args.spp_offset.is_none() {
        return Ok(None);
    }
    if ember::image_io::OutputFormat::from_path(out)? != ember::image_io::OutputFormat::Exr {
        bail!(
            "{}: a part (--shard, --spp-offset) is written as .exr for ember merge",
            out.display()
        );
    }
    if args.cell.is_some() {
        bail!(
            "-p cannot be used with --shard/--spp-offset: a part covers a band of the whole image"
        );
    }
    if args.shading == Shading::BvhCost {
        bail!("--shading bvh-cost cannot be rendered in parts: its colour scale depends on every pixel");
    }
    if args.time.is_some() || args.checkpoint.is_some() {
        bail!("--time/--checkpoint cannot be used with --shard/--spp-offset: a part must hold exactly its samples; split the samples with --spp-offset instead");
    }
    let Some(text) = &args.shard else {
        return Ok(Some((PixelRect::full(width, height), None)));
    };
    let shard = Shard::parse(text).map_err(anyhow::Error::msg)?;
    if shard.count > height {
        bail!(
            "--shard {shard}: {} bands but the image has {height} rows",
            shard.count
        );
    }
    Ok(Some((shard.rect(width, height), Some(shard))))
}

pub(super) fn output_path(args: &RenderArgs, scene: &Path) -> Result<PathBuf> {
    if let Some(out) = &args.output {
        check_image_destination("-f", out)?;
    }
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

/// An image is written to a file: `-` (standard output, for a text tool) is not one.
pub(super) fn check_image_destination(what: &str, out: &Path) -> Result<()> {
    if out == Path::new("-") {
        bail!("{what} -: standard output is not an image destination; give a file name ending in .png or .exr");
    }
    Ok(())
}

/// File types people try first, whose own loaders ember does not have.
const OTHER_SCENE_FORMATS: [&str; 12] = [
    "obj", "ply", "stl", "off", "fbx", "gltf", "glb", "3ds", "blend", "usd", "usda", "usdz",
];

/// ember reads COLLADA: a file named or made otherwise (an OBJ, a PLY, anything that is
/// not XML) is named as such, rather than reported as malformed XML by the loader.
pub(super) fn check_scene_file(path: &Path) -> Result<()> {
    let ext = (path.extension().and_then(|e| e.to_str()))
        .map(str::to_ascii_lowercase)
        .unwrap_or_default();
    if OTHER_SCENE_FORMATS.contains(&ext.as_str()) {
        bail!(
            "{}: ember reads COLLADA (.dae) scenes, not .{ext} files; export the model as COLLADA (Blender: File > Export > Collada)",
            path.display()
        );
    }
    // The first bytes decide; a file that cannot be read is left to the loader's message.
    let mut head = [0u8; 64];
    let Ok(n) = std::fs::File::open(path).and_then(|mut f| std::io::Read::read(&mut f, &mut head))
    else {
        return Ok(());
    };
    if loader_reads_as_is(&head[..n]) {
        return Ok(());
    }
    let text = head[..n]
        .strip_prefix(b"\xEF\xBB\xBF")
        .unwrap_or(&head[..n]);
    match text.iter().find(|b| !b.is_ascii_whitespace()) {
        Some(b'<') | None => Ok(()),
        Some(_) => bail!(
            "{}: not a COLLADA (.dae) scene: the file is not XML; ember reads COLLADA scenes only",
            path.display()
        ),
    }
}

/// Starts the loader recognises itself, which are not UTF-8 text: a `.zae` (zip)
/// archive, and UTF-16 XML with a byte-order mark or opening with `<`.
fn loader_reads_as_is(head: &[u8]) -> bool {
    const STARTS: [&[u8]; 5] = [b"PK\x03\x04", b"\xFF\xFE", b"\xFE\xFF", b"<\0", b"\0<"];
    STARTS.iter().any(|s| head.starts_with(s))
}

/// `-a` takes up to two values, so `ember -a scene.dae` hands the scene to `-a`;
/// give it back when it is clearly not a number.
pub(super) fn adopt_scene_from_adaptive(args: &mut RenderArgs) {
    if args.scene.is_some() {
        return;
    }
    if let Some(v) = args.adaptive.as_mut() {
        if v.last().is_some_and(|s| s.parse::<f64>().is_err()) {
            args.scene = v.pop().map(PathBuf::from);
        }
    }
}

/// `ember bench render`'s flags as the benchmark's options.
#[cfg(feature = "bench")]
pub(super) fn bench_render_options(
    a: BenchRenderArgs,
) -> Result<bench::render::RenderBenchOptions> {
    Ok(bench::render::RenderBenchOptions {
        scenes: match a.scenes.is_empty() {
            true => bench::render::RenderBenchOptions::default_scenes()?,
            false => a.scenes,
        },
        spp: a.spp,
        max_depth: a.max_depth,
        repeat: a.repeats.max(1),
        accels: bench::render::RenderBenchOptions::accels_for(a.accel, a.embree_steps),
        engines: a.engines,
        instruction_sets: (a.simds.into_iter())
            .map(|c| instruction_set_for(c, "--simds"))
            .collect::<Result<_>>()?,
    })
}

/// `ember bench accel`'s flags (without --scaling) as the benchmark's options.
#[cfg(feature = "bench")]
pub(super) fn bench_accel_options(a: BenchAccelArgs) -> Result<bench::accel::AccelBenchOptions> {
    if a.threads.is_empty() || a.threads.contains(&0) {
        bail!("--threads: each count must be at least 1");
    }
    if let Some(t) = a.threads.iter().find(|&&t| t > super::args::MAX_THREADS) {
        bail!(
            "--threads: {t} is more than the {} worker threads ember starts",
            super::args::MAX_THREADS
        );
    }
    let defaults = bench::accel::AccelBenchOptions::default();
    Ok(bench::accel::AccelBenchOptions {
        scenes: match a.scenes.is_empty() {
            true => bench::accel::AccelBenchOptions::default_scenes()?,
            false => a.scenes,
        },
        rays: a.rays,
        threads: a.threads,
        repeats: a.repeats.max(1),
        embree_quality: a.quality,
        embree_modes: !a.no_embree_modes,
        ..defaults
    })
}

/// `ember bench converge`'s flags as the benchmark's options.
#[cfg(feature = "bench")]
pub(super) fn bench_converge_options(
    a: BenchConvergeArgs,
) -> Result<bench::converge::ConvergeOptions> {
    let (width, height) = (a.resolution[0], a.resolution[1]);
    check_resolution(width, height)?;
    Ok(bench::converge::ConvergeOptions {
        scene: a.scene,
        reference_noise: match (a.reference_noise, &a.reference) {
            (None, Some(r)) => bench::stability::light_paths::manifest_noise(r)?,
            (noise, _) => noise,
        },
        reference: a.reference,
        width,
        height,
        max_depth: a.max_depth,
        max_spp: a.max_spp,
        max_seconds_per_point: a.max_seconds,
        reference_spp: a.reference_spp,
        out_dir: a.out,
        seed: a.seed,
        seeds: a.seeds,
        compare_backends: true,
        mitsuba: a.mitsuba.map(|python| bench::converge::MitsubaPeer {
            python,
            variants: a.mitsuba_variants,
            samplers: a.mitsuba_samplers,
            roulettes: a.mitsuba_rr,
        }),
        cycles: a.cycles,
    })
}

/// `ember bench estimators`'s flags as the benchmark's options (no scenes: every
/// scene the data folder has).
#[cfg(feature = "bench")]
pub(super) fn bench_estimators_options(
    a: BenchEstimatorsArgs,
) -> Result<bench::estimators::EstimatorsOptions> {
    let (width, height) = (a.resolution[0], a.resolution[1]);
    check_resolution(width, height)?;
    for scene in &a.scenes {
        check_scene_file(scene)?;
    }
    let scenes = match a.scenes.is_empty() {
        true => bench::estimators::scenes_under(&ember::data::root()?.join("scenes"))?,
        false => a.scenes,
    };
    Ok(bench::estimators::EstimatorsOptions {
        scenes,
        max_depth: a.max_depth,
        width,
        height,
        spp: a.spp,
        pairs: a.pairs,
        seed: a.seed,
    })
}

/// `ember bench stability`'s flags as the benchmark's options.
#[cfg(feature = "bench")]
pub(super) fn bench_stability_options(
    a: &BenchStabilityArgs,
) -> Result<bench::stability::StabilityOptions> {
    if !(a.spp_scale.is_finite() && a.spp_scale > 0.0) {
        bail!("--spp-scale must be a positive number");
    }
    Ok(bench::stability::StabilityOptions {
        spp_scale: a.spp_scale,
        seed: a.seed,
    })
}

/// `ember report`'s flags as the report's options: the scenes are checked to be COLLADA
/// files, and without --mitsuba a full report charts the Mitsuba that
/// scripts/mitsuba-env installed, if any.
#[cfg(feature = "bench")]
pub(super) fn report_options(a: &ReportArgs) -> Result<ember::report::ReportOptions> {
    for scene in &a.scenes {
        check_scene_file(scene)?;
        if !scene.is_file() {
            bail!("{}: no such scene file", scene.display());
        }
    }
    if a.out.is_file() {
        bail!("--out {}: is a file, not a folder", a.out.display());
    }
    if let Some(python) = &a.mitsuba {
        if !python.is_file() {
            bail!(
                "--mitsuba {}: no such file (scripts/mitsuba-env prints the Python to give)",
                python.display()
            );
        }
    }
    let installed = || (!a.quick).then(ember::report::installed_mitsuba).flatten();
    Ok(ember::report::ReportOptions {
        out: a.out.clone(),
        quick: a.quick,
        scenes: a.scenes.clone(),
        seed: a.seed,
        mitsuba: a.mitsuba.clone().or_else(installed),
    })
}

/// `-e FILE.exr`: the scene lit by that environment map instead of its ambient light.
pub(super) fn apply_env_map(env_map: Option<&Path>, scene: &mut ember::scene::Scene) -> Result<()> {
    if let Some(path) = env_map {
        let env = ember::lights::EnvironmentMap::load(path)?;
        scene.set_environment(std::sync::Arc::new(env));
    }
    Ok(())
}
/// The scene's camera with `--camera-placement` applied.
fn placed(scene: &Scene, lens: &LensArgs) -> ember::scene::CameraDesc {
    let mut desc = scene.camera;
    if let Some(p) = forced_placement(&lens.placement) {
        desc.placement = p;
    }
    desc
}

/// The placement `--camera-placement` chooses; `None` for auto, the loader's choice.
fn forced_placement(flag: &PlacementArgs) -> Option<ember::scene::Placement> {
    use ember::scene::Placement;
    match flag.camera_placement {
        CameraPlacement::Auto => None,
        CameraPlacement::Course => Some(Placement::Course),
        CameraPlacement::File => Some(Placement::File),
    }
}

/// `--camera-placement` applied to the scene itself, with the flag as the reason
/// `ember info` gives.
pub(super) fn apply_placement(scene: &mut Scene, flag: &PlacementArgs) {
    if let Some(p) = forced_placement(flag) {
        scene.camera.placement = p;
        let name = clap::ValueEnum::to_possible_value(&flag.camera_placement).expect("not skipped");
        scene.placement_reason = format!("--camera-placement {}", name.get_name());
    }
}

/// `-b` and `-d` on their own: a radius of at least 0, a positive distance.
pub(super) fn check_lens(lens: &LensArgs) -> Result<()> {
    if let Some(b) = lens.lens_radius {
        if !(b.is_finite() && b >= 0.0) {
            bail!("-b: the lens radius must be a finite number of at least 0, got {b}");
        }
    }
    if let Some(d) = lens.focal_distance {
        if !(d.is_finite() && d > 0.0) {
            bail!("-d: the focal distance must be a positive finite number, got {d}");
        }
    }
    Ok(())
}

/// The render's camera: the `-c` file's view if given, else the scene's (spec §4); then
/// `-b`/`-d` replace the lens. Also returns a warning about the file's field of view.
pub(super) fn camera(
    scene: &Scene,
    file: Option<&CourseCameraFile>,
    lens: &LensArgs,
    (width, height): (u32, u32),
) -> Result<(Camera, Option<String>)> {
    let (mut cam, warning) = match file {
        Some(f) => f.camera(width, height),
        None => (
            Camera::new(&placed(scene, lens), &scene.bounds, width, height),
            None,
        ),
    };
    if let Some(b) = lens.lens_radius {
        cam.lens.radius = b;
    }
    if let Some(d) = lens.focal_distance {
        cam.lens.focal_distance = d;
    }
    if !cam.lens.is_pinhole() && cam.lens.focal_distance <= 0.0 {
        bail!("-b: a lens needs a positive focal distance; give one with -d");
    }
    Ok((cam, warning))
}

/// `-p X Y DX DY` (Y counted from the bottom, as the course's frame buffer) as the pixel
/// rectangle of a `width × height` image (rows counted from the top), checked to lie inside.
pub(super) fn cell_rect(cell: &[u32], width: u32, height: u32) -> Result<PixelRect> {
    let &[x, y, dx, dy] = cell else {
        bail!("-p takes four values: X Y DX DY");
    };
    if dx == 0 || dy == 0 {
        bail!("-p {x} {y} {dx} {dy}: the cell is empty (DX and DY must be at least 1)");
    }
    if x as u64 + dx as u64 > width as u64 || y as u64 + dy as u64 > height as u64 {
        bail!(
            "-p {x} {y} {dx} {dy}: the cell (columns {x}..{}, rows {y}..{} from the bottom) \
             is not inside the {width}x{height} image",
            x as u64 + dx as u64,
            y as u64 + dy as u64
        );
    }
    Ok(PixelRect {
        x0: x,
        x1: x + dx,
        y0: height - y - dy,
        y1: height - y,
    })
}
