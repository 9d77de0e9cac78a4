//! `ember bench converge`: error against time for each method, so speed and
//! accuracy can be charted against each other, ember's methods and its peers'
//! (Mitsuba 3 with each of its samplers, Blender Cycles) on one chart against
//! one reference.
//!
//! Each point is a fresh render (its own seed) at a doubled sample count, timed
//! render-only with all threads; with `seeds` above 1 it is that many renders, their
//! MSEs averaged and their times' median taken, so that one lucky seed cannot move
//! a comparison. The methods take turns render by render (`interleave`), so a
//! change in the machine's speed during the run falls on all of them alike. Errors
//! are measured against a reference: a given EXR (e.g. the Mitsuba references, whose
//! noise is negligible at their spp and is subtracted anyway when known) or ember's
//! own high-spp render, rendered as two halves so that its own noise variance can be
//! subtracted from every MSE.
//! Methods are compared by reading each curve as measured (log-log interpolation
//! at common render times and sample counts), never by assuming MSE ∝ 1/time.

use super::chart::{write_chart_legend_outside, ChartSpec, Series};
use super::cycles::CyclesRunner;
use super::mitsuba::{MitsubaRunner, PeerRender};
use super::table::Table;
use super::{create_out_dir, write_text, Report};
use crate::accel::{AccelKind, BvhBuilder, EmbreeQuality};
use crate::camera::Camera;
use crate::export::{MitsubaRoulette, MitsubaSampler};
use crate::film::Image;
use crate::image_io::{read_image, write_image};
use crate::integrators::{DirectStrategy, Estimator, Roulette};
use crate::render::{average, Adaptive, RenderJob, RenderSettings};
use crate::scene::{collada, Scene};
use anyhow::{bail, Context, Result};
use std::path::{Path, PathBuf};
use std::rc::Rc;
use std::time::Instant;

#[derive(Clone, Debug)]
pub struct ConvergeOptions {
    pub scene: PathBuf,
    /// Linear EXR to measure against; None renders (and caches) ember's own.
    pub reference: Option<PathBuf>,
    /// Per-pixel RMS noise of `reference`, if known (e.g. from the references' manifest).
    pub reference_noise: Option<f64>,
    pub width: u32,
    pub height: u32,
    pub max_depth: u32,
    /// Largest spp of ember's doubling sequence (peers go one count further).
    pub max_spp: u32,
    /// A method stops doubling once one render takes longer than this.
    pub max_seconds_per_point: f64,
    /// spp of ember's own reference (split into two halves).
    pub reference_spp: u32,
    pub out_dir: PathBuf,
    pub seed: u64,
    /// Renders per point (each with its own seed): the point's MSE is their mean, its
    /// time their median.
    pub seeds: u32,
    /// Add the Embree backend as a method when this build has it.
    pub compare_backends: bool,
    /// Mitsuba 3 as peer methods, one curve per variant and sampler.
    pub mitsuba: Option<MitsubaPeer>,
    /// Blender Cycles as a peer method, through this Python (one that imports `bpy`).
    pub cycles: Option<PathBuf>,
}

/// Where Mitsuba 3 is and which of its variants and samplers to run.
#[derive(Clone, Debug)]
pub struct MitsubaPeer {
    /// A Python interpreter that imports `mitsuba` (`scripts/mitsuba-env` prints one).
    pub python: PathBuf,
    pub variants: Vec<String>,
    pub samplers: Vec<MitsubaSampler>,
    /// Each sampler runs once per roulette start.
    pub roulettes: Vec<MitsubaRoulette>,
}

/// One way of rendering the image.
#[derive(Clone, Debug)]
pub struct Method {
    pub name: String,
    pub settings: RenderSettings,
    pub accel: AccelKind,
}

#[derive(Clone, Debug)]
pub struct Point {
    pub method: String,
    /// Rendered by a peer (Mitsuba, Cycles), not by ember.
    pub peer: bool,
    pub spp: u32,
    pub samples: u64,
    pub seconds: f64,
    pub rmse: f64,
    pub rel_mse: f64,
}

pub struct ConvergeReport {
    /// The scene's file stem, which names the report's files.
    pub scene: String,
    pub max_depth: u32,
    pub width: u32,
    pub height: u32,
    pub points: Vec<Point>,
    pub reference_note: String,
    /// What the peers said about their own images (Cycles' mean check at its highest spp).
    pub peer_notes: Vec<String>,
    /// Renders per point.
    pub seeds: u32,
}

/// What a method changes in the default settings.
type Tweak = fn(&mut RenderSettings);

/// ember's methods at `-m 1`: the direct-lighting estimators.
const DIRECT_METHODS: &[(&str, Tweak)] = &[
    ("hemisphere", |s| {
        s.strategy = Some(DirectStrategy::Hemisphere)
    }),
    ("light sampling", |s| {
        s.strategy = Some(DirectStrategy::Light)
    }),
    ("MIS", |s| s.strategy = Some(DirectStrategy::Mis)),
];

