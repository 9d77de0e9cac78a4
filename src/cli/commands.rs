//! One short function per subcommand: convert the flags, call the library, report.

use super::args::{CameraArgs, ExportArgs, ExportFormat, PlacementArgs, RenderArgs};
use super::convert::{
    self, adopt_scene_from_adaptive, apply_env_map, cell_rect, check_flags,
    check_image_destination, check_lens, check_resolution, check_scene_file, flag_warnings,
    output_path, part_plan, run_plan, settings_from, RunPlan,
};
use super::interrupt::{self, Interrupted};
use anyhow::{bail, Context, Result};
use ember::accel;
use ember::camera::course_file::CourseCameraFile;
use ember::image_io::{is_same_file, OutputFormat, PendingImage};
use ember::image_metadata::ImageMetadata;
use ember::integrators::Estimator;
use ember::render::{
    render_passes, Engine, Film, PixelRect, RenderJob, RenderOutput, RenderSettings, Shading,
    StopReason, StopToken,
};
use ember::scene::{collada, Scene};
use ember::shard::Shard;
use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::sync::atomic::Ordering;
use std::time::{Duration, Instant};

/// `ember [OPTIONS] SCENE`: one render to an image file.
pub(super) fn render(mut args: RenderArgs) -> Result<()> {
    adopt_scene_from_adaptive(&mut args);
    let req = RenderRequest::new(&args)?;
    // Claim the outputs before loading, so a bad path fails at once and no partial file appears.
    let inputs: Vec<&Path> = std::iter::once(req.scene_path.as_path())
        .chain(args.env_map.as_deref())
        .collect();
    let mut pending = PendingImage::claim(&req.out, &inputs)?;
    let pending_rate = match (req.settings.adaptive, &req.part) {
        (Some(_), None) => Some(PendingImage::claim(&rate_path(&req.out), &inputs)?),
        _ => None,
    };
    let interrupt = interrupt::install()?;
    let pool = thread_pool(args.threads)?;
    req.check_memory()?;
    let (job, t_load, t_build) = req.build_job(&args, &pool)?;
    // Again now that the scene and its BVH hold their share.
    req.check_memory()?;
    if interrupt.load(Ordering::Relaxed) {
        return Err(Interrupted("interrupted before rendering; nothing written".into()).into());
    }
    req.warn_before_rendering(&args, &job, pool.current_num_threads());
    let t2 = Instant::now();
    let mut stop = StopToken::never().with_flag(interrupt);
    if let Some(t) = req.plan.time {
        stop = stop.with_deadline(t2 + t);
    }
    let run = RenderRun {
        scene_path: &req.scene_path,
        out: &req.out,
        args: &args,
        job: &job,
        settings: &req.settings,
        cell: req.cell,
        part: req.part,
    };
    let done = pool.install(|| run.execute(req.plan, &stop, &mut pending))?;
    let t_render = t2.elapsed();
    let cost_scale = run.write(&done, pending, pending_rate, t_render.as_secs_f64())?;
    if done.output.nonfinite_samples > 0 {
        ember::errln!(
            "ember: warning: {} samples were NaN or infinite and were counted as black",
            done.output.nonfinite_samples
        );
    }
    if !args.quiet {
        let samples = done.output.total_samples();
        ember::errln!(
            "ember: {}: loaded in {:.1} ms, {} built in {:.1} ms, {} samples in {:.3} s ({:.2} M samples/s); {}; wrote {}",
            req.scene_path.display(),
            t_load.as_secs_f64() * 1e3,
            job.accel.name(),
            t_build.as_secs_f64() * 1e3,
            samples,
            t_render.as_secs_f64(),
            samples as f64 / t_render.as_secs_f64() / 1e6,
            run.summary(&done, pool.current_num_threads()),
            req.out.display()
        );
    }
    run.outcome(&done, cost_scale)
}

/// A render's flags checked and converted, before anything is loaded.
struct RenderRequest {
    scene_path: PathBuf,
    width: u32,
    height: u32,
    settings: RenderSettings,
    plan: RunPlan,
    camera_file: Option<CourseCameraFile>,
    /// `-p`: the cell rendered instead of the whole image.
    cell: Option<PixelRect>,
    out: PathBuf,
    part: Option<(PixelRect, Option<Shard>)>,
    full_frame: bool,
}

