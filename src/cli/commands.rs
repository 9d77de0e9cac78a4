//! One short function per subcommand: convert the flags, call the library, report.

use super::args::{ExportArgs, ExportFormat, RenderArgs};
use super::convert::{adopt_scene_from_adaptive, check_resolution, output_path, settings_from};
use anyhow::{bail, Result};
use ember::accel;
use ember::render::RenderJob;
use ember::scene::{collada, Scene};
use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// `ember [OPTIONS] SCENE`: one render to an image file.
pub(super) fn render(mut args: RenderArgs) -> Result<()> {
    adopt_scene_from_adaptive(&mut args);
    if !args.accel.available() {
        bail!("{}", accel::AccelError::EmbreeUnavailable);
    }
    let Some(scene_path) = args.scene.clone() else {
        bail!("no scene given; usage: ember [OPTIONS] SCENE.dae (see ember --help)");
    };
    let (width, height) = (args.resolution[0], args.resolution[1]);
    check_resolution(width, height)?;
    let settings = settings_from(&args)?;
    let out = output_path(&args, &scene_path)?;
    // Claim the outputs before loading, so a bad path fails at once and no partial file appears.
    let pending = ember::image_io::PendingImage::claim(&out, &[&scene_path])?;
    let pending_rate = match settings.adaptive {
        Some(_) => Some(ember::image_io::PendingImage::claim(
            &rate_path(&out),
            &[&scene_path],
        )?),
        None => None,
    };
    let kind = match accel::AccelKind::new(args.accel, args.bvh, args.embree_quality) {
        // The BVH-cost heat map counts the native tree's traversal steps, which
        // Embree does not expose: auto keeps the native tree for it.
        accel::AccelKind::Auto { bvh, .. }
            if settings.shading == ember::render::Shading::BvhCost =>
        {
            accel::AccelKind::Native(bvh)
        }
        kind => kind,
    };
    let pool = thread_pool(args.threads)?;
    let t0 = Instant::now();
    let scene = load_scene(&scene_path)?;
    let t_load = t0.elapsed();
    let t1 = Instant::now();
    let job = pool.install(|| RenderJob::new(scene, kind, width, height))?;
    let t_build = t1.elapsed();
    for w in job.warnings(&settings) {
        ember::errln!("ember: warning: {w}");
    }
    let frame = job.full_frame();
    let pb = progress_bar(frame.area(), args.quiet);
    let t2 = Instant::now();
    let output = pool.install(|| job.render_rect(&settings, frame, &|n| pb.inc(n)));
    let t_render = t2.elapsed();
    pb.finish_and_clear();
    let meta = ember::image_metadata::ImageMetadata::for_render(
        &scene_path,
        &job,
        &settings,
        t_render.as_secs_f64(),
    );
    pending.write_with_metadata(&output.image, &meta)?;
    if let Some(pending_rate) = pending_rate {
        let rate = pending_rate.path().to_path_buf();
        pending_rate.write_with_metadata(&output.rate_image(settings.spp), &meta)?;
        if !args.quiet {
            ember::errln!("ember: sample rate map written to {}", rate.display());
        }
    }
    if output.nonfinite_samples > 0 {
        ember::errln!(
            "ember: warning: {} samples were NaN or infinite and were counted as black",
            output.nonfinite_samples
        );
    }
    if !args.quiet {
        let samples = output.total_samples();
        ember::errln!(
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
            ember::errln!("ember: bvh-cost scale: blue = 0, red = {s:.0} nodes + primitives tested per camera ray (99th percentile)");
        }
    }
    Ok(())
}

/// `ember info SCENE`: what the scene holds and the backends of this build.
pub(super) fn info(path: &Path, w: u32, h: u32) -> Result<()> {
    // An image prints the metadata it was written with.
    if ember::image_io::OutputFormat::from_path(path).is_ok() {
        let meta = ember::image_io::read_metadata(path)?;
        ember::outln!("{}", path.display())?;
        ember::out!("{}", meta.to_text())?;
        return Ok(());
    }
    check_resolution(w, h)?;
    let scene = load_scene(path)?;
    ember::outln!("{}", path.display())?;
    ember::out!("{}", ember::info::scene_info(&scene, w, h))?;
    ember::outln!("{}", accel::backends_info())?;
    let auto = accel::choose_auto(&scene);
    ember::outln!(
        "--accel auto (the default) picks {}: {}",
        auto.kind,
        auto.reason
    )?;
    Ok(())
}

fn load_scene(path: &Path) -> Result<Scene> {
    let scene = collada::load(path)?;
    for w in &scene.warnings {
        ember::errln!("ember: warning: {w}");
    }
    Ok(scene)
}

fn thread_pool(threads: Option<usize>) -> Result<rayon::ThreadPool> {
    if threads == Some(0) {
        bail!("-t: thread count must be at least 1");
    }
    Ok(accel::tracing_pool(threads)?)
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

/// `ember export`: the scene in another renderer's format, for side-by-side measurements.
pub(super) fn export(a: ExportArgs) -> Result<()> {
    let (w, h) = (a.resolution[0], a.resolution[1]);
    check_resolution(w, h)?;
    if a.spp == 0 {
        bail!("-s must be at least 1");
    }
    let scene = load_scene(&a.scene)?;
    let camera = ember::camera::Camera::new(&scene.camera, &scene.bounds, w, h);
    std::fs::create_dir_all(&a.out)
        .map_err(|e| anyhow::anyhow!("{}: cannot create folder: {e}", a.out.display()))?;
    let stem = a
        .scene
        .file_stem()
        .map_or("scene".into(), |s| s.to_string_lossy().into_owned());
    let ExportFormat::Mitsuba = a.format;
    let settings = ember::export::MitsubaSettings::for_ember(
        a.spp,
        a.max_depth,
        &ember::integrators::Roulette::default(),
    );
    let summary = ember::export::write_mitsuba(&scene, &camera, &settings, &a.out, &stem)?;
    for w in &summary.warnings {
        ember::errln!("ember: warning: {w}");
    }
    ember::outln!("{}", summary.files[0].display())?;
    Ok(())
}
