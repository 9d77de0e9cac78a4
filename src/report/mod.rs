//! `ember report`: the CS184 pathtracer write-up, rendered and laid out as a page.
//!
//! The course's write-up has five parts (ray generation and intersection, the BVH,
//! direct illumination, global illumination, adaptive sampling); [`plan`] says which
//! figures each holds, [`run`] renders them through [`RenderJob`] like the CLI does,
//! times part 2's table, runs `ember bench converge` for a sixth section, and writes
//! `index.html` and `README.md` ([`page`]). Under every figure stands the `ember`
//! command that renders the same image bit for bit ([`recipe::Recipe::command`]).

mod converge;
pub mod page;
pub mod plan;
pub mod recipe;
mod timing;

use crate::film::Image;
use crate::image_io::PendingImage;
use crate::image_metadata::ImageMetadata;
use crate::render::{RenderJob, RenderOutput};
use crate::scene::{collada, Scene};
use anyhow::{bail, Context, Result};
use page::{Block, Figure, FigureRow, Page, Section};
use plan::{Budget, Make, Planned, Scenes, Shot};
use recipe::Recipe;
use std::path::{Path, PathBuf};
use std::time::Instant;

#[derive(Clone, Debug)]
pub struct ReportOptions {
    /// The folder the page and its images are written to (created if missing).
    pub out: PathBuf,
    pub quick: bool,
    /// The user's scenes for every part; empty: the course's.
    pub scenes: Vec<PathBuf>,
    pub seed: u64,
    /// A Python that imports Mitsuba 3, for section 6's peer curves.
    pub mitsuba: Option<PathBuf>,
}

/// Hears how the report advances; the CLI draws a progress bar. Called from the
/// render threads, hence `Sync`.
pub trait Progress: Sync {
    /// The total work, in the units [`Progress::advance`] counts.
    fn start(&self, total: u64);
    /// A new figure or table begins.
    fn step(&self, what: &str);
    fn advance(&self, units: u64);
    /// Something the user should read (a warning, a skipped peer).
    fn note(&self, line: &str);
    /// Whether to stop (Ctrl-C): asked between figures.
    fn should_stop(&self) -> bool {
        false
    }
}

/// What [`run`] wrote.
#[derive(Clone, Debug)]
pub struct Written {
    pub html: PathBuf,
    pub markdown: PathBuf,
    pub images: usize,
    pub seconds: f64,
}

#[derive(Debug, thiserror::Error)]
#[error("interrupted after {figures} figures (in {dir}); the page was not written")]
pub struct Interrupted {
    pub figures: usize,
    pub dir: String,
}

/// Where Mitsuba 3 is when the project's `scripts/mitsuba-env` installed it: in the
/// data folder's `.cache/mitsuba`.
pub fn installed_mitsuba() -> Option<PathBuf> {
    let python = crate::data::root().ok()?.join(".cache/mitsuba/bin/python");
    python.is_file().then_some(python)
}

/// Renders every figure, runs the timing table and the convergence charts, and
/// writes the page into `opts.out`.
pub fn run(opts: &ReportOptions, progress: &dyn Progress) -> Result<Written> {
    let t0 = Instant::now();
    let scenes = match opts.scenes.is_empty() {
        true => Scenes::course(opts.quick)?,
        false => {
            check_scene_names(&opts.scenes)?;
            // Each scene loads before anything is written, so a bad one leaves no folders.
            for path in &opts.scenes {
                crate::scene::collada::load(path)?;
            }
            Scenes::given(&opts.scenes)
        }
    };
    let budget = match opts.quick {
        true => Budget::quick(),
        false => Budget::full(),
    };
    let sections = plan::plan(&scenes, &budget, opts.seed);
    for dir in ["figures", "converge"] {
        let d = opts.out.join(dir);
        std::fs::create_dir_all(&d).with_context(|| format!("{}: cannot create", d.display()))?;
    }
    let mut maker = Maker::new(opts, &budget, progress);
    progress.start(maker.total_work(&sections));
    let mut page = Page {
        title: "CS184 Pathtracer write-up".into(),
        intro: intro(opts),
        sections: Vec::new(),
    };
    for s in &sections {
        let mut blocks = Vec::new();
        for item in &s.items {
            blocks.extend(maker.make(item)?);
        }
        page.sections.push(Section {
            id: s.id.into(),
            title: s.title.into(),
            blocks,
        });
    }
    let seconds = t0.elapsed().as_secs_f64();
    page.intro.push(format!(
        "This page took {:.0} s to make on this machine.",
        seconds
    ));
    let html = opts.out.join("index.html");
    let markdown = opts.out.join("README.md");
    write_atomically(&html, &page.to_html())?;
    write_atomically(&markdown, &page.to_markdown())?;
    Ok(Written {
        html,
        markdown,
        images: page.images().len(),
        seconds,
    })
}

