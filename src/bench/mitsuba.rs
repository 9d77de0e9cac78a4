//! Mitsuba 3 as a peer in the benchmarks: the scene is exported with
//! `ember export --format mitsuba` and rendered by `scripts/mitsuba-render.py`
//! in a Python that has `mitsuba` (see `scripts/mitsuba-env`). Mitsuba is only
//! ever run as a separate process, never linked.

use crate::camera::Camera;
use crate::export::{write_mitsuba, MitsubaRoulette, MitsubaSampler, MitsubaSettings};
use crate::film::Image;
use crate::image_io::read_image;
use crate::integrators::Roulette;
use crate::scene::Scene;
use anyhow::{bail, Context, Result};
use std::path::{Path, PathBuf};
use std::process::Command;

/// The render script, embedded so the binary needs no source tree.
const RENDER_SCRIPT: &str = include_str!("../../scripts/mitsuba-render.py");

/// One Mitsuba variant, sampler and roulette start driven through a Python interpreter.
pub struct MitsubaRunner {
    python: PathBuf,
    script: PathBuf,
    variant: String,
    sampler: MitsubaSampler,
    roulette: MitsubaRoulette,
    dir: PathBuf,
}

/// One timed render by a peer renderer.
pub struct PeerRender {
    /// Render-only seconds (Mitsuba: a warm call, JIT compilation excluded).
    pub seconds: f64,
    /// Samples per pixel the peer reports it rendered.
    pub spp: u32,
    pub image: Image,
}

impl MitsubaRunner {
    /// Checks that `python` imports Mitsuba with `variant` and writes the render
    /// script into `dir`.
    pub fn new(
        python: &Path,
        variant: &str,
        sampler: MitsubaSampler,
        roulette: MitsubaRoulette,
        dir: &Path,
    ) -> Result<Self> {
        let probe = format!("import mitsuba as mi, numpy; mi.set_variant('{variant}')");
        let failed = format!("cannot use Mitsuba variant {variant}");
        let script = peer_script(
            python,
            &probe,
            &failed,
            dir,
            "mitsuba-render.py",
            RENDER_SCRIPT,
        )?;
        Ok(MitsubaRunner {
            python: python.to_path_buf(),
            script,
            variant: variant.to_string(),
            sampler,
            roulette,
            dir: dir.to_path_buf(),
        })
    }

    /// What the export of a render at `spp` and `-m max_depth` tells Mitsuba.
    fn settings(&self, spp: u32, max_depth: u32) -> MitsubaSettings {
        let ember = MitsubaSettings::for_ember(spp, max_depth, &Roulette::default());
        MitsubaSettings {
            sampler: self.sampler,
            roulette_start: match self.roulette {
                MitsubaRoulette::Ember => ember.roulette_start,
                MitsubaRoulette::Depth(d) => Some(d),
            },
            ..ember
        }
    }

    /// "Mitsuba 3 llvm_ad_rgb, multijitter" (with ember's roulette start), or
    /// "Mitsuba 3 llvm_ad_rgb, multijitter, rr_depth 5".
    pub fn name(&self) -> String {
        match self.roulette {
            MitsubaRoulette::Ember => format!("Mitsuba 3 {}, {}", self.variant, self.sampler),
            MitsubaRoulette::Depth(d) => {
                format!("Mitsuba 3 {}, {}, rr_depth {d}", self.variant, self.sampler)
            }
        }
    }

    /// The sample counts of the doubling sequence 1, 2, 4, … up to `max_spp` as
    /// this sampler takes them (rounded up as Mitsuba does, repeats dropped), and
    /// the first count it takes beyond: ember's render at `max_spp` often takes
    /// longer than a peer's, and the equal-time table compares at ember's times.
    pub fn sample_counts(&self, max_spp: u32) -> Vec<u32> {
        let mut v: Vec<u32> = super::doubling(1, max_spp)
            .map(|n| self.sampler.sample_count(n))
            .filter(|&n| n <= max_spp)
            .collect();
        v.push(self.sampler.sample_count(max_spp.saturating_mul(2)));
        v.dedup();
        v
    }

