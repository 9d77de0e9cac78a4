//! How an image was made, as an ordered list of key/value strings: written into EXR
//! headers as string attributes and into PNG files as text chunks, read back by
//! `ember info IMAGE`. Shard headers and merges reuse the same list.

use crate::integrators::{Estimator, Roulette};
use crate::render::{Adaptive, RenderJob, RenderSettings, Shading, StopReason, StopRule};
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
        m.push("ember.git_hash", env!("EMBER_GIT_HASH"));
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
        match s.spp {
            u32::MAX => m.push("ember.spp", "no cap"),
            spp => m.push("ember.spp", spp),
        }
        // Light transport settings mean nothing to a normals or BVH-cost image.
        if s.shading == Shading::Radiance {
            m.push("ember.light_samples", s.light_samples);
            m.push("ember.max_depth", s.max_depth);
            m.push("ember.accumulate", s.accumulate);
            m.push("ember.estimator", estimator_label(s, job));
            m.push("ember.roulette", roulette_text(&s.roulette));
        }
        m.push("ember.adaptive", adaptive_text(s.adaptive.as_ref()));
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

    /// The samples the image holds: per-pixel mean, least and most, the passes done,
    /// and why the render ended early (`ember.stopped`) or `complete`.
    pub fn push_samples(&mut self, samples: &[u32], passes: Option<u32>, stop: Option<StopReason>) {
        let total: u64 = samples.iter().map(|&s| s as u64).sum();
        let mean = total as f64 / samples.len().max(1) as f64;
        let min = samples.iter().min().copied().unwrap_or(0);
        let max = samples.iter().max().copied().unwrap_or(0);
        self.push(
            "ember.samples_per_pixel",
            format!("mean {mean:.3}, min {min}, max {max}"),
        );
        let rendered = samples.iter().filter(|&&s| s > 0).count();
        self.push(
            "ember.pixels_rendered",
            format!("{rendered} of {}", samples.len()),
        );
        if let Some(p) = passes {
            self.push("ember.passes", p);
        }
        self.push(
            "ember.stopped",
            stop.map_or("complete".to_string(), |r| r.to_string()),
        );
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

/// `--rr` as a user reads it: `off`, `throughput from bounce 5, min 0.05`,
/// `probability 0.5 from bounce 3`.
pub fn roulette_text(r: &Roulette) -> String {
    match *r {
        Roulette::Off => "off".into(),
        Roulette::Throughput { start, min_prob } => {
            format!("throughput from bounce {start}, min {min_prob}")
        }
        Roulette::Fixed { start, prob } => format!("probability {prob} from bounce {start}"),
    }
}

/// `-a` as a user reads it: `off`, or `batch 32, tolerance 0.05, ...` with the rule for
/// pixels whose samples are all equal.
pub fn adaptive_text(a: Option<&Adaptive>) -> String {
    let Some(a) = a else {
        return "off".into();
    };
    let constant = match a.rule {
        StopRule::Neighbourhood => {
            "pixels of zeros as their neighbourhood says, other constant pixels"
        }
        StopRule::PerPixel => "constant pixels",
    };
    format!(
        "batch {}, tolerance {}, {constant} after {} samples",
        a.batch, a.tol, a.min_samples_if_constant
    )
}

/// What `--integrator` (perhaps auto) chose for `scene`: light tracing, or path
/// tracing with its direct-lighting strategy.
pub fn estimator_label(s: &RenderSettings, job: &RenderJob) -> String {
    let strategy = s.strategy_for(&job.scene);
    let e = job.estimator(s);
    let split = (e == Estimator::Caustics)
        .then(|| job.caustics_split(s))
        .flatten();
    match (e, split) {
        (Estimator::LightTracing, _) => e.to_string(),
        (_, Some((split, _))) => {
            let per = match split.divisor {
                1 => "1 light path per camera sample".to_string(),
                d => format!("1 light path per {d} camera samples"),
            };
            format!("{e} ({strategy}, {per})")
        }
        (_, None) => format!("{e} ({strategy})"),
    }
}

/// FNV-1a 64-bit hash: small, dependency-free and stable, enough to tell scenes apart.
pub fn fnv1a64(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

/// The CPU model from /proc/cpuinfo, or "unknown". On x86 its family and model
/// numbers follow the name: some virtual machines name every Xeon generation alike
/// ("Intel(R) Xeon(R) Processor"), and a speed ratio means little without the core.
pub fn cpu_model() -> String {
    std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| cpu_model_of(&s))
        .unwrap_or_else(|| "unknown".into())
}

fn cpu_model_of(cpuinfo: &str) -> Option<String> {
    let field = |key: &str| {
        cpuinfo
            .lines()
            .take_while(|l| !l.trim().is_empty())
            .filter_map(|l| l.split_once(':'))
            .find(|(k, _)| k.trim() == key)
            .map(|(_, v)| v.trim().to_string())
    };
    let name = field("model name")?;
    Some(match (field("cpu family"), field("model")) {
        (Some(family), Some(model)) => format!("{name} (family {family}, model {model})"),
        _ => name,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cpu_model_names_family_and_model() {
        let info = "processor\t: 0\nvendor_id\t: GenuineIntel\ncpu family\t: 6\nmodel\t\t: 207\n\
                    model name\t: Intel(R) Xeon(R) Processor\n\nprocessor\t: 1\nmodel\t\t: 1\n";
        assert_eq!(
            cpu_model_of(info).as_deref(),
            Some("Intel(R) Xeon(R) Processor (family 6, model 207)")
        );
        let arm = "processor\t: 0\nmodel name\t: ARMv8 Processor rev 1 (v8l)\n";
        assert_eq!(
            cpu_model_of(arm).as_deref(),
            Some("ARMv8 Processor rev 1 (v8l)")
        );
        assert_eq!(cpu_model_of("processor\t: 0\n"), None);
    }

    #[test]
    fn settings_read_as_words_not_rust_syntax() {
        let default = roulette_text(&Roulette::default());
        assert_eq!(default, "throughput from bounce 5, min 0.05");
        let fixed = Roulette::Fixed {
            start: 2,
            prob: 0.5,
        };
        assert_eq!(roulette_text(&fixed), "probability 0.5 from bounce 2");
        assert_eq!(roulette_text(&Roulette::Off), "off");
        assert_eq!(adaptive_text(None), "off");
        let a = adaptive_text(Some(&Adaptive::new(32, 0.05)));
        assert!(a.starts_with("batch 32, tolerance 0.05, "), "{a}");
        for text in [default, a] {
            assert!(!text.contains(['{', '}', '(', ')', ':']), "{text}");
        }
    }

    #[test]
    fn fnv1a64_known_values() {
        assert_eq!(fnv1a64(b""), 0xcbf2_9ce4_8422_2325);
        assert_eq!(fnv1a64(b"a"), 0xaf63_dc4c_8601_ec8c);
    }
}