impl RenderRequest {
    fn new(args: &RenderArgs) -> Result<RenderRequest> {
        check_flags(args)?;
        if !args.accel.available() {
            bail!("{}", accel::AccelError::EmbreeUnavailable);
        }
        let Some(scene_path) = args.scene.clone() else {
            return Err(super::UsageError(
                "no scene given; usage: ember [OPTIONS] SCENE.dae (see ember --help)".into(),
            )
            .into());
        };
        let (width, height) = (args.resolution[0], args.resolution[1]);
        check_resolution(width, height)?;
        let settings = settings_from(args)?;
        let plan = run_plan(args, &settings)?;
        check_lens(&args.lens)?;
        let camera_file = (args.camera_file.as_deref())
            .map(CourseCameraFile::read)
            .transpose()?;
        let cell = (args.cell.as_deref())
            .map(|c| cell_rect(c, width, height))
            .transpose()?;
        let out = output_path(args, &scene_path)?;
        let part = part_plan(args, &out, width, height)?;
        // Only once every flag is known to be good.
        for w in flag_warnings(args, &settings) {
            ember::errln!("ember: warning: {w}");
        }
        Ok(RenderRequest {
            scene_path,
            width,
            height,
            settings,
            plan,
            camera_file,
            cell,
            out,
            part,
            full_frame: args.full_frame,
        })
    }

    /// At most how many rays the render traces: per sample, the camera ray and, at each
    /// of up to -m bounces, one continuation and -l shadow rays per light (for
    /// `--accel none`'s time estimate; roulette and escaping paths only make it fewer).
    fn most_rays(&self, job: &RenderJob) -> f64 {
        let pixels = match self.cell {
            Some(r) => r.area(),
            None => self.width as u64 * self.height as u64,
        };
        let s = &self.settings;
        let per_sample = match s.shading {
            Shading::Radiance => {
                let shadow = s.light_samples as f64 * job.scene.lights.len() as f64;
                1.0 + s.max_depth as f64 * (1.0 + shadow)
            }
            _ => 1.0,
        };
        let spp = if s.spp == u32::MAX { 1 } else { s.spp };
        pixels as f64 * spp as f64 * per_sample
    }

    /// The buffers are the cell's, unless the cell is written in a full frame.
    fn check_memory(&self) -> Result<()> {
        let (w, h) = match (self.cell, self.full_frame) {
            (Some(r), false) => (r.width(), r.height()),
            _ => (self.width, self.height),
        };
        check_memory(w, h, self.plan)
    }

    /// The backend `--accel` asks for. The BVH-cost heat map counts the native tree's
    /// traversal steps, which Embree does not expose: auto keeps the native tree for it.
    fn accel_kind(&self, args: &RenderArgs) -> accel::AccelKind {
        match accel::AccelKind::new(
            args.accel,
            args.bvh.unwrap_or_default(),
            args.embree_quality.unwrap_or_default(),
        ) {
            accel::AccelKind::Auto { bvh, .. } if self.settings.shading == Shading::BvhCost => {
                accel::AccelKind::Native(bvh)
            }
            kind => kind,
        }
    }

    /// Loads the scene (and `-e` map), places the camera and builds the accelerator;
    /// returns the job with the load and build times.
    fn build_job(
        &self,
        args: &RenderArgs,
        pool: &rayon::ThreadPool,
    ) -> Result<(RenderJob, Duration, Duration)> {
        let t0 = Instant::now();
        let mut scene = load_scene(&self.scene_path)?;
        apply_env_map(args.env_map.as_deref(), &mut scene)?;
        let t_load = t0.elapsed();
        let (camera, camera_warning) = convert::camera(
            &scene,
            self.camera_file.as_ref(),
            &args.lens,
            (self.width, self.height),
        )?;
        if let (Some(w), Some(file)) = (camera_warning, &args.camera_file) {
            ember::errln!("ember: warning: {}: {w}", file.display());
        }
        let kind = self.accel_kind(args);
        let t1 = Instant::now();
        let job = pool.install(|| RenderJob::with_camera(scene, kind, camera))?;
        if self.part.is_some()
            && pool.install(|| job.estimator(&self.settings)) == Estimator::LightTracing
        {
            bail!("--shard/--spp-offset cannot be used with light tracing (the estimator for {}): its light paths splat anywhere in the image, so every band would trace all of them, and its paths are not numbered by sample; use --integrator path", self.scene_path.display());
        }
        if self.settings.engine == Engine::Packet {
            if let Some(why) = self.settings.packet_blocker() {
                bail!(
                    "--engine packet: {} needs the scalar engine ({why}); use --engine auto or scalar",
                    self.scene_path.display()
                );
            }
        }
        Ok((job, t_load, t1.elapsed()))
    }