/// `--integrator auto`: the estimator and direct-lighting strategy the scene calls
/// for (`RenderSettings::default()` fixes path tracing with light sampling).
fn auto(s: &mut RenderSettings) {
    s.estimator = None;
    s.strategy = None;
}

/// The name of ember's default settings, the first method.
pub const DEFAULT_METHOD: &str = "ember default (auto)";

/// ember's default without split samples of light of few bounces.
pub const NO_DIRECT_SPLIT: &str = "auto, --direct-split 0";

/// ember's methods beyond `-m 1`. A variant (another sampler, say) is one more row.
const PATH_METHODS: &[(&str, Tweak)] = &[
    ("light sampling, RR", |s| {
        s.strategy = Some(DirectStrategy::Light)
    }),
    ("MIS, RR", |s| s.strategy = Some(DirectStrategy::Mis)),
    ("MIS, no RR", |s| {
        s.strategy = Some(DirectStrategy::Mis);
        s.roulette = Roulette::Off;
    }),
    ("MIS, RR, -l 4", |s| {
        s.strategy = Some(DirectStrategy::Mis);
        s.light_samples = 4;
    }),
    ("MIS, RR, -l 16", |s| {
        s.strategy = Some(DirectStrategy::Mis);
        s.light_samples = 16;
    }),
];

/// The methods compared for depth `m`: ember's default, the rows of [`DIRECT_METHODS`]
/// or [`PATH_METHODS`] (path tracing unless a row says otherwise), light tracing where
/// it can converge, adaptive sampling and (optionally) Embree, the last two with
/// `--integrator auto` otherwise.
pub fn methods(base: &RenderSettings, scene: &Scene, compare_backends: bool) -> Vec<Method> {
    let native = AccelKind::Native(BvhBuilder::Sah);
    let with = |name: &str, tweak: Tweak, accel: AccelKind| {
        let mut settings = base.clone();
        tweak(&mut settings);
        Method {
            name: name.to_string(),
            settings,
            accel,
        }
    };
    let table = if base.max_depth <= 1 {
        DIRECT_METHODS
    } else {
        PATH_METHODS
    };
    // First ember's default, whatever `--integrator auto` picks for the scene: the
    // method the tables divide by each peer's figure.
    let mut v = vec![with(DEFAULT_METHOD, auto, native)];
    // What the split samples of light of few bounces (`--direct-split`) are worth.
    let without_split: Tweak = |s| {
        auto(s);
        s.direct_split = 0;
    };
    v.push(with(NO_DIRECT_SPLIT, without_split, native));
    v.extend(table.iter().map(|&(name, tweak)| with(name, tweak, native)));
    // Light tracing cannot show specular surfaces to the camera: only where it can
    // converge. (Where a light shines on them, the default light-traces their
    // caustics, and the rows above are path tracing alone.)
    if !scene.materials.iter().any(|mat| mat.is_delta()) {
        let light_tracing: Tweak = |s| s.estimator = Some(Estimator::LightTracing);
        v.push(with("light tracing", light_tracing, native));
    }
    let adaptive: Tweak = |s| {
        auto(s);
        s.adaptive = Some(Adaptive::new(16, 0.05));
    };
    v.push(with("adaptive (-a 16 0.05)", adaptive, native));
    if compare_backends && cfg!(any(feature = "embree", feature = "embree4")) {
        let embree = AccelKind::embree(EmbreeQuality::Medium);
        v.push(with("Embree backend", auto, embree));
    }
    v
}

struct Reference {
    image: Image,
    /// Per-pixel-channel noise variance of the reference, subtracted from every MSE.
    noise_var: f64,
    note: String,
}

pub fn run(opts: &ConvergeOptions, log: &mut dyn FnMut(&str)) -> Result<ConvergeReport> {
    check_peer_seeds(opts)?;
    let scene = collada::load(&opts.scene)?;
    let base = RenderSettings {
        max_depth: opts.max_depth,
        seed: opts.seed,
        ..Default::default()
    };
    let reference = reference(opts, &scene, &base, log)?;
    let camera = Camera::new(&scene.camera, &scene.bounds, opts.width, opts.height);
    let mut peer_notes = Vec::new();
    let cycles = cycles_peer(opts, &scene, &camera, log, &mut peer_notes)?;
    let mitsuba = mitsuba_runners(opts)?;
    let mut curves = ember_curves(&scene, methods(&base, &scene, opts.compare_backends), opts)?;
    for runner in &mitsuba {
        let render = |spp, seed, _: &mut dyn FnMut(&str)| {
            runner.render(&scene, &camera, opts.max_depth, spp, seed)
        };
        let counts = runner.sample_counts(opts.max_spp);
        curves.push(Curve::peer(runner.name(), counts, render, opts));
    }
    if let Some(runner) = &cycles {
        let render = |spp, seed, log: &mut dyn FnMut(&str)| {
            runner.render(&scene, &camera, opts.max_depth, spp, seed, log)
        };
        let counts = runner.sample_counts(opts.max_spp);
        let mut curve = Curve::peer(runner.name(), counts, render, opts);
        // Cycles' check of its own mean: the summary keeps the highest spp's.
        curve.notes = true;
        curves.push(curve);
    }
    interleave(&mut curves, opts, &reference, log, &mut peer_notes)?;
    Ok(ConvergeReport {
        scene: scene_stem(&opts.scene),
        max_depth: opts.max_depth,
        width: opts.width,
        height: opts.height,
        points: curves.into_iter().flat_map(|c| c.points).collect(),
        reference_note: reference.note,
        peer_notes,
        seeds: opts.seeds.max(1),
    })
}

