//! `ember bench estimators`: does `--integrator auto` pick the most efficient of path
//! tracing, light tracing and path tracing with light-traced caustics, on every scene
//! (each where it can render the image)?
//!
//! Each estimator renders the scene in pairs with independent seeds. Its noise is the
//! variance of one pixel of a pair's averaged image (from the two renders' difference,
//! as the pilot measures it); its cost is the pair's render time; its inefficiency is
//! their product, the error² it would reach in one second. auto's pick is what `ember`
//! runs for the scene: its rule where the scene decides, else its pilot. The row says
//! how much less efficient the pick is than the best estimator (1 when it picked it).

use super::table::Table;
use super::{create_out_dir, median, Report};
use crate::accel::{AccelKind, BvhBuilder};
use crate::integrators::{light_tracing, Estimator};
use crate::names::Named;
use crate::render::{RenderJob, RenderSettings};
use crate::scene::collada;
use anyhow::Result;
use std::path::{Path, PathBuf};
use std::time::Instant;

#[derive(Clone, Debug)]
pub struct EstimatorsOptions {
    pub scenes: Vec<PathBuf>,
    pub max_depth: u32,
    pub width: u32,
    pub height: u32,
    /// Samples per pixel of each render.
    pub spp: u32,
    /// Pairs of renders per estimator (each pair gives one noise estimate).
    pub pairs: u32,
    pub seed: u64,
}

/// One estimator on one scene: the noise² of a pair's averaged pixel and the pair's
/// render time, each the median over the pairs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cost {
    pub variance: f64,
    pub seconds: f64,
}

impl Cost {
    pub fn inefficiency(&self) -> f64 {
        self.variance * self.seconds
    }

    /// Table cells: noise², seconds, and inefficiency over path tracing's `path`.
    fn cells(&self, path: &Cost) -> [String; 3] {
        let p = path.inefficiency();
        let ratio = if p == 0.0 {
            "— (black image)".into()
        } else {
            format!("{:.3}", self.inefficiency() / p)
        };
        [
            format!("{:.3e}", self.variance),
            format!("{:.3}", self.seconds),
            ratio,
        ]
    }
}

#[derive(Clone, Debug)]
pub struct Row {
    pub scene: String,
    pub lights: String,
    /// What auto runs, and whether the scene's rule or the pilot chose it.
    pub pick: Estimator,
    pub by_pilot: bool,
    pub path: Cost,
    /// Path tracing cannot converge: it misses the caustics of point, spot or
    /// directional lights (`light_tracing::path_misses_caustics`), so its noise is
    /// not its error and it is not a candidate for the best.
    pub path_misses_caustics: bool,
    /// Where light tracing cannot show the image: why.
    pub light: Result<Cost, String>,
    /// Where light-traced caustics differ from path tracing
    /// (`light_tracing::caustics_possible`).
    pub caustics: Option<Cost>,
    /// There: camera samples per light path, the caustics pilot's choice.
    pub caustics_divisor: Option<u32>,
}

impl Row {
    /// The pick's inefficiency over the best estimator's (1: auto took the best;
    /// infinite for path tracing where it misses caustics).
    pub fn pick_over_best(&self) -> f64 {
        let path = self.path.inefficiency();
        let light = self.light.as_ref().ok().map(Cost::inefficiency);
        let caustics = self.caustics.map(|c| c.inefficiency());
        if self.path_misses_caustics && self.pick == Estimator::Path {
            return f64::INFINITY; // it does not converge to the image
        }
        let path = (!self.path_misses_caustics).then_some(path);
        let picked = match self.pick {
            Estimator::Path => path,
            Estimator::LightTracing => light,
            Estimator::Caustics => caustics,
        };
        // A pick that could not be measured is auto's rule saying it equals another.
        let Some(picked) = picked else {
            return 1.0;
        };
        let best = [path, light, caustics]
            .into_iter()
            .flatten()
            .fold(f64::INFINITY, f64::min);
        if picked == best {
            return 1.0; // also for a black image, where all are 0
        }
        picked / best
    }
}

pub struct EstimatorsReport {
    pub rows: Vec<Row>,
    /// Scenes left out, and why (unlit).
    pub skipped: Vec<String>,
    pub settings: String,
}

/// Every `.dae` under `dir` (recursively), sorted: the default scene list.
pub fn scenes_under(dir: &Path) -> Result<Vec<PathBuf>> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d)? {
            let p = entry?.path();
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|e| e.eq_ignore_ascii_case("dae")) {
                out.push(p);
            }
        }
    }
    out.sort();
    Ok(out)
}

