//! One short function per subcommand: convert the flags, call the library, report.

use super::args::{CameraArgs, ExportArgs, ExportFormat, RenderArgs};
use super::convert::{
    self, adopt_scene_from_adaptive, apply_env_map, cell_rect, check_lens, check_resolution,
    output_path, part_plan, settings_from,
};
use anyhow::{bail, Result};
use ember::accel;
use ember::camera::course_file::CourseCameraFile;
use ember::image_metadata::ImageMetadata;
use ember::integrators::Estimator;
use ember::render::{PixelRect, RenderJob, RenderSettings};
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
    check_lens(&args.lens)?;
    let camera_file = (args.camera_file.as_deref())
        .map(CourseCameraFile::read)
        .transpose()?;
    let cell = (args.cell.as_deref())
        .map(|c| cell_rect(c, width, height))
        .transpose()?;
    let out = output_path(&args, &scene_path)?;
    let part = part_plan(&args, &out, width, height)?;
    // Claim the outputs before loading, so a bad path fails at once and no partial file appears.
    let inputs: Vec<&Path> = std::iter::once(scene_path.as_path())
        .chain(args.env_map.as_deref())
        .collect();
    let pending = ember::image_io::PendingImage::claim(&out, &inputs)?;
    let pending_rate = match (settings.adaptive, part) {
        (Some(_), None) => Some(ember::image_io::PendingImage::claim(
            &rate_path(&out),
            &inputs,
        )?),
        _ => None,
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
    let mut scene = load_scene(&scene_path)?;
    apply_env_map(args.env_map.as_deref(), &mut scene)?;
    let t_load = t0.elapsed();
    if part.is_some() && settings.estimator_for(&scene) == Estimator::LightTracing {
        bail!("--shard/--spp-offset cannot be used with light tracing (the estimator for {}): its light paths splat anywhere in the image, so every band would trace all of them, and its paths are not numbered by sample; use --integrator path", scene_path.display());
    }
    let (camera, camera_warning) =
        convert::camera(&scene, camera_file.as_ref(), &args.lens, (width, height))?;
    if let (Some(w), Some(file)) = (camera_warning, &args.camera_file) {
        ember::errln!("ember: warning: {}: {w}", file.display());
    }
    let t1 = Instant::now();
    let job = pool.install(|| RenderJob::with_camera(scene, kind, camera))?;
    let t_build = t1.elapsed();
    for w in job.warnings(&settings) {
        ember::errln!("ember: warning: {w}");
    }
    if cell.is_some() && settings.shading == ember::render::Shading::BvhCost {
        ember::errln!("ember: warning: -p: the bvh-cost heat map is scaled to the cell's own pixels, not the full image's");
    }
    let rect = match (part, cell) {
        (Some((band, _)), _) => band,
        (None, Some(cell)) => cell,
        (None, None) => job.full_frame(),
    };
    let pb = progress_bar(rect.area(), args.quiet);
    let t2 = Instant::now();
    let mut output = pool.install(|| job.render_rect(&settings, rect, &|n| pb.inc(n)));
    let t_render = t2.elapsed();
    pb.finish_and_clear();
    if args.full_frame {
        output = output.into_frame(rect, width, height);
    }
    let mut meta = render_metadata(
        &scene_path,
        &args,
        &job,
        &settings,
        cell,
        t_render.as_secs_f64(),
    );
    match part {
        None => pending.write_with_metadata(&output.image, &meta)?,
        Some((rect, shard)) => {
            if let Some(shard) = shard {
                meta.push("ember.shard", shard);
            }
            pending.write_part(&ember::shard::Part {
                name: out.display().to_string(),
                meta: meta.clone(),
                frame: (width, height),
                rect,
                image: output.image.clone(),
                samples: output.samples.clone(),
            })?
        }
    }
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

/// `ember merge OUT PARTS...`: the parts of a sharded render assembled into one image.
pub(super) fn merge(out: &Path, parts: &[PathBuf]) -> Result<()> {
    let inputs: Vec<&Path> = parts.iter().map(PathBuf::as_path).collect();
    let pending = ember::image_io::PendingImage::claim(out, &inputs)?;
    let parts = parts
        .iter()
        .map(|p| ember::image_io::read_part(p))
        .collect::<Result<Vec<_>, _>>()?;
    let merged = ember::shard::merge(&parts)?;
    pending.write_with_metadata(&merged.image, &merged.meta)?;
    ember::errln!(
        "ember: merged {} parts ({}x{}, {} spp) into {}",
        parts.len(),
        merged.image.width,
        merged.image.height,
        merged.meta.get("ember.spp").unwrap_or("?"),
        out.display()
    );
    Ok(())
}

/// What the image records: the render's settings, and the camera file and cell if given.
fn render_metadata(
    scene: &Path,
    args: &RenderArgs,
    job: &RenderJob,
    settings: &RenderSettings,
    cell: Option<PixelRect>,
    seconds: f64,
) -> ImageMetadata {
    let mut meta = ImageMetadata::for_render(scene, job, settings, seconds);
    if let Some(file) = &args.camera_file {
        meta.push_file("ember.camera_file", file);
    }
    if let Some(file) = &args.env_map {
        meta.push_file("ember.env_map", file);
    }
    if let (Some(c), Some(r)) = (&args.cell, cell) {
        meta.push(
            "ember.cell",
            format!(
                "X Y DX DY = {} {} {} {} (pixels {}..{} x {}..{} from the top left){}",
                c[0],
                c[1],
                c[2],
                c[3],
                r.x0,
                r.x1,
                r.y0,
                r.y1,
                if args.full_frame { ", full frame" } else { "" }
            ),
        );
    }
    meta
}

/// `ember camera SCENE [--save FILE]`: the course's camera settings file of the scene's camera.
pub(super) fn camera(a: CameraArgs) -> Result<()> {
    let (w, h) = (a.resolution[0], a.resolution[1]);
    check_resolution(w, h)?;
    check_lens(&a.lens)?;
    let scene = load_scene(&a.scene)?;
    let (camera, _) = convert::camera(&scene, None, &a.lens, (w, h))?;
    let text = CourseCameraFile::from_camera(&camera, &scene.bounds).to_text();
    match &a.save {
        None => ember::out!("{text}")?,
        Some(path) => write_text_file(path, &text)?,
    }
    Ok(())
}

/// Writes `text` to `path` through a temporary sibling, so no partial file is ever left.
fn write_text_file(path: &Path, text: &str) -> Result<()> {
    let fail = |e: std::io::Error| anyhow::anyhow!("{}: cannot write: {e}", path.display());
    let mut tmp_name = path.file_name().unwrap_or_default().to_os_string();
    tmp_name.push(".ember-tmp");
    let tmp = path.with_file_name(tmp_name);
    std::fs::write(&tmp, text).map_err(fail)?;
    std::fs::rename(&tmp, path).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        fail(e)
    })
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
    let mut scene = load_scene(&a.scene)?;
    apply_env_map(a.env_map.as_deref(), &mut scene)?;
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