/// Cycles, when asked for and able to translate the scene exactly; otherwise a note
/// says why it is left out. Checked before the long run.
fn cycles_peer(
    opts: &ConvergeOptions,
    scene: &Scene,
    camera: &Camera,
    log: &mut dyn FnMut(&str),
    notes: &mut Vec<String>,
) -> Result<Option<CyclesRunner>> {
    let Some(python) = &opts.cycles else {
        return Ok(None);
    };
    let dir = opts.out_dir.join("cycles");
    let runner = CyclesRunner::new(python, &dir, opts.reference.as_deref())?;
    Ok(match runner.check(scene, camera, opts.max_depth) {
        Ok(()) => Some(runner),
        Err(e) => {
            let note = format!("Blender Cycles left out: {e}");
            log(&note);
            notes.push(note);
            None
        }
    })
}

/// Mitsuba's runners, one per variant, sampler and roulette start (a start equal to
/// ember's runs once).
fn mitsuba_runners(opts: &ConvergeOptions) -> Result<Vec<MitsubaRunner>> {
    let Some(peer) = &opts.mitsuba else {
        return Ok(Vec::new());
    };
    let dir = opts.out_dir.join("mitsuba");
    let mut v = Vec::new();
    for variant in &peer.variants {
        for &sampler in &peer.samplers {
            for &roulette in &peer.roulettes {
                if !roulette.repeats_ember(&peer.roulettes) {
                    v.push(MitsubaRunner::new(
                        &peer.python,
                        variant,
                        sampler,
                        roulette,
                        &dir,
                    )?);
                }
            }
        }
    }
    Ok(v)
}

/// One render of a curve's point.
struct Rendered {
    seconds: f64,
    spp: u32,
    samples: u64,
    image: Image,
}

/// Renders one image of a curve: `render(spp, seed, log)`.
type RenderFn<'a> = Box<dyn Fn(u32, u64, &mut dyn FnMut(&str)) -> Result<Rendered> + 'a>;

/// One method's curve: the sample counts it has still to render, and its points.
struct Curve<'a> {
    name: String,
    /// Rendered by a peer (Mitsuba, Cycles), not by ember.
    peer: bool,
    /// Ascending; a count leaves when its point is measured.
    pending: Vec<u32>,
    render: RenderFn<'a>,
    /// What its renders log are the report's peer notes (the last one kept).
    notes: bool,
    points: Vec<Point>,
}

impl<'a> Curve<'a> {
    fn peer(
        name: String,
        counts: Vec<u32>,
        render: impl Fn(u32, u64, &mut dyn FnMut(&str)) -> Result<PeerRender> + 'a,
        opts: &ConvergeOptions,
    ) -> Curve<'a> {
        let pixels = u64::from(opts.width) * u64::from(opts.height);
        Curve {
            name,
            peer: true,
            pending: counts,
            render: Box::new(move |spp, seed, log| {
                let m = render(spp, seed, log)?;
                Ok(Rendered {
                    seconds: m.seconds,
                    spp: m.spp,
                    samples: u64::from(m.spp) * pixels,
                    image: m.image,
                })
            }),
            notes: false,
            points: Vec::new(),
        }
    }
}

/// ember's methods as curves. One job per accelerator is shared by the methods that
/// use it: a large scene is held once, not once per method.
fn ember_curves<'a>(
    scene: &Scene,
    methods: Vec<Method>,
    opts: &ConvergeOptions,
) -> Result<Vec<Curve<'a>>> {
    let mut jobs: Vec<(AccelKind, Rc<RenderJob>)> = Vec::new();
    let mut curves = Vec::new();
    for method in methods {
        let job = match jobs.iter().find(|(kind, _)| *kind == method.accel) {
            Some((_, job)) => Rc::clone(job),
            None => {
                let job = RenderJob::new(scene.clone(), method.accel, opts.width, opts.height)?;
                let job = Rc::new(job);
                jobs.push((method.accel, Rc::clone(&job)));
                job
            }
        };
        curves.push(ember_curve(job, method, opts));
    }
    Ok(curves)
}

/// ember's `method` at 1, 2, 4, … up to `--max-spp`, timed render-only.
fn ember_curve<'a>(job: Rc<RenderJob>, method: Method, opts: &ConvergeOptions) -> Curve<'a> {
    let counts = super::doubling(1, opts.max_spp).collect();
    let settings = method.settings;
    Curve {
        name: method.name,
        peer: false,
        pending: counts,
        render: Box::new(move |spp, seed, _| {
            let s = RenderSettings {
                spp,
                seed,
                ..settings.clone()
            };
            let t = Instant::now();
            let o = job.render(&s);
            Ok(Rendered {
                seconds: t.elapsed().as_secs_f64(),
                spp,
                samples: o.total_samples(),
                image: o.image,
            })
        }),
        notes: false,
        points: Vec::new(),
    }
}