pub fn run(opts: &EstimatorsOptions, log: &mut dyn FnMut(&str)) -> Result<EstimatorsReport> {
    let mut rows = Vec::new();
    let mut skipped = Vec::new();
    for path in &opts.scenes {
        let name = label(path);
        let scene = collada::load(path)?;
        if scene.lights.is_empty() && !scene.materials.iter().any(|m| m.emits()) {
            skipped.push(format!("{name}: unlit"));
            continue;
        }
        log(&format!("scene: {name}"));
        let lights = light_kinds(&scene);
        let gaps = light_tracing::warnings(&scene, opts.max_depth);
        let job = RenderJob::new(
            scene,
            AccelKind::Native(BvhBuilder::Sah),
            opts.width,
            opts.height,
        )?;
        // What `ember SCENE` runs: auto's estimator and direct-lighting strategy
        // (`RenderSettings::default()` fixes path tracing with light sampling).
        let base = RenderSettings {
            spp: opts.spp,
            max_depth: opts.max_depth,
            estimator: None,
            strategy: None,
            ..Default::default()
        };
        let (pick, scores) = job.estimator_choice(&base);
        let path = cost(&job, &base, Estimator::Path, opts);
        let light = match gaps.first() {
            Some(why) => Err(short_reason(why)),
            None => Ok(cost(&job, &base, Estimator::LightTracing, opts)),
        };
        // The caustics pilot runs here, as auto's pilot above, not in the timed renders.
        let caustics_divisor = job.caustics_split(&base).map(|(split, _)| split.divisor);
        let caustics = caustics_divisor.map(|_| cost(&job, &base, Estimator::Caustics, opts));
        rows.push(Row {
            scene: name,
            lights,
            pick,
            by_pilot: scores.is_some(),
            path,
            path_misses_caustics: light_tracing::path_misses_caustics(&job.scene, opts.max_depth),
            light,
            caustics,
            caustics_divisor,
        });
    }
    let settings = format!(
        "{}x{}, {} spp per render, -m {}, {} pair(s) of renders per estimator, all threads",
        opts.width, opts.height, opts.spp, opts.max_depth, opts.pairs
    );
    Ok(EstimatorsReport {
        rows,
        skipped,
        settings,
    })
}

/// The first clause of a light-tracing warning (`cannot connect mirror or glass
/// surfaces to the pinhole camera`), for a table cell.
fn short_reason(warning: &str) -> String {
    let clause = warning.split(':').next().unwrap_or(warning);
    clause.trim_start_matches("light tracing ").to_string()
}

/// A scene's name in the table: its path under a `scenes/` folder (`cs184/sky/CBempty.dae`),
/// else as given.
fn label(path: &Path) -> String {
    let parts: Vec<_> = path.components().collect();
    match parts.iter().rposition(|c| c.as_os_str() == "scenes") {
        Some(i) if i + 1 < parts.len() => parts[i + 1..]
            .iter()
            .map(|c| c.as_os_str().to_string_lossy())
            .collect::<Vec<_>>()
            .join("/"),
        _ => path.display().to_string(),
    }
}

/// The lights of a scene by kind, as `2 point, 1 area`.
fn light_kinds(scene: &crate::scene::Scene) -> String {
    let mut kinds: Vec<(&str, usize)> = Vec::new();
    for l in &scene.lights {
        match kinds.iter_mut().find(|(k, _)| *k == l.kind()) {
            Some((_, n)) => *n += 1,
            None => kinds.push((l.kind(), 1)),
        }
    }
    if scene.has_unsampled_emitters() {
        kinds.push(("emissive surface", 1));
    }
    let parts: Vec<String> = kinds.iter().map(|(k, n)| format!("{n} {k}")).collect();
    parts.join(", ")
}

fn cost(job: &RenderJob, base: &RenderSettings, e: Estimator, opts: &EstimatorsOptions) -> Cost {
    let mut variances = Vec::new();
    let mut seconds = Vec::new();
    for k in 0..u64::from(opts.pairs.max(1)) {
        // Pair k: two renders of `base.spp` each, seeds 2(seed + k) + 1 and + 2.
        let s = RenderSettings {
            estimator: Some(e),
            spp: base.spp.saturating_mul(2),
            seed: opts.seed.wrapping_add(k),
            ..base.clone()
        };
        let t = Instant::now();
        let pair = job.halves(&s);
        seconds.push(t.elapsed().as_secs_f64());
        variances.push(pair.noise_per_pixel().powi(2));
    }
    Cost {
        variance: median(&mut variances),
        seconds: median(&mut seconds),
    }
}