    /// Exports `scene` as ember renders it (`-m max_depth`; roulette from ember's
    /// start or the runner's `rr_depth`) at `spp` and renders it twice in one
    /// process, timing the second call. Fails when Mitsuba renders another count
    /// than `spp` rounded for the sampler.
    pub fn render(
        &self,
        scene: &Scene,
        camera: &Camera,
        max_depth: u32,
        spp: u32,
        seed: u64,
    ) -> Result<PeerRender> {
        let rr = match self.roulette {
            MitsubaRoulette::Ember => String::new(),
            MitsubaRoulette::Depth(d) => format!("_rr{d}"),
        };
        let stem = format!("scene_m{max_depth}_{spp}spp_{}{rr}", self.sampler);
        let settings = self.settings(spp, max_depth);
        let xml = export(scene, camera, &settings, &self.dir, &stem)?;
        let exr = self.dir.join(format!("{stem}_{}_{seed}.exr", self.variant));
        let out = Command::new(&self.python)
            .arg(&self.script)
            .arg(&xml)
            .args(["--variant", &self.variant, "--renders", "2"])
            .args(["--seed", &seed.to_string(), "--out"])
            .arg(&exr)
            .output()
            .with_context(|| format!("{}: cannot run", self.python.display()))?;
        if !out.status.success() {
            bail!(
                "{}: Mitsuba ({}) failed: {}",
                xml.display(),
                self.variant,
                last_line(&out.stderr)
            );
        }
        let stdout = String::from_utf8_lossy(&out.stdout);
        let last = stdout.lines().last().unwrap_or_default();
        let seconds = number_of(last, "seconds")
            .with_context(|| format!("{}: no timing in Mitsuba's output", xml.display()))?;
        let used = number_of(last, "spp").unwrap_or(0.0) as u32;
        let expected = self.sampler.sample_count(spp);
        if used != expected {
            bail!(
                "{}: Mitsuba's {} sampler rendered {used} spp where {expected} were expected",
                xml.display(),
                self.sampler
            );
        }
        let image = read_image(&exr)?;
        Ok(PeerRender {
            seconds,
            spp: used,
            image,
        })
    }
}

/// Writes `scene` with `settings` to `dir/stem.xml` and its meshes, always anew: a
/// file left there by another scene (the names do not say which scene) must not
/// be rendered in its place.
pub(crate) fn export(
    scene: &Scene,
    camera: &Camera,
    settings: &MitsubaSettings,
    dir: &Path,
    stem: &str,
) -> Result<PathBuf> {
    write_mitsuba(scene, camera, settings, dir, stem)?;
    Ok(dir.join(format!("{stem}.xml")))
}

/// The number in field `key` of one flat JSON line printed by a render script.
pub(crate) fn number_of(line: &str, key: &str) -> Option<f64> {
    let tag = format!("\"{key}\":");
    let rest = &line[line.find(&tag)? + tag.len()..];
    let end = rest.find([',', '}'])?;
    rest[..end].trim().parse().ok()
}

/// Checks that `python` runs `probe` (else `failed` and Python's last line of error),
/// then writes a peer's render script as `dir/name`: its path.
pub(crate) fn peer_script(
    python: &Path,
    probe: &str,
    failed: &str,
    dir: &Path,
    name: &str,
    text: &str,
) -> Result<PathBuf> {
    std::fs::create_dir_all(dir).with_context(|| format!("{}: cannot create", dir.display()))?;
    let out = Command::new(python)
        .args(["-c", probe])
        .output()
        .with_context(|| format!("{}: cannot run", python.display()))?;
    if !out.status.success() {
        bail!("{}: {failed}: {}", python.display(), last_line(&out.stderr));
    }
    let script = dir.join(name);
    std::fs::write(&script, text).with_context(|| format!("{}: cannot write", script.display()))?;
    Ok(script)
}