/// Renders every curve's points with the methods interleaved, as `farm-bench` times
/// two commands: in the round of `n` spp, seed by seed, each curve renders its counts
/// up to `n`, so a drift in the machine's speed falls on every method alike rather
/// than on the one that happened to run then. A curve stops once a point's median
/// time exceeds `--max-seconds`.
fn interleave(
    curves: &mut [Curve],
    opts: &ConvergeOptions,
    r: &Reference,
    log: &mut dyn FnMut(&str),
    peer_notes: &mut Vec<String>,
) -> Result<()> {
    let mut round = 1u32;
    while curves.iter().any(|c| !c.pending.is_empty()) {
        let due: Vec<usize> = curves
            .iter()
            .map(|c| c.pending.iter().take_while(|&&n| n <= round).count())
            .collect();
        let methods = due.iter().filter(|&&n| n > 0).count();
        if methods > 0 {
            log(&format!("round of {round} spp: {methods} methods"));
        }
        let runs = render_round(curves, &due, opts, r, log, peer_notes)?;
        for ((curve, due), runs) in curves.iter_mut().zip(due).zip(runs) {
            curve.pending.drain(..due);
            for runs in runs {
                let point = runs.point(curve);
                let over = point.seconds > opts.max_seconds_per_point;
                curve.points.push(point);
                if over {
                    curve.pending.clear();
                }
            }
        }
        round = match round.checked_mul(2) {
            Some(n) => n,
            None => break,
        };
    }
    Ok(())
}

/// One round's renders, seed by seed and curve by curve: curve `i` renders the first
/// `due[i]` of its pending counts. The runs of each curve's points, in that order.
fn render_round(
    curves: &[Curve],
    due: &[usize],
    opts: &ConvergeOptions,
    r: &Reference,
    log: &mut dyn FnMut(&str),
    peer_notes: &mut Vec<String>,
) -> Result<Vec<Vec<PointRuns>>> {
    let mut runs: Vec<Vec<PointRuns>> = due
        .iter()
        .map(|&n| (0..n).map(|_| PointRuns::default()).collect())
        .collect();
    for k in 0..opts.seeds.max(1) {
        for ((curve, &n), runs) in curves.iter().zip(due).zip(&mut runs) {
            for (&spp, run) in curve.pending[..n].iter().zip(runs.iter_mut()) {
                let mut messages = Vec::new();
                let m = (curve.render)(spp, point_seed(opts, spp, k), &mut |line| {
                    messages.push(line.to_string())
                })
                .with_context(|| format!("{}: {spp} spp", curve.name))?;
                for line in &messages {
                    log(line);
                }
                if let Some(last) = messages.last().filter(|_| curve.notes) {
                    *peer_notes = vec![last.clone()];
                }
                run.runs.add(m.seconds, errors(&m.image, r));
                (run.spp, run.samples) = (m.spp, m.samples);
            }
        }
    }
    Ok(runs)
}

/// A point's renders so far, and the counts its renderer reports for them.
#[derive(Default)]
struct PointRuns {
    runs: Runs,
    spp: u32,
    samples: u64,
}

impl PointRuns {
    /// The point of `curve`, at the count its renderer reports.
    fn point(self, curve: &Curve) -> Point {
        let (seconds, rmse, rel_mse) = self.runs.point();
        Point {
            method: curve.name.clone(),
            peer: curve.peer,
            spp: self.spp,
            samples: self.samples,
            seconds,
            rmse,
            rel_mse,
        }
    }
}

/// The seed of render `k` of the point at `spp`: render 0 keeps the seed a point
/// had before there were several.
fn point_seed(opts: &ConvergeOptions, spp: u32, k: u32) -> u64 {
    opts.seed.wrapping_add(seed_offset(spp, k))
}

/// How far past `--seed` render `k` of the point at `spp` takes its seed. Small
/// numbers: Mitsuba takes 32-bit seeds.
fn seed_offset(spp: u32, k: u32) -> u64 {
    1000 + u64::from(spp) + (u64::from(k) << 16)
}

/// Mitsuba takes 32-bit seeds: refused before the long run if the largest point seed
/// would not fit.
fn check_peer_seeds(opts: &ConvergeOptions) -> Result<()> {
    // Peers go one count past --max-spp, at most 4× it (`MitsubaRunner::sample_counts`).
    let largest = opts.max_spp.saturating_mul(4);
    let most = u64::from(u32::MAX) - seed_offset(largest, opts.seeds.max(1) - 1);
    if opts.mitsuba.is_some() && opts.seed > most {
        bail!(
            "--seed {}: Mitsuba takes 32-bit seeds; with these --max-spp and --seeds, --seed must be at most {most}",
            opts.seed
        );
    }
    Ok(())
}

/// The renders of one point: their times and errors (MSE and relMSE, the
/// reference's noise removed, not yet clamped).
#[derive(Default)]
struct Runs {
    seconds: Vec<f64>,
    mse: f64,
    rel_mse: f64,
}