/// Two of the user's scenes with the same file name would write the same figures.
fn check_scene_names(scenes: &[PathBuf]) -> Result<()> {
    for (i, a) in scenes.iter().enumerate() {
        if let Some(b) = scenes[..i].iter().find(|b| plan::stem(b) == plan::stem(a)) {
            bail!(
                "{} and {}: two scenes of the same name would write the same figures; rename one",
                b.display(),
                a.display()
            );
        }
    }
    Ok(())
}

fn intro(opts: &ReportOptions) -> Vec<String> {
    let threads = crate::names::thread_count(rayon::current_num_threads());
    vec![format!(
        "Made by `ember report{}` (ember {}, {}) on {} with {threads}, seed {}. \
             Under every figure is the `ember` command that renders the same pixels bit for bit, \
             into a PNG that records the same settings \
             (the same seed gives the same image whatever the thread count); run it from the \
             folder `ember report` ran in.",
        if opts.quick { " --quick" } else { "" },
        env!("CARGO_PKG_VERSION"),
        env!("EMBER_GIT_HASH"),
        crate::image_metadata::cpu_model(),
        opts.seed
    )]
}

/// Writes a page whole or not at all, so a reader never sees half of one.
fn write_atomically(path: &Path, text: &str) -> Result<()> {
    crate::image_io::write_atomically(path, text.as_bytes())
        .with_context(|| format!("{}: cannot write", path.display()))
}

/// Carries out the plan: renders (each recipe once), tables and charts.
struct Maker<'a> {
    opts: &'a ReportOptions,
    budget: &'a Budget,
    progress: &'a dyn Progress,
    /// The last job, reused while recipes share its scene, resolution and backend.
    job: Option<(JobKey, RenderJob)>,
    /// Renders done with their seconds, so a recipe used twice (part 4's difference)
    /// renders once.
    done: Vec<(Recipe, RenderOutput, f64)>,
    figures: usize,
}

#[derive(Clone, Debug, PartialEq)]
struct JobKey {
    scene: PathBuf,
    size: (u32, u32),
    accel: crate::accel::AccelKind,
}

impl<'a> Maker<'a> {
    fn new(opts: &'a ReportOptions, budget: &'a Budget, progress: &'a dyn Progress) -> Self {
        Maker {
            opts,
            budget,
            progress,
            job: None,
            done: Vec::new(),
            figures: 0,
        }
    }

    /// Work units of the whole plan: each distinct render's pixels times its work per
    /// pixel, and a share for each table and convergence run.
    fn total_work(&self, sections: &[plan::PlannedSection]) -> u64 {
        let mut recipes: Vec<&Recipe> = Vec::new();
        let mut other = 0;
        for item in sections.iter().flat_map(|s| &s.items) {
            match item {
                Planned::Figures { shots, .. } => {
                    for shot in shots {
                        match &shot.make {
                            Make::Render(r) => recipes.push(r),
                            Make::Difference { full, minus } => recipes.extend([full, minus]),
                        }
                    }
                }
                Planned::BvhTable { scenes } => other += timing::work(scenes, self.budget),
                Planned::Converge(_) => other += converge::work(self.budget),
                Planned::Text(_) => {}
            }
        }
        // A recipe renders once however many figures use it.
        let mut unique: Vec<&Recipe> = Vec::new();
        for r in recipes {
            if !unique.contains(&r) {
                unique.push(r);
            }
        }
        let renders: u64 = unique.iter().map(|r| work(r)).sum();
        renders + other
    }