    fn warn_before_rendering(&self, args: &RenderArgs, job: &RenderJob, threads: usize) {
        for w in job.warnings(&self.settings) {
            ember::errln!("ember: warning: {}: {w}", self.scene_path.display());
        }
        if args.accel == accel::Backend::None {
            let rays = self.most_rays(job);
            if let Some(w) = accel::brute::slow_warning(job.scene.num_prims(), rays, threads) {
                ember::errln!("ember: warning: {}: {w}", self.scene_path.display());
            }
        }
        if self.cell.is_some()
            && self.settings.shading == Shading::BvhCost
            && args.cost_scale.is_none()
        {
            ember::errln!("ember: warning: -p: the bvh-cost heat map is scaled to the cell's own pixels, not the full image's; --cost-scale fixes the scale");
        }
    }
}

/// The bvh-cost image: raw counts in an EXR, a heat map (blue 0, red `scale`) in a PNG.
/// Returns the scale used; both it and the mean cost go into the metadata.
fn write_cost_map(
    pending: PendingImage,
    output: &RenderOutput,
    scale: Option<f32>,
    meta: &mut ImageMetadata,
) -> Result<f32> {
    let (heat, scale) = output.cost_heat_map(scale);
    meta.push("ember.cost_scale", scale);
    meta.push(
        "ember.mean_cost_per_ray",
        format!("{:.4}", output.mean_cost_per_ray()),
    );
    let image = match pending.format() {
        OutputFormat::Exr => &output.image,
        OutputFormat::Png => &heat,
    };
    pending.write_with_metadata(image, meta)?;
    Ok(scale)
}

/// Refuses a render whose buffers (all allocated up front) would not fit in the
/// memory left, instead of dying of an allocation failure halfway.
fn check_memory(width: u32, height: u32, plan: RunPlan) -> Result<()> {
    let need = ember::render::render_bytes(width, height, plan.in_passes());
    let Some(free) = ember::render::available_bytes() else {
        return Ok(());
    };
    if need > free {
        let gib = |b: u64| b as f64 / (1u64 << 30) as f64;
        bail!(
            "-r {width} {height}: the render needs about {:.1} GiB for its image buffers, but only {:.1} GiB \
             of memory is available (MemAvailable, cgroup memory.max); choose a smaller -r",
            gib(need),
            gib(free)
        );
    }
    Ok(())
}

/// `ember merge OUT PARTS...`: the parts of a sharded render assembled into one image.
pub(super) fn merge(out: &Path, parts: &[PathBuf]) -> Result<()> {
    check_image_destination("merge", out)?;
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

/// What a render produced, and why it ended early if it did.
struct Rendered {
    output: RenderOutput,
    /// The pixels rendered: the whole image, the `-p` cell or a part's band.
    frame: PixelRect,
    passes: Option<u32>,
    stopped: Option<StopReason>,
}

/// One render's fixed inputs, shared by its run, its checkpoints and its metadata.
struct RenderRun<'a> {
    scene_path: &'a Path,
    out: &'a Path,
    args: &'a RenderArgs,
    job: &'a RenderJob,
    settings: &'a RenderSettings,
    /// `-p`: the cell rendered instead of the whole image.
    cell: Option<PixelRect>,
    /// `--shard`/`--spp-offset`: the band of a part for `ember merge`, and its shard.
    part: Option<(PixelRect, Option<Shard>)>,
}