impl Runs {
    fn add(&mut self, seconds: f64, (mse, rel_mse): (f64, f64)) {
        self.seconds.push(seconds);
        self.mse += mse;
        self.rel_mse += rel_mse;
    }

    /// Median time, RMSE from the mean MSE, mean relMSE (errors never below 0).
    fn point(mut self) -> (f64, f64, f64) {
        let n = self.seconds.len() as f64;
        let seconds = super::median(&mut self.seconds);
        let rmse = (self.mse / n).max(0.0).sqrt();
        (seconds, rmse, (self.rel_mse / n).max(0.0))
    }
}

/// MSE and relMSE with the reference's own noise variance removed (may fall below 0
/// for one render; [`Runs::point`] clamps their mean).
fn errors(img: &Image, r: &Reference) -> (f64, f64) {
    let mse = img.rmse(&r.image).powi(2) - r.noise_var;
    let n = (3 * img.pixels.len()) as f64;
    let mut rel = 0.0;
    for (a, b) in img.pixels.iter().zip(&r.image.pixels) {
        for c in 0..3 {
            let (a, b) = (a[c] as f64, b[c] as f64);
            rel += ((a - b).powi(2) - r.noise_var) / (b * b + 0.01);
        }
    }
    (mse, rel / n)
}

fn reference(
    opts: &ConvergeOptions,
    scene: &Scene,
    base: &RenderSettings,
    log: &mut dyn FnMut(&str),
) -> Result<Reference> {
    if let Some(p) = &opts.reference {
        let image = read_image(p)?;
        if (image.width, image.height) != (opts.width, opts.height) {
            bail!(
                "{}: reference is {}x{}, but the renders are {}x{} (use -r)",
                p.display(),
                image.width,
                image.height,
                opts.width,
                opts.height
            );
        }
        let noise_var = opts.reference_noise.map_or(0.0, |n| n * n);
        let note = format!(
            "reference {} (its per-pixel noise {} is subtracted from every MSE)",
            p.display(),
            opts.reference_noise
                .map_or("unknown, taken as negligible,".to_string(), |n| format!(
                    "{n:.2e}"
                ))
        );
        return Ok(Reference {
            image,
            noise_var,
            note,
        });
    }
    own_reference(opts, scene, base, log)
}

/// Seed of ember's own reference.
const REFERENCE_SEED: u64 = 0x607FF7;

fn own_reference(
    opts: &ConvergeOptions,
    scene: &Scene,
    base: &RenderSettings,
    log: &mut dyn FnMut(&str),
) -> Result<Reference> {
    let stem = scene_stem(&opts.scene);
    let cache = opts.out_dir.join("cache");
    std::fs::create_dir_all(&cache)
        .with_context(|| format!("{}: cannot create", cache.display()))?;
    let name = |half: &str| {
        cache.join(format!(
            "{stem}_m{}_{}x{}_{}spp_{half}.exr",
            opts.max_depth, opts.width, opts.height, opts.reference_spp
        ))
    };
    let (pa, pb) = (name("a"), name("b"));
    let (a, b) = if pa.exists() && pb.exists() {
        log(&format!("reference: cached {}", pa.display()));
        (read_image(&pa)?, read_image(&pb)?)
    } else {
        log(&format!(
            "reference: rendering {} spp (two halves) with MIS, no roulette",
            opts.reference_spp
        ));
        let job = RenderJob::new(
            scene.clone(),
            AccelKind::Native(BvhBuilder::Sah),
            opts.width,
            opts.height,
        )?;
        let h = job.halves(&RenderSettings {
            spp: opts.reference_spp,
            // MIS whatever the depth: light sampling alone (which this chose at `-m 1`)
            // leaves a glossy scene's highlights noisy even at 8192 spp.
            strategy: Some(DirectStrategy::Mis),
            roulette: Roulette::Off,
            // The halves' seeds 2·seed + 1 and 2·seed + 2 are 0xC0FFEE + 1 and + 2.
            seed: REFERENCE_SEED,
            ..base.clone()
        });
        write_image(&h.a.image, &pa)?;
        write_image(&h.b.image, &pb)?;
        (h.a.image, h.b.image)
    };
    let noise_var = a.rmse(&b).powi(2) / 4.0;
    let image = average(&a, &b);
    let note = format!(
        "ember's own reference, {} spp in two halves; its per-pixel noise {:.2e} (from the halves) is subtracted from every MSE",
        opts.reference_spp,
        noise_var.sqrt()
    );
    Ok(Reference {
        image,
        noise_var,
        note,
    })
}

