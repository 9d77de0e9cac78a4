//! How an image was made, as an ordered list of key/value strings: written into EXR
//! headers as string attributes and into PNG files as text chunks, read back by
//! `ember info IMAGE`. Shard headers and merges reuse the same list.

use crate::render::{RenderJob, RenderSettings};
use std::path::Path;

/// Ordered key/value strings describing how an image was made.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ImageMetadata {
    pub entries: Vec<(String, String)>,
}

impl ImageMetadata {
    /// The facts every ember image records: version, command line, CPU model.
    pub fn provenance() -> Self {
        let mut m = ImageMetadata::default();
        m.push("ember.version", env!("CARGO_PKG_VERSION"));
        let args: Vec<String> = std::env::args().collect();
        m.push("ember.command_line", args.join(" "));
        m.push("ember.cpu", cpu_model());
        m
    }

    /// Everything a render's image records: provenance, the scene and its hash, every
    /// resolved setting, the backend, and the render time.
    pub fn for_render(
        scene: &Path,
        job: &RenderJob,
        settings: &RenderSettings,
        render_seconds: f64,
    ) -> Self {
        let mut m = ImageMetadata::provenance();
        m.push_file("ember.scene", scene);
        let s = settings;
        m.push(
            "ember.resolution",
            format!("{}x{}", job.camera.width, job.camera.height),
        );
        m.push("ember.spp", s.spp);
        m.push("ember.light_samples", s.light_samples);
        m.push("ember.max_depth", s.max_depth);
        m.push("ember.accumulate", s.accumulate);
        m.push("ember.estimator", s.strategy_for(&job.scene));
        m.push("ember.roulette", format!("{:?}", s.roulette));
        m.push("ember.adaptive", format!("{:?}", s.adaptive));
        m.push("ember.shading", s.shading);
        m.push("ember.seed", s.seed);
        m.push("ember.spp_offset", s.spp_offset);
        let lens = job.camera.lens;
        if !lens.is_pinhole() {
            m.push(
                "ember.lens",
                format!(
                    "radius {} focal distance {}",
                    lens.radius, lens.focal_distance
                ),
            );
        }
        m.push("ember.backend", job.accel.name());
        m.push("ember.render_seconds", format!("{render_seconds:.3}"));
        m
    }

    /// Appends `key = value` (a repeated key keeps both, in order).
    pub fn push(&mut self, key: impl Into<String>, value: impl ToString) {
        self.entries.push((key.into(), value.to_string()));
    }

    /// Records `path` and a hash of its bytes (FNV-1a 64, stable across builds).
    pub fn push_file(&mut self, key: &str, path: &Path) {
        self.push(key, path.display());
        if let Ok(bytes) = std::fs::read(path) {
            self.push(
                format!("{key}.fnv1a64"),
                format!("{:016x}", fnv1a64(&bytes)),
            );
        }
    }

    /// The value of the first entry named `key`.
    pub fn get(&self, key: &str) -> Option<&str> {
        self.entries
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v.as_str())
    }

    /// One `key: value` line per entry.
    pub fn to_text(&self) -> String {
        self.entries
            .iter()
            .map(|(k, v)| format!("{k}: {v}\n"))
            .collect()
    }
}

/// FNV-1a 64-bit hash: small, dependency-free and stable, enough to tell scenes apart.
pub fn fnv1a64(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

/// The CPU model from /proc/cpuinfo, or "unknown".
pub fn cpu_model() -> String {
    std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split_once(':'))
                .map(|(_, v)| v.trim().to_string())
        })
        .unwrap_or_else(|| "unknown".into())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fnv1a64_known_values() {
        assert_eq!(fnv1a64(b""), 0xcbf2_9ce4_8422_2325);
        assert_eq!(fnv1a64(b"a"), 0xaf63_dc4c_8601_ec8c);
    }
}