    fn make(&mut self, item: &Planned) -> Result<Vec<Block>> {
        match item {
            Planned::Text(t) => Ok(vec![Block::Text(t.clone())]),
            Planned::Figures { caption, shots } => {
                let mut figures = Vec::new();
                for shot in shots {
                    if self.progress.should_stop() {
                        return Err(Interrupted {
                            figures: self.figures,
                            dir: self.opts.out.join("figures").display().to_string(),
                        }
                        .into());
                    }
                    self.progress.step(&format!("{caption}: {}", shot.label));
                    figures.extend(self.shot(shot)?);
                    self.figures += 1;
                }
                Ok(vec![Block::Figures(FigureRow {
                    caption: caption.clone(),
                    figures,
                })])
            }
            Planned::BvhTable { scenes } => {
                self.progress
                    .step("part 2: render times with and without the BVH");
                timing::blocks(scenes, self.budget, self.opts.seed, self.progress)
            }
            Planned::Converge(case) => {
                self.progress.step(&format!(
                    "bench converge {} -m {}",
                    plan::stem(&case.scene),
                    case.max_depth
                ));
                converge::blocks(case, self.opts, self.budget, self.progress)
            }
        }
    }

    /// Renders (or computes) one figure and writes its image(s).
    fn shot(&mut self, shot: &Shot) -> Result<Vec<Figure>> {
        let path = self.opts.out.join(&shot.file);
        match &shot.make {
            Make::Render(r) => {
                let command = self.command(r, &path);
                let i = self.render(r)?;
                self.ensure_job(r)?;
                let (_, output, seconds) = &self.done[i];
                let job = &self.job.as_ref().expect("ensured").1;
                // What the printed command writes: the same keys in the same order
                // (it renders in one pass, so no passes and `complete`).
                let mut meta = ImageMetadata::for_render(&r.scene, job, &r.settings(), *seconds);
                meta.push_samples(&output.samples, None, None);
                set_command_line(&mut meta, &command);
                write_png(&path, &r.scene, &output.image, &meta)?;
                let mut figures = vec![figure(shot, &output.image, vec![command.clone()])];
                if r.adaptive.is_some() {
                    figures.push(self.rate_map(shot, r, output, &meta, command)?);
                }
                Ok(figures)
            }
            Make::Difference { full, minus } => {
                let (a, b) = (self.render(full)?, self.render(minus)?);
                let diff = difference(&self.done[a].1.image, &self.done[b].1.image);
                let commands = vec![
                    self.command(full, "full.exr"),
                    self.command(minus, "minus.exr"),
                ];
                let mut meta = ImageMetadata::provenance();
                let how = format!("full.exr − minus.exr: {} ; {}", commands[0], commands[1]);
                meta.push("ember.computed", how);
                write_png(&path, &full.scene, &diff, &meta)?;
                let mut f = figure(shot, &diff, commands);
                f.note = "the first image minus the second, pixel by pixel (their linear EXR values), encoded as the PNG".into();
                Ok(vec![f])
            }
        }
    }

    /// The `<stem>_rate.png` the CLI writes beside an adaptive render, as a figure.
    fn rate_map(
        &self,
        shot: &Shot,
        r: &Recipe,
        output: &RenderOutput,
        meta: &ImageMetadata,
        command: String,
    ) -> Result<Figure> {
        let file = shot.file.replace(".png", "_rate.png");
        let (w, h) = (output.image.width, output.image.height);
        let rate = crate::film::sample_rate_map(w, h, &output.samples, r.spp);
        write_png(&self.opts.out.join(&file), &r.scene, &rate, meta)?;
        let mean = output.total_samples() as f64 / (w as f64 * h as f64);
        Ok(Figure {
            image: file,
            label: format!("{}: sample rate, mean {mean:.0} spp", shot.label),
            width: rate.width,
            height: rate.height,
            commands: vec![command],
            note: "written by the same command beside its image".into(),
        })
    }