/// `method`'s RMSE at `x` on its curve, interpolated log-log between the two
/// points that bracket it (`None` outside its points' range); `x` is in render
/// seconds, or in spp when `by_spp`. Curves are read as measured: nothing assumes
/// MSE ∝ 1/time, which stratified samplers beat.
pub fn rmse_at(points: &[Point], method: &str, x: f64, by_spp: bool) -> Option<f64> {
    let mut pts: Vec<(f64, f64)> = points
        .iter()
        .filter(|p| p.method == method && p.seconds > 0.0 && p.rmse > 0.0)
        .map(|p| (if by_spp { f64::from(p.spp) } else { p.seconds }, p.rmse))
        .collect();
    pts.sort_by(|a, b| a.0.total_cmp(&b.0));
    if let Some(p) = pts.iter().find(|p| p.0 == x) {
        return Some(p.1);
    }
    let (a, b) = pts
        .windows(2)
        .map(|w| (w[0], w[1]))
        .find(|(a, b)| a.0 <= x && x <= b.0)?;
    let f = (x / a.0).ln() / (b.0 / a.0).ln();
    Some((a.1.ln() + f * (b.1 / a.1).ln()).exp())
}

/// The sample counts of ember's default the tables compare at (issue 24's bar).
const TABLE_SPP: [u32; 3] = [16, 64, 256];

/// `path`'s file name without its extension ("" when it has none).
fn scene_stem(path: &Path) -> String {
    path.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default()
}

impl ConvergeReport {
    pub fn to_csv(&self) -> String {
        let mut t = Table::new([
            "scene", "method", "peer", "spp", "samples", "seconds", "rmse", "relmse",
        ]);
        for p in &self.points {
            t.push(vec![
                self.scene.clone(),
                p.method.clone(),
                p.peer.to_string(),
                p.spp.to_string(),
                p.samples.to_string(),
                format!("{:.6}", p.seconds),
                format!("{:.6e}", p.rmse),
                format!("{:.6e}", p.rel_mse),
            ]);
        }
        t.to_csv()
    }

    /// Method names in the order they ran; ember's default first.
    fn names(&self) -> Vec<&str> {
        let mut names: Vec<&str> = Vec::new();
        for p in &self.points {
            if !names.contains(&p.method.as_str()) {
                names.push(&p.method);
            }
        }
        names
    }

    fn peers(&self) -> Vec<&str> {
        let names = self.names();
        names
            .into_iter()
            .filter(|n| self.points.iter().any(|p| p.peer && p.method == *n))
            .collect()
    }

    /// ember's default (the first method, [`DEFAULT_METHOD`]) at [`TABLE_SPP`]:
    /// (spp, its render seconds).
    fn default_points(&self) -> Vec<(u32, f64)> {
        let Some(first) = self.points.first() else {
            return Vec::new();
        };
        TABLE_SPP
            .iter()
            .filter_map(|&n| {
                self.points
                    .iter()
                    .find(|p| p.method == first.method && p.spp == n)
                    .map(|p| (n, p.seconds))
            })
            .collect()
    }

    /// One row per method of its RMSE at each `x` (seconds, or spp with `by_spp`),
    /// then ember's default divided by each peer's and by the best peer's there.
    fn comparison(&self, header: Vec<String>, xs: &[f64], by_spp: bool) -> String {
        let names = self.names();
        let mut table = Table::new(header);
        let cell =
            |v: Option<f64>, digits: usize| v.map_or("–".into(), |v| format!("{v:.digits$}"));
        let at = |name: &str, x: f64| rmse_at(&self.points, name, x, by_spp);
        for name in &names {
            let mut row = vec![name.to_string()];
            row.extend(xs.iter().map(|&x| cell(at(name, x), 5)));
            table.push(row);
        }
        let peers = self.peers();
        let ratio = |x: f64, peer: Option<f64>| at(names[0], x).zip(peer).map(|(a, b)| a / b);
        for peer in &peers {
            let mut row = vec![format!("{} ÷ {peer}", names[0])];
            row.extend(xs.iter().map(|&x| cell(ratio(x, at(peer, x)), 2)));
            table.push(row);
        }
        if peers.len() > 1 {
            let mut row = vec![format!("{} ÷ the best peer there", names[0])];
            row.extend(xs.iter().map(|&x| {
                let best = peers.iter().filter_map(|p| at(p, x)).reduce(f64::min);
                cell(ratio(x, best), 2)
            }));
            table.push(row);
        }
        table.to_markdown()
    }

    /// Each method's RMSE at the render times of ember's default at 16, 64 and 256
    /// spp, interpolated log-log on its own curve ("–" outside the range it
    /// measured), and ember's default as a fraction of each peer's.
    pub fn equal_time_table(&self) -> String {
        let at = self.default_points();
        if at.is_empty() {
            return String::new();
        }
        let mut header = vec!["method (RMSE at equal render time)".to_string()];
        header.extend(
            at.iter()
                .map(|(n, t)| format!("{t:.3} s (ember's {n} spp)")),
        );
        let xs: Vec<f64> = at.iter().map(|&(_, t)| t).collect();
        self.comparison(header, &xs, false)
    }

    /// Each method's RMSE at 16, 64 and 256 spp (peers whose sampler takes other
    /// counts interpolated log-log in spp), and ember's default as a fraction of each peer's.
    pub fn equal_spp_table(&self) -> String {
        let at = self.default_points();
        if at.is_empty() {
            return String::new();
        }
        let mut header = vec!["method (RMSE at equal spp)".to_string()];
        header.extend(at.iter().map(|(n, _)| format!("{n} spp")));
        let xs: Vec<f64> = at.iter().map(|&(n, _)| f64::from(n)).collect();
        self.comparison(header, &xs, true)
    }

