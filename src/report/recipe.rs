//! One figure's render: the settings the report renders it with, and the `ember`
//! command line that renders the same image bit for bit. Both come from the same
//! fields here, so the command printed under a figure cannot drift from the render.

use crate::accel::{AccelKind, Backend, BvhBuilder, EmbreeQuality};
use crate::integrators::{DirectStrategy, Estimator};
use crate::render::{Adaptive, RenderSettings, Shading};
use std::path::PathBuf;

/// What one image of the report is: a scene at a resolution, with the flags of the
/// course's command line that matter to it. Everything else is ember's default.
#[derive(Clone, Debug, PartialEq)]
pub struct Recipe {
    pub scene: PathBuf,
    pub width: u32,
    pub height: u32,
    /// `-s`: samples per pixel (with `-a`, the most a pixel takes).
    pub spp: u32,
    /// `-l`.
    pub light_samples: u32,
    /// `-m`.
    pub max_depth: u32,
    /// `-o 1` (true, the default) or `-o 0`.
    pub accumulate: bool,
    /// `-H`: uniform hemisphere sampling instead of light sampling.
    pub hemisphere: bool,
    /// `-a BATCH TOL`.
    pub adaptive: Option<(u32, f32)>,
    /// `--shading`.
    pub shading: Shading,
    /// `--accel`.
    pub accel: Backend,
    /// `--seed`.
    pub seed: u64,
}

impl Recipe {
    /// A radiance render of `scene` at `width × height` with ember's defaults
    /// (`-s 1 -l 1 -m 1`, light sampling, accumulated bounces, `--accel auto`).
    pub fn new(scene: PathBuf, (width, height): (u32, u32), seed: u64) -> Recipe {
        Recipe {
            scene,
            width,
            height,
            spp: 1,
            light_samples: 1,
            max_depth: 1,
            accumulate: true,
            hemisphere: false,
            adaptive: None,
            shading: Shading::Radiance,
            accel: Backend::Auto,
            seed,
        }
    }

    /// The render settings the command line gives for these flags: the estimator and
    /// direct-lighting strategy are left to the scene unless `-H` names them, as
    /// `--integrator auto` does.
    pub fn settings(&self) -> RenderSettings {
        RenderSettings {
            spp: self.spp,
            light_samples: self.light_samples.max(1),
            max_depth: self.max_depth,
            accumulate: self.accumulate,
            estimator: self.hemisphere.then_some(Estimator::Path),
            strategy: self.hemisphere.then_some(DirectStrategy::Hemisphere),
            adaptive: self.adaptive.map(|(batch, tol)| Adaptive::new(batch, tol)),
            shading: self.shading,
            seed: self.seed,
            ..RenderSettings::default()
        }
    }

    /// The acceleration structure `--accel` builds (with the default builder and quality).
    pub fn accel_kind(&self) -> AccelKind {
        AccelKind::new(self.accel, BvhBuilder::default(), EmbreeQuality::default())
    }

    /// The flags of `ember FLAGS -f OUT SCENE` in the order people write them; a flag
    /// at its default is left out, except a radiance render's `-s`, `-l` and `-m`.
    pub fn flags(&self) -> Vec<String> {
        let mut f: Vec<String> = Vec::new();
        let mut push = |flag: &str, values: &[String]| {
            f.push(flag.to_string());
            f.extend(values.iter().cloned());
        };
        if self.shading != Shading::Radiance {
            push("--shading", &[self.shading.to_string()]);
        }
        if self.hemisphere {
            push("-H", &[]);
        }
        // A radiance render states its samples, light rays and depth even at their
        // defaults, so the figures of a row differ visibly in one flag.
        let radiance = self.shading == Shading::Radiance;
        if radiance || self.spp != 1 {
            push("-s", &[self.spp.to_string()]);
        }
        if let Some((batch, tol)) = self.adaptive {
            push("-a", &[batch.to_string(), tol.to_string()]);
        }
        if radiance || self.light_samples != 1 {
            push("-l", &[self.light_samples.to_string()]);
        }
        if radiance || self.max_depth != 1 {
            push("-m", &[self.max_depth.to_string()]);
        }
        if !self.accumulate {
            push("-o", &["0".to_string()]);
        }
        push("-r", &[self.width.to_string(), self.height.to_string()]);
        if self.accel != Backend::Auto {
            push("--accel", &[self.accel.to_string()]);
        }
        if self.seed != 0 {
            push("--seed", &[self.seed.to_string()]);
        }
        f
    }

    /// The whole command line, with the scene and the output as `scene` and `out` name them.
    pub fn command(&self, scene: &str, out: &str) -> String {
        let mut words = vec!["ember".to_string()];
        words.extend(self.flags());
        words.extend(["-f".to_string(), out.to_string(), scene.to_string()]);
        let quoted: Vec<String> = words.iter().map(|w| shell_word(w)).collect();
        quoted.join(" ")
    }

    /// How much work a pixel of this render is, for the progress bar: its samples
    /// times the rays a sample may trace.
    pub fn work_per_pixel(&self) -> u64 {
        let per_sample = match self.shading {
            Shading::Radiance => 1 + self.max_depth as u64 * (1 + self.light_samples as u64),
            _ => 1,
        };
        // An adaptive pixel takes a fraction of its cap; a quarter is typical.
        let spp = match self.adaptive {
            Some(_) => (self.spp as u64 / 4).max(1),
            None => self.spp as u64,
        };
        spp * per_sample
    }
}

/// `word` as a POSIX shell reads it: bare when it is made of safe characters, else in
/// single quotes.
pub fn shell_word(word: &str) -> String {
    let safe = |c: char| c.is_ascii_alphanumeric() || "-_./=:,+@%".contains(c);
    if !word.is_empty() && word.chars().all(safe) {
        word.to_string()
    } else {
        format!("'{}'", word.replace('\'', "'\\''"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_left_out_of_the_command() {
        let r = Recipe::new("scenes/a.dae".into(), (480, 360), 0);
        assert_eq!(
            r.command("scenes/a.dae", "out/a.png"),
            "ember -s 1 -l 1 -m 1 -r 480 360 -f out/a.png scenes/a.dae"
        );
        let normals = Recipe {
            shading: Shading::Normals,
            ..r.clone()
        };
        assert_eq!(
            normals.command("a.dae", "a.png"),
            "ember --shading normals -r 480 360 -f a.png a.dae"
        );
        let s = r.settings();
        assert_eq!((s.estimator, s.strategy), (None, None));
    }

    #[test]
    fn every_flag_that_differs_is_written() {
        let r = Recipe {
            hemisphere: true,
            spp: 16,
            light_samples: 4,
            max_depth: 5,
            accumulate: false,
            adaptive: Some((64, 0.05)),
            accel: Backend::None,
            seed: 3,
            ..Recipe::new("a b.dae".into(), (80, 60), 0)
        };
        assert_eq!(
            r.command("a b.dae", "x.png"),
            "ember -H -s 16 -a 64 0.05 -l 4 -m 5 -o 0 -r 80 60 --accel none --seed 3 -f x.png 'a b.dae'"
        );
        let s = r.settings();
        assert_eq!(s.strategy, Some(DirectStrategy::Hemisphere));
        assert_eq!(s.adaptive, Some(Adaptive::new(64, 0.05)));
        assert_eq!(r.accel_kind(), AccelKind::None);
    }

    #[test]
    fn shell_words_are_quoted_only_when_needed() {
        assert_eq!(shell_word("report/figures/a.png"), "report/figures/a.png");
        assert_eq!(shell_word("it's"), "'it'\\''s'");
        assert_eq!(shell_word(""), "''");
    }
}