impl RenderRun<'_> {
    /// Writes the image (and the rate map with -a) with their metadata; returns the
    /// bvh-cost scale used, if the image is a cost map.
    fn write(
        &self,
        done: &Rendered,
        pending: PendingImage,
        pending_rate: Option<PendingImage>,
        seconds: f64,
    ) -> Result<Option<f32>> {
        let mut meta = self.metadata(done, seconds);
        let cost_scale = match self.settings.shading {
            Shading::BvhCost => Some(write_cost_map(
                pending,
                &done.output,
                self.args.cost_scale,
                &mut meta,
            )?),
            _ => {
                match self.part {
                    None => pending.write_with_metadata(&done.output.image, &meta)?,
                    Some((rect, shard)) => {
                        if let Some(shard) = shard {
                            meta.push("ember.shard", shard);
                        }
                        pending.write_part(&ember::shard::Part {
                            name: self.out.display().to_string(),
                            meta: meta.clone(),
                            frame: (self.job.camera.width, self.job.camera.height),
                            rect,
                            image: done.output.image.clone(),
                            samples: done.output.samples.clone(),
                        })?
                    }
                }
                None
            }
        };
        if let Some(pending_rate) = pending_rate {
            let rate = pending_rate.path().to_path_buf();
            // The rate map: raw samples per pixel in an EXR, the course's colours (and
            // a legend below) in a PNG.
            let image = match pending_rate.format() {
                OutputFormat::Exr => done.output.sample_count_image(),
                OutputFormat::Png => {
                    let (w, h) = (done.output.image.width, done.output.image.height);
                    ember::film::sample_rate_map(w, h, &done.output.samples, self.settings.spp)
                }
            };
            pending_rate.write_with_metadata(&image, &meta)?;
            if !self.args.quiet {
                ember::errln!("ember: sample rate map written to {}", rate.display());
            }
        }
        Ok(cost_scale)
    }

    /// The last words: the cost map's scale, and how a stopped render ended (an
    /// interrupt is an `Interrupted` error, for exit status 130).
    fn outcome(&self, done: &Rendered, cost_scale: Option<f32>) -> Result<()> {
        if let (Some(scale), false) = (cost_scale, self.args.quiet) {
            ember::errln!(
                "ember: bvh-cost: mean {:.2} nodes + primitives tested per camera ray; PNG scale: blue = 0, red = {scale} ({})",
                done.output.mean_cost_per_ray(),
                match self.args.cost_scale {
                    Some(_) => "--cost-scale",
                    None => "99th percentile",
                }
            );
        }
        match done.stopped {
            Some(StopReason::Interrupted) => Err(Interrupted(format!(
                "interrupted: wrote what was rendered so far ({}) to {}",
                coverage(done),
                self.out.display()
            ))
            .into()),
            Some(StopReason::TimeUp) if !self.args.quiet => {
                ember::errln!("ember: time budget spent: wrote {}", coverage(done));
                Ok(())
            }
            _ => Ok(()),
        }
    }

    /// Renders in one pass, or in passes (writing checkpoints to `pending`) as `plan` says.
    fn execute(
        &self,
        plan: RunPlan,
        stop: &StopToken,
        pending: &mut PendingImage,
    ) -> Result<Rendered> {
        let frame = match (self.part, self.cell) {
            (Some((band, _)), _) => band,
            (None, Some(cell)) => cell,
            (None, None) => self.job.full_frame(),
        };
        let t0 = Instant::now();
        if !plan.in_passes() {
            let pb = progress_bar(frame.area(), self.args.quiet);
            let output = self
                .job
                .render_rect_until(self.settings, frame, &|n| pb.inc(n), stop);
            pb.finish_and_clear();
            return Ok(Rendered {
                output: self.framed(output),
                frame,
                passes: None,
                stopped: stop.reason(),
            });
        }
        // A time budget shows time spent; otherwise samples traced.
        let pb = match plan.time {
            Some(t) => progress_bar(t.as_millis() as u64, self.args.quiet),
            None => progress_bar(frame.area() * self.settings.spp as u64, self.args.quiet),
        };
        let tick = |n: u64| match plan.time {
            Some(_) => pb.set_position(t0.elapsed().as_millis() as u64),
            None => pb.inc(n),
        };
        let mut last = Instant::now();
        let mut checkpoint = |film: &Film| -> Result<()> {
            match plan.checkpoint {
                Some(every) if last.elapsed() >= every => {
                    let output = self.framed(film.output());
                    let mut meta = self.metadata_base(t0.elapsed().as_secs_f64());
                    meta.push_samples(&output.samples, Some(film.passes), None);
                    meta.push("ember.checkpoint", "true");
                    pending.checkpoint(&output.image, &meta)?;
                    last = Instant::now();
                    Ok(())
                }
                _ => Ok(()),
            }
        };
        let (film, stopped) =
            render_passes(self.job, self.settings, frame, &tick, stop, &mut checkpoint)?;
        pb.finish_and_clear();
        Ok(Rendered {
            output: self.framed(film.output()),
            frame,
            passes: Some(film.passes),
            stopped,
        })
    }

    /// With `-p … --full-frame`, the cell placed in the black full-size image.
    fn framed(&self, output: RenderOutput) -> RenderOutput {
        match (self.cell, self.args.full_frame) {
            (Some(rect), true) => {
                output.into_frame(rect, self.job.camera.width, self.job.camera.height)
            }
            _ => output,
        }
    }

    fn metadata_base(&self, seconds: f64) -> ImageMetadata {
        render_metadata(
            self.scene_path,
            self.args,
            self.job,
            self.settings,
            self.cell,
            seconds,
        )
    }

    /// The metadata of the final image: settings, samples taken, and how it ended.
    fn metadata(&self, done: &Rendered, seconds: f64) -> ImageMetadata {
        let mut meta = self.metadata_base(seconds);
        meta.push_samples(&done.output.samples, done.passes, done.stopped);
        meta
    }

    /// What was rendered and how, for the summary line: the resolution (and cell or
    /// band), what a pixel shows, the samples of the pixels rendered, seed, threads, engine.
    fn summary(&self, done: &Rendered, threads: usize) -> String {
        let s = self.settings;
        let mean = done.output.total_samples() as f64 / done.frame.area().max(1) as f64;
        let spp = match (s.adaptive, done.stopped, done.passes) {
            (None, None, _) => format!("{} spp", mean.round()),
            (Some(_), _, _) => format!("mean {mean:.1} spp (at most {}, -a)", s.spp),
            (None, _, _) => format!("mean {mean:.1} spp"),
        };
        let split = match done.output.split_pixels {
            0 => String::new(),
            n => format!(", {}x direct samples in {n} split pixels", s.direct_split),
        };
        let shows = match s.shading {
            Shading::Radiance => format!(
                "{} estimator, -m {}, -l {}{split}",
                ember::image_metadata::estimator_label(s, self.job),
                s.max_depth,
                s.light_samples
            ),
            other => format!("--shading {other}"),
        };
        let engine = if s.uses_packets() {
            format!(
                "packets of {} ({})",
                ember::lanes::LANES,
                ember::lanes::instruction_set()
            )
        } else {
            "one path at a time".into()
        };
        format!(
            "{}, {shows}, {spp}, seed {}, {}, {engine}",
            self.region(done.frame),
            s.seed,
            ember::names::thread_count(threads)
        )
    }

    /// `480x360`, or the part of it rendered: `cell 17x11 at (5, 3) of 40x30`.
    fn region(&self, frame: PixelRect) -> String {
        let (w, h) = (self.job.camera.width, self.job.camera.height);
        match (self.cell, &self.part) {
            (Some(_), _) => {
                let c = self.args.cell.as_deref().unwrap_or_default();
                format!("cell {}x{} at ({}, {}) of {w}x{h}", c[2], c[3], c[0], c[1])
            }
            (None, Some(_)) if frame.area() < w as u64 * h as u64 => {
                format!("rows {}..{} of {w}x{h}", frame.y0, frame.y1)
            }
            _ => format!("{w}x{h}"),
        }
    }
}