pub(crate) fn last_line(bytes: &[u8]) -> String {
    let s = String::from_utf8_lossy(bytes);
    s.lines()
        .rev()
        .find(|l| !l.trim().is_empty())
        .unwrap_or("no message")
        .trim()
        .to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The converge runs of CBbunny once rendered CBspheres_lambertian in Mitsuba: the
    /// export was skipped when a file of the same name was there.
    #[test]
    fn each_export_replaces_what_another_scene_left() {
        let scene = |f: &str| format!("{}/scenes/cs184/sky/{f}", env!("CARGO_MANIFEST_DIR"));
        let load = |f: &str| crate::scene::collada::load(std::path::Path::new(&scene(f))).unwrap();
        let dir = std::env::temp_dir().join(format!("ember-mitsuba-export-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let mut texts = Vec::new();
        for f in ["CBspheres_lambertian.dae", "CBbunny.dae"] {
            let scene = load(f);
            let camera = Camera::new(&scene.camera, &scene.bounds, 16, 12);
            let settings = MitsubaSettings::for_ember(4, 5, &Roulette::default());
            let xml = export(&scene, &camera, &settings, &dir, "scene_m5_4spp").unwrap();
            texts.push(std::fs::read_to_string(xml).unwrap());
        }
        std::fs::remove_dir_all(&dir).unwrap();
        let spheres = |t: &str| t.matches("type=\"sphere\"").count();
        assert!(
            spheres(&texts[0]) > 0 && spheres(&texts[1]) == 0,
            "{}",
            texts[1]
        );
    }

    /// `ember` keeps ember's roulette start, a number becomes Mitsuba's `rr_depth`,
    /// and the written scene says so.
    #[test]
    fn roulette_starts_parse_and_reach_the_export() {
        assert_eq!("ember".parse(), Ok(MitsubaRoulette::Ember));
        assert_eq!("5".parse(), Ok(MitsubaRoulette::Depth(5)));
        assert!("five".parse::<MitsubaRoulette>().is_err());
        let start = Roulette::default().start().unwrap();
        let both = [MitsubaRoulette::Ember, MitsubaRoulette::Depth(start)];
        assert!(both[1].repeats_ember(&both) && !both[0].repeats_ember(&both));
        assert!(!MitsubaRoulette::Depth(start + 1).repeats_ember(&both));
        assert!(!both[1].repeats_ember(&both[1..]));
        let scene = crate::scene::collada::load(std::path::Path::new(&format!(
            "{}/scenes/cs184/sky/CBempty.dae",
            env!("CARGO_MANIFEST_DIR")
        )))
        .unwrap();
        let camera = Camera::new(&scene.camera, &scene.bounds, 16, 12);
        let dir = std::env::temp_dir().join(format!("ember-mitsuba-rr-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let ember_start = MitsubaSettings::for_ember(4, 5, &Roulette::default()).roulette_start;
        for (roulette, start) in [
            (MitsubaRoulette::Ember, ember_start.unwrap()),
            (MitsubaRoulette::Depth(5), 5),
        ] {
            let runner = MitsubaRunner {
                python: PathBuf::new(),
                script: PathBuf::new(),
                variant: "scalar_rgb".into(),
                sampler: MitsubaSampler::Multijitter,
                roulette,
                dir: dir.clone(),
            };
            let xml = export(&scene, &camera, &runner.settings(4, 5), &dir, "rr").unwrap();
            let text = std::fs::read_to_string(xml).unwrap();
            let want = format!("<integer name=\"rr_depth\" value=\"{start}\"/>");
            assert!(text.contains(&want), "{roulette:?}: {text}");
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// Each sampler's counts up to the largest, as it takes them, then one past it.
    #[test]
    fn peer_counts_go_one_past_the_largest() {
        let counts = |sampler| {
            let runner = MitsubaRunner {
                python: PathBuf::new(),
                script: PathBuf::new(),
                variant: "scalar_rgb".into(),
                sampler,
                roulette: MitsubaRoulette::Ember,
                dir: PathBuf::new(),
            };
            runner.sample_counts(256)
        };
        assert_eq!(counts(MitsubaSampler::Ldsampler), [4, 16, 64, 256, 1024]);
        let multijitter = counts(MitsubaSampler::Multijitter);
        assert_eq!(multijitter[..3], [1, 2, 4]);
        assert_eq!(multijitter[multijitter.len() - 2..], [256, 528]);
        assert_eq!(counts(MitsubaSampler::Independent).last(), Some(&512));
    }

    #[test]
    fn reads_the_numbers_of_a_render_line() {
        let line = r#"{"render": 1, "seconds": 0.25, "samples_per_second": 1.0, "spp": 16}"#;
        assert_eq!(number_of(line, "seconds"), Some(0.25));
        assert_eq!(number_of(line, "spp"), Some(16.0));
        assert_eq!(number_of(r#"{"seconds": 3e-2}"#, "seconds"), Some(0.03));
        assert_eq!(number_of("Traceback", "seconds"), None);
    }
}
