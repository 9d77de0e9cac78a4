//! Blender Cycles as a peer in the benchmarks: the scene is exported as for
//! Mitsuba (`ember export --format mitsuba`, the one statement of what ember
//! renders) and `scripts/cycles_render.py` translates that into `bpy` and renders
//! it, in a Python that has Blender 4.5 as a module (see `scripts/cycles-env`).
//! The script refuses what it cannot translate exactly (it names the element),
//! and checks its image mean against the reference's manifest. Cycles is only
//! ever run as a separate process, never linked.

use super::mitsuba::{export, last_line, number_of, peer_script, PeerRender};
use crate::camera::Camera;
use crate::export::{MitsubaSampler, MitsubaSettings};
use crate::image_io::read_image;
use crate::integrators::Roulette;
use crate::scene::Scene;
use anyhow::{bail, Context, Result};
use std::path::{Path, PathBuf};
use std::process::Command;

/// The render script, embedded so the binary needs no source tree.
const RENDER_SCRIPT: &str = include_str!("../../scripts/cycles_render.py");

/// Cycles driven through a Python interpreter that imports `bpy`.
pub struct CyclesRunner {
    python: PathBuf,
    script: PathBuf,
    dir: PathBuf,
    /// The reference EXR the script checks its image mean against, if any.
    reference: Option<PathBuf>,
}

impl CyclesRunner {
    /// Checks that `python` imports `bpy` and writes the render script into `dir`.
    pub fn new(python: &Path, dir: &Path, reference: Option<&Path>) -> Result<Self> {
        let script = peer_script(
            python,
            "import bpy, numpy",
            "cannot import bpy (scripts/cycles-env installs it)",
            dir,
            "cycles_render.py",
            RENDER_SCRIPT,
        )?;
        Ok(CyclesRunner {
            python: python.to_path_buf(),
            script,
            dir: dir.to_path_buf(),
            reference: reference.map(Path::to_path_buf),
        })
    }

    pub fn name(&self) -> String {
        "Blender Cycles 4.5".into()
    }

    /// 2, 4, … up to `max_spp` and one step beyond (as Mitsuba's counts): the script
    /// subtracts a 1-spp render as fixed cost, so a 1-spp point has no time of its own.
    pub fn sample_counts(&self, max_spp: u32) -> Vec<u32> {
        super::doubling(2, max_spp.saturating_mul(2)).collect()
    }

    /// Whether the script can translate `scene` exactly (`Err` says what it cannot),
    /// checked before a long run so that a scene Cycles cannot render costs nothing.
    pub fn check(&self, scene: &Scene, camera: &Camera, max_depth: u32) -> Result<()> {
        let settings = MitsubaSettings::for_ember(1, max_depth, &Roulette::default());
        let xml = export(scene, camera, &settings, &self.dir, "scene_check_cycles")?;
        let out = Command::new(&self.python)
            .arg(&self.script)
            .arg(&xml)
            .arg("--check-only")
            .output()
            .with_context(|| format!("{}: cannot run", self.python.display()))?;
        if !out.status.success() {
            bail!("{}", last_line(&out.stderr));
        }
        Ok(())
    }

    /// Exports `scene` as ember renders it and renders it with Cycles at `spp`;
    /// the time is that of `spp` samples without the render call's fixed cost.
    /// Fails when the script cannot translate the scene, or when its image mean
    /// disagrees with the reference's.
    pub fn render(
        &self,
        scene: &Scene,
        camera: &Camera,
        max_depth: u32,
        spp: u32,
        seed: u64,
        log: &mut dyn FnMut(&str),
    ) -> Result<PeerRender> {
        let stem = format!("scene_m{max_depth}_{spp}spp_cycles");
        let settings = MitsubaSettings {
            sampler: MitsubaSampler::Independent,
            ..MitsubaSettings::for_ember(spp, max_depth, &Roulette::default())
        };
        let xml = export(scene, camera, &settings, &self.dir, &stem)?;
        let exr = self.dir.join(format!("{stem}_{seed}.exr"));
        let mut cmd = Command::new(&self.python);
        cmd.arg(&self.script)
            .arg(&xml)
            .args(["--spp", &spp.to_string(), "--seed"])
            // Cycles' seed is an int.
            .arg((seed % (1 << 31)).to_string())
            .arg("--out")
            .arg(&exr);
        if let Some(r) = &self.reference {
            cmd.arg("--reference").arg(r);
        }
        let out = cmd
            .output()
            .with_context(|| format!("{}: cannot run", self.python.display()))?;
        let stderr = String::from_utf8_lossy(&out.stderr);
        let check = stderr.lines().find(|l| l.starts_with("mean check:"));
        if let Some(line) = check {
            log(&format!("Cycles {spp} spp: {line}"));
        }
        if !out.status.success() {
            bail!(
                "{}: Cycles failed: {}",
                xml.display(),
                check.map_or_else(|| last_line(&out.stderr), str::to_string)
            );
        }
        let stdout = String::from_utf8_lossy(&out.stdout);
        // Blender prints its progress on stdout too; the script's line is the last JSON one.
        let last = stdout
            .lines()
            .rev()
            .find(|l| l.starts_with('{'))
            .unwrap_or_default();
        let seconds = number_of(last, "seconds").with_context(|| {
            format!("{}: no timing in the Cycles script's output", xml.display())
        })?;
        let image = read_image(&exr)?;
        Ok(PeerRender {
            seconds,
            spp,
            image,
        })
    }
}