    /// The index in `done` of `r`'s render, made once.
    fn render(&mut self, r: &Recipe) -> Result<usize> {
        if let Some(i) = self.done.iter().position(|(d, _, _)| d == r) {
            return Ok(i);
        }
        self.ensure_job(r)?;
        let job = &self.job.as_ref().expect("ensured").1;
        let settings = r.settings();
        for w in job.warnings(&settings) {
            self.progress.note(&format!("{}: {w}", r.scene.display()));
        }
        let per_pixel = r.work_per_pixel();
        let progress = self.progress;
        let t0 = Instant::now();
        let output = job.render_rect(&settings, job.full_frame(), &|n| {
            progress.advance(n * per_pixel)
        });
        self.done
            .push((r.clone(), output, t0.elapsed().as_secs_f64()));
        Ok(self.done.len() - 1)
    }

    /// Makes the current job `r`'s scene at its resolution and backend.
    fn ensure_job(&mut self, r: &Recipe) -> Result<()> {
        let key = JobKey {
            scene: r.scene.clone(),
            size: (r.width, r.height),
            accel: r.accel_kind(),
        };
        if self.job.as_ref().map(|(k, _)| k) != Some(&key) {
            self.job = None; // free the last scene before loading the next
            let scene = load(&r.scene, self.progress)?;
            let job = RenderJob::new(scene, key.accel, r.width, r.height)?;
            self.job = Some((key, job));
        }
        Ok(())
    }

    /// `r`'s command line writing `out`, with paths as the user's shell sees them.
    fn command(&self, r: &Recipe, out: impl AsRef<Path>) -> String {
        r.command(&shell_path(&r.scene), &shell_path(out.as_ref()))
    }
}

/// Work units of one render (see [`Maker::total_work`]).
fn work(r: &Recipe) -> u64 {
    r.width as u64 * r.height as u64 * r.work_per_pixel()
}

/// A path as a command run from the current directory names it: relative when it
/// lies below the current directory, else as it is.
fn shell_path(p: &Path) -> String {
    let relative = std::env::current_dir()
        .ok()
        .and_then(|cwd| p.strip_prefix(&cwd).ok().map(Path::to_path_buf));
    let p = relative.unwrap_or_else(|| p.to_path_buf());
    p.to_string_lossy().replace('\\', "/")
}

fn load(path: &Path, progress: &dyn Progress) -> Result<Scene> {
    let scene = collada::load(path)?;
    // Each warning names the file already (the loader's messages start with it).
    for w in &scene.warnings {
        progress.note(&format!("warning: {w}"));
    }
    Ok(scene)
}

/// The image's `ember.command_line`: the command that renders it, not `ember report`,
/// so that the figure's metadata has the keys the command's image has.
fn set_command_line(meta: &mut ImageMetadata, command: &str) {
    for (k, v) in &mut meta.entries {
        if k == "ember.command_line" {
            *v = command.to_string();
        }
    }
}

fn write_png(path: &Path, scene: &Path, image: &Image, meta: &ImageMetadata) -> Result<()> {
    PendingImage::claim(path, &[scene])?.write_with_metadata(image, meta)?;
    Ok(())
}

fn figure(shot: &Shot, image: &Image, commands: Vec<String>) -> Figure {
    Figure {
        image: shot.file.clone(),
        label: shot.label.clone(),
        width: image.width,
        height: image.height,
        commands,
        note: String::new(),
    }
}

/// `a − b`, pixel by pixel.
fn difference(a: &Image, b: &Image) -> Image {
    Image {
        pixels: a
            .pixels
            .iter()
            .zip(&b.pixels)
            .map(|(x, y)| *x - *y)
            .collect(),
        ..a.clone()
    }
}