    fn series(&self, y: impl Fn(&Point) -> f64) -> Vec<Series> {
        let mut out: Vec<Series> = Vec::new();
        for p in &self.points {
            match out.iter_mut().find(|s| s.name == p.method) {
                Some(s) => s.points.push((p.seconds, y(p))),
                None => out.push(Series {
                    name: p.method.clone(),
                    points: vec![(p.seconds, y(p))],
                }),
            }
        }
        out
    }
}

impl Report for ConvergeReport {
    /// `<scene>_m<M>.csv`, and error-vs-time charts `<scene>_m<M>_rmse.{png,svg}` and
    /// `<scene>_m<M>_relmse.{png,svg}`, every method's curve on one chart.
    fn write(&self, out_dir: &Path) -> Result<Vec<PathBuf>> {
        create_out_dir(out_dir)?;
        let stem = format!("{}_m{}", self.scene, self.max_depth);
        let csv = out_dir.join(format!("{stem}.csv"));
        write_text(&csv, &self.to_csv())?;
        let title = format!(
            "{}, -m {}, {}x{}: error vs time",
            self.scene, self.max_depth, self.width, self.height
        );
        let (rmse, relmse) = (
            out_dir.join(format!("{stem}_rmse")),
            out_dir.join(format!("{stem}_relmse")),
        );
        let spec = ChartSpec {
            title: &title,
            x_label: "render time (s, all threads)",
            y_label: "RMSE vs reference",
            log_x: true,
            log_y: true,
        };
        write_chart_legend_outside(&rmse, &spec, &self.series(|p| p.rmse))?;
        let spec = ChartSpec {
            y_label: "relMSE vs reference",
            ..spec
        };
        write_chart_legend_outside(&relmse, &spec, &self.series(|p| p.rel_mse))?;
        let mut files = vec![csv];
        for chart in [rmse, relmse] {
            files.extend(["png", "svg"].map(|ext| chart.with_extension(ext)));
        }
        Ok(files)
    }

    /// Where the reference came from, what the peers said of their own images, and
    /// the RMSEs at equal render time and at equal spp.
    fn summary(&self) -> String {
        let mut s = self.reference_note.clone();
        if self.seeds > 1 {
            s += &format!(
                "\neach point: {} renders with their own seeds, RMSE from their mean MSE, their median time",
                self.seeds
            );
        }
        for note in &self.peer_notes {
            s += &format!("\n{note}");
        }
        format!(
            "{s}\n\n{}\n{}",
            self.equal_time_table(),
            self.equal_spp_table()
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A curve whose renders take `seconds` each and write down what they rendered.
    fn fake<'a>(
        name: &str,
        counts: Vec<u32>,
        seconds: f64,
        order: &'a std::cell::RefCell<Vec<String>>,
    ) -> Curve<'a> {
        let tag = name.to_string();
        Curve {
            name: name.to_string(),
            peer: false,
            pending: counts,
            render: Box::new(move |spp, seed, _| {
                order.borrow_mut().push(format!("{tag}{spp}/{seed}"));
                Ok(Rendered {
                    seconds,
                    spp,
                    samples: u64::from(spp),
                    image: Image::new(1, 1),
                })
            }),
            notes: false,
            points: Vec::new(),
        }
    }

    /// Methods take turns seed by seed within each round of spp, counts a sampler
    /// rounds up (9) wait for the round that reaches them, and a curve stops after
    /// the first point over the time limit.
    #[test]
    fn curves_are_rendered_in_turn_and_stop_at_the_time_limit() {
        let order = std::cell::RefCell::new(Vec::new());
        let mut curves = vec![
            fake("a", vec![1, 2, 4, 8, 16], 0.1, &order),
            fake("b", vec![1, 4, 9, 16], 0.1, &order),
            fake("slow", vec![1, 2, 4], 9.0, &order),
        ];
        let opts = ConvergeOptions {
            scene: PathBuf::new(),
            reference: None,
            reference_noise: None,
            width: 1,
            height: 1,
            max_depth: 1,
            max_spp: 16,
            max_seconds_per_point: 8.0,
            reference_spp: 1,
            out_dir: PathBuf::new(),
            seed: 0,
            seeds: 2,
            compare_backends: false,
            mitsuba: None,
            cycles: None,
        };
        let r = Reference {
            image: Image::new(1, 1),
            noise_var: 0.0,
            note: String::new(),
        };
        let mut notes = Vec::new();
        interleave(&mut curves, &opts, &r, &mut |_| {}, &mut notes).unwrap();
        let seed = |spp: u32, k: u32| point_seed(&opts, spp, k);
        let mut want = Vec::new();
        // Round by round (1, 2, 4, 8, 16 spp): what each curve has due.
        for due in [
            vec![("a", 1), ("b", 1), ("slow", 1)],
            vec![("a", 2)],
            vec![("a", 4), ("b", 4)],
            vec![("a", 8)],
            vec![("a", 16), ("b", 9), ("b", 16)],
        ] {
            for k in 0..2 {
                for &(name, spp) in &due {
                    want.push(format!("{name}{spp}/{}", seed(spp, k)));
                }
            }
        }
        assert_eq!(*order.borrow(), want);
        let spps = |c: &Curve| c.points.iter().map(|p| p.spp).collect::<Vec<_>>();
        assert_eq!(spps(&curves[0]), [1, 2, 4, 8, 16]);
        assert_eq!(spps(&curves[1]), [1, 4, 9, 16]);
        assert_eq!(spps(&curves[2]), [1]);
    }