impl EstimatorsReport {
    pub fn table(&self) -> Table {
        let mut t = Table::new([
            "scene",
            "lights",
            "auto runs",
            "path: noise²",
            "path: s",
            "light tracing: noise²",
            "light tracing: s",
            "noise²·s, light tracing ÷ path",
            "caustics: camera samples per light path",
            "caustics: noise²",
            "caustics: s",
            "noise²·s, caustics ÷ path",
            "auto's pick ÷ the best (noise²·s)",
        ]);
        for r in &self.rows {
            let how = if r.by_pilot { "pilot" } else { "rule" };
            let unmeasured = |why: &str| ["—".into(), "—".into(), format!("— ({why})")];
            let light = match &r.light {
                Ok(l) => l.cells(&r.path),
                Err(why) => unmeasured(why),
            };
            let caustics = match &r.caustics {
                Some(c) => c.cells(&r.path),
                None => unmeasured("no caustics"),
            };
            let mut cells = vec![
                r.scene.clone(),
                r.lights.clone(),
                format!("{} ({how})", r.pick.name()),
                format!(
                    "{:.3e}{}",
                    r.path.variance,
                    if r.path_misses_caustics {
                        " (misses caustics)"
                    } else {
                        ""
                    }
                ),
                format!("{:.3}", r.path.seconds),
            ];
            cells.extend(light);
            cells.push(r.caustics_divisor.map_or("—".into(), |d| d.to_string()));
            cells.extend(caustics);
            cells.push(format!("{:.2}", r.pick_over_best()));
            t.push(cells);
        }
        t
    }
}

impl Report for EstimatorsReport {
    fn write(&self, out_dir: &Path) -> Result<Vec<PathBuf>> {
        create_out_dir(out_dir)?;
        let stem = out_dir.join("estimators");
        self.table().write(&stem)?;
        Ok(vec![stem.with_extension("csv"), stem.with_extension("md")])
    }

    fn summary(&self) -> String {
        let mut s = format!("{}\n\n{}", self.settings, self.table().to_markdown());
        for skip in &self.skipped {
            s += &format!("\nleft out: {skip}");
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(pick: Estimator, path: f64, light: f64) -> Row {
        let c = |v| Cost {
            variance: v,
            seconds: 2.0,
        };
        Row {
            scene: "s".into(),
            lights: String::new(),
            pick,
            by_pilot: true,
            path: c(path),
            path_misses_caustics: false,
            light: Ok(c(light)),
            caustics: None,
            caustics_divisor: None,
        }
    }

    #[test]
    fn scenes_are_named_by_their_path_under_scenes() {
        assert_eq!(
            label(Path::new("/x/ember/scenes/cs184/sky/CBempty.dae")),
            "cs184/sky/CBempty.dae"
        );
        assert_eq!(label(Path::new("my/room.dae")), "my/room.dae");
    }

    #[test]
    fn the_pick_is_compared_with_the_better_estimator() {
        assert_eq!(row(Estimator::Path, 1.0, 4.0).pick_over_best(), 1.0);
        assert_eq!(row(Estimator::LightTracing, 1.0, 4.0).pick_over_best(), 4.0);
        assert_eq!(row(Estimator::LightTracing, 3.0, 1.5).pick_over_best(), 1.0);
        assert_eq!(row(Estimator::Path, 0.0, 0.0).pick_over_best(), 1.0);
        let mut only_path = row(Estimator::Path, 1.0, 0.1);
        only_path.light = Err("mirrors".into());
        assert_eq!(only_path.pick_over_best(), 1.0);
        let mut glass = only_path.clone();
        glass.caustics = Some(Cost {
            variance: 0.25,
            seconds: 2.0,
        });
        assert_eq!(glass.pick_over_best(), 4.0);
        glass.pick = Estimator::Caustics;
        assert_eq!(glass.pick_over_best(), 1.0);
        // Path tracing that misses caustics is no candidate, however low its noise.
        let mut sun = glass.clone();
        sun.path = Cost {
            variance: 0.01,
            seconds: 1.0,
        };
        sun.path_misses_caustics = true;
        assert_eq!(sun.pick_over_best(), 1.0);
        sun.pick = Estimator::Path;
        assert_eq!(sun.pick_over_best(), f64::INFINITY);
    }
}
