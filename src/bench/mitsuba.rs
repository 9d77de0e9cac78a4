//! Mitsuba 3 as a peer in the benchmarks: the scene is exported with
//! `ember export --format mitsuba` and rendered by `scripts/mitsuba-render.py`
//! in a Python that has `mitsuba` (see `scripts/mitsuba-env`). Mitsuba is only
//! ever run as a separate process, never linked.

use crate::camera::Camera;
use crate::export::{write_mitsuba, MitsubaSettings};
use crate::film::Image;
use crate::image_io::read_image;
use crate::integrators::Roulette;
use crate::scene::Scene;
use anyhow::{bail, Context, Result};
use std::path::{Path, PathBuf};
use std::process::Command;

/// The render script, embedded so the binary needs no source tree.
const RENDER_SCRIPT: &str = include_str!("../../scripts/mitsuba-render.py");

/// One Mitsuba variant driven through a Python interpreter.
pub struct MitsubaRunner {
    python: PathBuf,
    script: PathBuf,
    variant: String,
    dir: PathBuf,
}

/// One timed Mitsuba render.
pub struct MitsubaRender {
    /// Render-only seconds of a warm call (JIT compilation excluded).
    pub seconds: f64,
    pub image: Image,
}

impl MitsubaRunner {
    /// Checks that `python` imports Mitsuba with `variant` and writes the render
    /// script into `dir`.
    pub fn new(python: &Path, variant: &str, dir: &Path) -> Result<Self> {
        std::fs::create_dir_all(dir)
            .with_context(|| format!("{}: cannot create", dir.display()))?;
        let probe = Command::new(python)
            .args([
                "-c",
                &format!("import mitsuba as mi, numpy; mi.set_variant('{variant}')"),
            ])
            .output()
            .with_context(|| format!("{}: cannot run", python.display()))?;
        if !probe.status.success() {
            bail!(
                "{}: cannot use Mitsuba variant {variant}: {}",
                python.display(),
                last_line(&probe.stderr)
            );
        }
        let script = dir.join("mitsuba-render.py");
        std::fs::write(&script, RENDER_SCRIPT)
            .with_context(|| format!("{}: cannot write", script.display()))?;
        Ok(MitsubaRunner {
            python: python.to_path_buf(),
            script,
            variant: variant.to_string(),
            dir: dir.to_path_buf(),
        })
    }

    pub fn variant(&self) -> &str {
        &self.variant
    }

    /// Exports `scene` as ember renders it (`-m max_depth`, default roulette) at
    /// `spp` and renders it twice in one process, timing the second call.
    pub fn render(
        &self,
        scene: &Scene,
        camera: &Camera,
        max_depth: u32,
        spp: u32,
        seed: u64,
    ) -> Result<MitsubaRender> {
        let stem = format!("scene_m{max_depth}_{spp}spp");
        let xml = export(scene, camera, max_depth, spp, &self.dir, &stem)?;
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
        let seconds = stdout
            .lines()
            .last()
            .and_then(seconds_of)
            .with_context(|| format!("{}: no timing in Mitsuba's output", xml.display()))?;
        let image = read_image(&exr)?;
        Ok(MitsubaRender { seconds, image })
    }
}

/// Writes `scene` as ember renders it (`-m max_depth`, default roulette, `spp`) to
/// `dir/stem.xml` and its meshes, always anew: a file left there by another scene
/// (the names do not say which scene) must not be rendered in its place.
fn export(
    scene: &Scene,
    camera: &Camera,
    max_depth: u32,
    spp: u32,
    dir: &Path,
    stem: &str,
) -> Result<PathBuf> {
    let settings = MitsubaSettings::for_ember(spp, max_depth, &Roulette::default());
    write_mitsuba(scene, camera, &settings, dir, stem)?;
    Ok(dir.join(format!("{stem}.xml")))
}

/// The `"seconds"` field of one JSON line printed by the render script.
fn seconds_of(line: &str) -> Option<f64> {
    let rest = &line[line.find("\"seconds\":")? + "\"seconds\":".len()..];
    let end = rest.find([',', '}'])?;
    rest[..end].trim().parse().ok()
}

fn last_line(bytes: &[u8]) -> String {
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
            let xml = export(&scene, &camera, 5, 4, &dir, "scene_m5_4spp").unwrap();
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

    #[test]
    fn reads_the_seconds_of_a_render_line() {
        let line = r#"{"render": 1, "seconds": 0.25, "samples_per_second": 1.0}"#;
        assert_eq!(seconds_of(line), Some(0.25));
        assert_eq!(seconds_of(r#"{"seconds": 3e-2}"#), Some(0.03));
        assert_eq!(seconds_of("Traceback"), None);
    }
}