    fn pt(method: &str, peer: bool, spp: u32, seconds: f64, rmse: f64) -> Point {
        Point {
            method: method.into(),
            peer,
            spp,
            samples: 1,
            seconds,
            rmse,
            rel_mse: 0.0,
        }
    }

    /// The first method is what `ember SCENE` renders (`--integrator auto`), not
    /// `RenderSettings::default()`'s light sampling: on glossy spheres that is MIS at the
    /// glossy vertices.
    #[test]
    fn the_first_method_is_embers_default() {
        let path = format!(
            "{}/scenes/cs184/sky/CBspheres_microfacet_al_ag.dae",
            env!("CARGO_MANIFEST_DIR")
        );
        let scene = collada::load(Path::new(&path)).unwrap();
        let base = RenderSettings::default();
        let all = methods(&base, &scene, false);
        assert_eq!(all[0].name, DEFAULT_METHOD);
        let s = &all[0].settings;
        assert_eq!(s.strategy_for(&scene), DirectStrategy::MisGlossy);
        assert_eq!(s.estimator, None, "the default method is auto's choice");
        let adaptive = all.iter().find(|m| m.settings.adaptive.is_some()).unwrap();
        assert_eq!(
            adaptive.settings.strategy_for(&scene),
            DirectStrategy::MisGlossy
        );
    }

    #[test]
    fn curves_are_read_log_log_as_measured() {
        // On the log-log line RMSE = 0.1/√t: 2 s lies between the 1 s and 4 s points.
        let pts = vec![
            pt("a", false, 1, 0.01, 5.0),
            pt("a", false, 8, 1.0, 0.1),
            pt("a", false, 16, 4.0, 0.05),
            pt("a", false, 32, 16.0, 0.025),
        ];
        let r = rmse_at(&pts, "a", 2.0, false).unwrap();
        assert!((r - 0.1 / 2f64.sqrt()).abs() < 1e-12, "{r}");
        assert_eq!(rmse_at(&pts, "a", 16.0, true), Some(0.05));
        assert_eq!(rmse_at(&pts, "a", 20.0, false), None);
        assert_eq!(rmse_at(&pts, "b", 1.0, false), None);
    }

    /// Several renders make one point: the mean of their MSEs (one render's may fall
    /// below zero once the reference's noise is removed) and the median of their times.
    #[test]
    fn a_points_renders_average_their_mse_and_take_the_median_time() {
        let mut runs = Runs::default();
        for (t, mse) in [(3.0, 4e-4), (1.0, -1e-4), (2.0, 3e-4)] {
            runs.add(t, (mse, mse));
        }
        let (seconds, rmse, rel) = runs.point();
        assert_eq!(seconds, 2.0);
        assert!((rmse - 2e-4f64.sqrt()).abs() < 1e-12, "{rmse}");
        assert!((rel - 2e-4).abs() < 1e-12, "{rel}");
    }

    /// A peer whose error falls faster than 1/√time is compared where it was
    /// measured, not extrapolated from its efficiency: the ratio follows its curve.
    #[test]
    fn tables_compare_at_the_defaults_times_and_spp() {
        let mut pts = Vec::new();
        for (k, spp) in [16u32, 64, 256].into_iter().enumerate() {
            let t = 0.1 * 4f64.powi(k as i32);
            pts.push(pt("ember", false, spp, t, 0.01 / 2f64.powi(k as i32)));
        }
        // The peer: 10x slower per sample, RMSE ∝ 1/spp (faster than 1/√spp).
        for spp in [4u32, 16, 64, 256, 1024] {
            let t = 1e-2 * f64::from(spp) / 16.0 * 10.0;
            pts.push(pt("peer", true, spp, t, 0.16 / f64::from(spp)));
        }
        let report = ConvergeReport {
            scene: "s".into(),
            max_depth: 5,
            width: 1,
            height: 1,
            points: pts,
            reference_note: String::new(),
            peer_notes: Vec::new(),
            seeds: 1,
        };
        let time = report.equal_time_table();
        // At 0.1 s the peer has rendered 16 spp: RMSE 0.01, the ratio 1.00; at 1.6 s,
        // 256 spp: 0.000625 against ember's 0.0025, ratio 4.00.
        assert!(
            time.contains("| ember ÷ peer | 1.00 | 2.00 | 4.00 |"),
            "{time}"
        );
        let spp = report.equal_spp_table();
        assert!(
            spp.contains("| ember ÷ peer | 1.00 | 2.00 | 4.00 |"),
            "{spp}"
        );
    }
}