/// "N of M pixels, mean X spp": how much of the pixels asked for (the image, cell or
/// band) a stopped render holds.
fn coverage(done: &Rendered) -> String {
    let samples = &done.output.samples;
    let rendered = samples.iter().filter(|&&s| s > 0).count();
    let total: u64 = samples.iter().map(|&s| s as u64).sum();
    let asked = done.frame.area().max(1);
    format!(
        "{rendered} of {asked} pixels, mean {:.2} spp",
        total as f64 / asked as f64
    )
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
        Some(path) if is_same_file(path, &a.scene) => {
            bail!(
                "{}: is the input scene; --save would overwrite it",
                path.display()
            )
        }
        Some(path) => write_text_file(path, &text)?,
    }
    Ok(())
}

/// Writes `text` to `path` whole or not at all.
fn write_text_file(path: &Path, text: &str) -> Result<()> {
    ember::image_io::write_atomically(path, text.as_bytes())
        .map_err(|e| anyhow::anyhow!("{}: cannot write: {e}", path.display()))
}

/// `ember info SCENE`: what the scene holds and the backends of this build.
pub(super) fn info(path: &Path, w: u32, h: u32, placement: &PlacementArgs) -> Result<()> {
    // An image: what it holds, and the metadata it was written with.
    if ember::image_io::OutputFormat::from_path(path).is_ok() {
        let text = ember::info::image_info(path)?;
        ember::outln!("{}", path.display())?;
        ember::out!("{text}")?;
        return Ok(());
    }
    check_resolution(w, h)?;
    let mut scene = load_scene(path)?;
    convert::apply_placement(&mut scene, placement);
    ember::outln!("{}", path.display())?;
    ember::out!("{}", ember::info::scene_info(&scene, w, h))?;
    let t0 = Instant::now();
    let bvh = accel::build(&scene, accel::AccelKind::Native(accel::BvhBuilder::Sah))?;
    let build_ms = t0.elapsed().as_secs_f64() * 1e3;
    if let Some(stats) = bvh.bvh_stats() {
        ember::out!("{}", ember::info::bvh_info(&bvh.name(), &stats, build_ms))?;
    }
    ember::outln!("{}", accel::backends_info())?;
    let auto = accel::choose_auto(&scene);
    ember::outln!(
        "--accel auto (the default) picks {}: {}",
        auto.kind,
        auto.reason
    )?;
    // What the default render (`ember SCENE`) would run on, packets or single paths.
    match RenderSettings::default().packet_blocker() {
        None => ember::outln!(
            "--engine auto (the default) runs packets of {} paths ({})",
            ember::lanes::LANES,
            ember::lanes::instruction_set()
        )?,
        Some(why) => ember::outln!("--engine auto (the default) runs one path at a time: {why}")?,
    }
    Ok(())
}

fn load_scene(path: &Path) -> Result<Scene> {
    check_scene_file(path)?;
    let scene = collada::load(path)?;
    for w in &scene.warnings {
        ember::errln!("ember: warning: {w}");
    }
    Ok(scene)
}

/// The pool of `-t` threads (at least 1, as the flag's parser checks), all cores without it.
pub(super) fn thread_pool(threads: Option<usize>) -> Result<rayon::ThreadPool> {
    accel::tracing_pool(threads).with_context(|| match threads {
        Some(t) => format!("could not start {t} worker threads (-t)"),
        None => "could not start the worker threads".into(),
    })
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

/// `out.png` → `out_rate.png` (`out.exr` → `out_rate.exr`, raw counts): the adaptive
/// sample-rate map beside the image.
fn rate_path(out: &Path) -> PathBuf {
    let stem = out
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let ext = out
        .extension()
        .map_or("png".into(), |e| e.to_string_lossy());
    out.with_file_name(format!("{stem}_rate.{ext}"))
}

/// `ember export`: the scene in another renderer's format, for side-by-side measurements.
pub(super) fn export(a: ExportArgs) -> Result<()> {
    let (w, h) = (a.resolution[0], a.resolution[1]);
    check_resolution(w, h)?;
    let mut scene = load_scene(&a.scene)?;
    convert::apply_placement(&mut scene, &a.placement);
    apply_env_map(a.env_map.as_deref(), &mut scene)?;
    let camera = ember::camera::Camera::new(&scene.camera, &scene.bounds, w, h);
    std::fs::create_dir_all(&a.out)
        .map_err(|e| anyhow::anyhow!("{}: cannot create folder: {e}", a.out.display()))?;
    let stem = a
        .scene
        .file_stem()
        .map_or("scene".into(), |s| s.to_string_lossy().into_owned());
    if let Some(map) = &a.env_map {
        // The map is exported as `<stem>_env.exr` beside the scene file.
        let exported = a.out.join(format!("{stem}_env.exr"));
        if is_same_file(map, &exported) {
            bail!(
                "{}: the exported map {} would overwrite this -e input; choose another --out",
                map.display(),
                exported.display()
            );
        }
    }
    let ExportFormat::Mitsuba = a.format;
    let settings = ember::export::MitsubaSettings {
        sampler: a.sampler,
        ..ember::export::MitsubaSettings::for_ember(
            a.spp,
            a.max_depth,
            &ember::integrators::Roulette::default(),
        )
    };
    let summary = ember::export::write_mitsuba(&scene, &camera, &settings, &a.out, &stem)?;
    for w in &summary.warnings {
        ember::errln!("ember: warning: {w}");
    }
    ember::outln!("{}", summary.files[0].display())?;
    Ok(())
}
