//! `ember bench accel --scaling`: build time, memory and ray throughput of every
//! backend against the triangle count, on a surface (a displaced sphere) and on a
//! random triangle soup, with least-squares fits of how each grows.
//!
//! A top-down build touches every primitive once per level, so its time should
//! grow like N·log N; a traversal visits about one node per level, so the time per
//! ray should grow like log N. The fits say how close each backend comes.

use super::chart::{write_chart_legend_outside, ChartSpec, Series};
use super::fit::{
    log2_fit_nonnegative, n_log_n_fit, power_law_fit, LinearFit, NLogNFit, PowerLawFit,
};
use super::measure::{make_rays, measure_all, three_digits, Measurement, Repeats};
use super::meshes;
use super::table::Table;
use super::Report;
use crate::accel::{self, AccelBuilder, AccelKind, BvhBuilder, EmbreeQuality};
use crate::scene::Scene;
use anyhow::{bail, Context, Result};
use std::path::{Path, PathBuf};

/// A family of generated meshes, one per size.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ScalingMesh {
    /// [`meshes::displaced_sphere`]: a finely tessellated closed surface.
    DisplacedSphere,
    /// [`meshes::random_soup`]: independent overlapping triangles in a box.
    RandomSoup,
}

impl ScalingMesh {
    pub const ALL: [ScalingMesh; 2] = [ScalingMesh::DisplacedSphere, ScalingMesh::RandomSoup];

    pub fn name(self) -> &'static str {
        match self {
            ScalingMesh::DisplacedSphere => "displaced sphere",
            ScalingMesh::RandomSoup => "random soup",
        }
    }

    /// File-name stem of this mesh's charts.
    pub fn slug(self) -> &'static str {
        match self {
            ScalingMesh::DisplacedSphere => "sphere",
            ScalingMesh::RandomSoup => "soup",
        }
    }

    pub fn generate(self, triangles: usize, seed: u64) -> Scene {
        match self {
            ScalingMesh::DisplacedSphere => meshes::displaced_sphere(triangles),
            ScalingMesh::RandomSoup => meshes::random_soup(triangles, seed),
        }
    }
}

#[derive(Clone, Debug)]
pub struct ScalingOptions {
    /// Target triangle counts (the sphere's tessellation rounds them slightly).
    pub sizes: Vec<usize>,
    pub meshes: Vec<ScalingMesh>,
    /// Rays of each kind per measurement (camera rays: the nearest 4:3 image).
    pub rays: usize,
    /// Build and tracing threads.
    pub threads: usize,
    /// Each figure is the median of up to this many runs.
    pub repeats: usize,
    /// A figure (a build, or a traversal of one ray set) stops repeating once its
    /// runs have taken this many seconds in total.
    pub budget_s: f64,
    /// Measure Embree at its three build qualities when this build has it.
    pub include_embree: bool,
    /// Growth fits use only sizes from this count up (all sizes when fewer than
    /// two qualify): at a thousand triangles fixed costs dominate and would bend the fit.
    pub fit_min_triangles: usize,
    pub seed: u64,
}

impl Default for ScalingOptions {
    fn default() -> Self {
        ScalingOptions {
            sizes: vec![1_000, 4_000, 16_000, 64_000, 256_000, 1_000_000, 4_000_000],
            meshes: ScalingMesh::ALL.to_vec(),
            rays: 200_000,
            threads: std::thread::available_parallelism().map_or(1, |n| n.get()),
            repeats: 3,
            budget_s: 2.0,
            include_embree: true,
            fit_min_triangles: 16_000,
            seed: 7,
        }
    }
}

/// One backend on one mesh of one size. Throughputs are in Mrays/s.
#[derive(Clone, Debug, PartialEq)]
pub struct ScalingRow {
    pub mesh: ScalingMesh,
    pub triangles: usize,
    pub backend: String,
    pub is_embree: bool,
    pub threads: usize,
    pub measured: Measurement,
}

#[derive(Clone, Debug, Default, PartialEq)]
pub struct ScalingReport {
    pub rows: Vec<ScalingRow>,
    pub fit_min_triangles: usize,
}

/// Both native builders, and robust Embree at each build quality.
fn backends(include_embree: bool) -> Vec<AccelKind> {
    let mut list = vec![
        AccelKind::Native(BvhBuilder::Midpoint),
        AccelKind::Native(BvhBuilder::Sah),
    ];
    if include_embree && cfg!(any(feature = "embree", feature = "embree4")) {
        list.extend(EmbreeQuality::ALL.map(AccelKind::embree));
    }
    list
}

/// Width and height of a 4:3 image with about `rays` pixels (at least 1×1).
fn camera_resolution(rays: usize) -> (u32, u32) {
    let height = ((rays as f64 * 0.75).sqrt().round() as u32).max(1);
    let width = (rays as u32).div_ceil(height).max(1);
    (width, height)
}

/// Measures every mesh, size and backend and returns the report (its [`Report::write`]
/// writes `scaling.csv`, `scaling.md` and the charts). `progress` hears one
/// line per measured row.
pub fn run_scaling(opts: &ScalingOptions, mut progress: impl FnMut(&str)) -> Result<ScalingReport> {
    if opts.sizes.is_empty() || opts.sizes.contains(&0) {
        bail!("scaling: sizes must be a non-empty list of positive triangle counts");
    }
    if opts.rays == 0 || opts.threads == 0 {
        bail!("scaling: rays and threads must be at least 1");
    }
    let pool = accel::tracing_pool(Some(opts.threads))?;
    let builder = AccelBuilder::new(opts.threads);
    let repeats = Repeats {
        count: opts.repeats.max(1),
        budget_s: opts.budget_s,
    };
    let (width, height) = camera_resolution(opts.rays);
    let mut report = ScalingReport {
        rows: Vec::new(),
        fit_min_triangles: opts.fit_min_triangles,
    };
    for &mesh in &opts.meshes {
        for &size in &opts.sizes {
            let scene = mesh.generate(size, opts.seed);
            let rays = make_rays(&scene, width, height, opts.rays, opts.seed);
            let kinds = backends(opts.include_embree);
            let measured = measure_all(&scene, &rays, &pool, &builder, &kinds, repeats)?;
            for (kind, m) in kinds.into_iter().zip(measured) {
                let row = ScalingRow {
                    mesh,
                    triangles: scene.triangles.len(),
                    backend: kind.to_string(),
                    is_embree: matches!(kind, AccelKind::Embree(_)),
                    threads: opts.threads,
                    measured: m,
                };
                progress(&format!(
                    "{} / {} tris / {}: build {} ms, {} MB, {:.2} / {:.2} / {:.2} Mrays/s",
                    mesh.name(),
                    row.triangles,
                    row.backend,
                    three_digits(row.measured.build_ms),
                    three_digits(row.measured.memory_mb),
                    row.measured.camera_mrays,
                    row.measured.incoherent_mrays,
                    row.measured.shadow_mrays
                ));
                report.rows.push(row);
            }
        }
    }
    Ok(report)
}

/// A measured quantity of a row, for charts and fits.
#[derive(Clone, Copy)]
struct Metric {
    stem: &'static str,
    title: &'static str,
    y_label: &'static str,
    value: fn(&ScalingRow) -> f64,
}

const METRICS: [Metric; 5] = [
    Metric {
        stem: "build",
        title: "Build time",
        y_label: "build time (ms)",
        value: |r| r.measured.build_ms,
    },
    Metric {
        stem: "memory",
        title: "Memory",
        y_label: "memory (MB)",
        value: |r| r.measured.memory_mb,
    },
    Metric {
        stem: "camera",
        title: "Camera rays",
        y_label: "throughput (Mrays/s)",
        value: |r| r.measured.camera_mrays,
    },
    Metric {
        stem: "incoherent",
        title: "Incoherent rays",
        y_label: "throughput (Mrays/s)",
        value: |r| r.measured.incoherent_mrays,
    },
    Metric {
        stem: "shadow",
        title: "Shadow rays",
        y_label: "throughput (Mrays/s)",
        value: |r| r.measured.shadow_mrays,
    },
];

/// Nanoseconds per ray at a throughput in Mrays/s (wall time over all threads).
fn ns_per_ray(mrays: f64) -> f64 {
    1e3 / mrays
}

/// The growth of one backend on one mesh.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GrowthFits {
    /// Build time in ms against N.
    pub build_power: Option<PowerLawFit>,
    /// Build time in ms as a·N·log2 N.
    pub build_n_log_n: Option<NLogNFit>,
    pub memory_power: Option<PowerLawFit>,
    /// Nanoseconds per ray as c + d·log2 N with c, d ≥ 0 (non-negative least
    /// squares), for camera, incoherent and shadow rays.
    pub per_ray: [Option<LinearFit>; 3],
    /// Nanoseconds per ray as a power law: an exponent well above 0 means the cost
    /// grows faster than log N (e.g. once the tree no longer fits in cache).
    pub per_ray_power: [Option<PowerLawFit>; 3],
}

impl ScalingReport {
    /// Meshes in first-seen order.
    fn meshes(&self) -> Vec<ScalingMesh> {
        let mut out: Vec<ScalingMesh> = Vec::new();
        for r in &self.rows {
            if !out.contains(&r.mesh) {
                out.push(r.mesh);
            }
        }
        out
    }

    /// Backends measured on `mesh`, in first-seen order.
    fn backends(&self, mesh: ScalingMesh) -> Vec<&str> {
        let mut out: Vec<&str> = Vec::new();
        for r in self.rows.iter().filter(|r| r.mesh == mesh) {
            if !out.contains(&r.backend.as_str()) {
                out.push(&r.backend);
            }
        }
        out
    }

    /// `(N, value)` of one backend on one mesh, in row order.
    fn points(
        &self,
        mesh: ScalingMesh,
        backend: &str,
        value: fn(&ScalingRow) -> f64,
    ) -> Vec<(f64, f64)> {
        self.rows
            .iter()
            .filter(|r| r.mesh == mesh && r.backend == backend)
            .map(|r| (r.triangles as f64, value(r)))
            .collect()
    }

    /// The points the fits use: those from `fit_min_triangles` up, or all when
    /// fewer than two are that large.
    fn fit_points(&self, points: Vec<(f64, f64)>) -> Vec<(f64, f64)> {
        let large: Vec<_> = points
            .iter()
            .copied()
            .filter(|p| p.0 >= self.fit_min_triangles as f64)
            .collect();
        if large.len() >= 2 {
            large
        } else {
            points
        }
    }

    pub fn fits(&self, mesh: ScalingMesh, backend: &str) -> GrowthFits {
        let pts =
            |value: fn(&ScalingRow) -> f64| self.fit_points(self.points(mesh, backend, value));
        let build = pts(|r| r.measured.build_ms);
        let ns: [Vec<(f64, f64)>; 3] = [
            pts(|r| r.measured.camera_mrays),
            pts(|r| r.measured.incoherent_mrays),
            pts(|r| r.measured.shadow_mrays),
        ]
        .map(|p| p.into_iter().map(|(n, m)| (n, ns_per_ray(m))).collect());
        GrowthFits {
            build_power: power_law_fit(&build),
            build_n_log_n: n_log_n_fit(&build),
            memory_power: power_law_fit(&pts(|r| r.measured.memory_mb)),
            per_ray: ns.clone().map(|p| log2_fit_nonnegative(&p)),
            per_ray_power: ns.map(|p| power_law_fit(&p)),
        }
    }

    /// One row per measurement.
    pub fn table(&self) -> Table {
        let mut t = Table::new([
            "mesh",
            "triangles",
            "backend",
            "threads",
            "build (ms)",
            "memory (MB)",
            "camera (Mrays/s)",
            "incoherent (Mrays/s)",
            "shadow (Mrays/s)",
        ]);
        for r in &self.rows {
            let m = &r.measured;
            t.push(vec![
                r.mesh.name().into(),
                r.triangles.to_string(),
                r.backend.clone(),
                r.threads.to_string(),
                three_digits(m.build_ms),
                three_digits(m.memory_mb),
                format!("{:.3}", m.camera_mrays),
                format!("{:.3}", m.incoherent_mrays),
                format!("{:.3}", m.shadow_mrays),
            ]);
        }
        t
    }

    /// The measurements as one table, then the fitted growth of each backend.
    pub fn to_markdown(&self) -> String {
        format!(
            "{}\n{}\n\n{}",
            self.table().to_markdown(),
            self.growth_caption(),
            self.growth_table().to_markdown()
        )
    }

    fn growth_caption(&self) -> String {
        format!(
            "Growth, least squares over N ≥ {} triangles (all sizes when fewer than two qualify). \
             Build: a power law N^b fitted on log-log axes, and a·N·log2 N (a in ns). \
             Traversal: time per ray (ns, wall time over all threads) = c + d·log2 N, fitted by non-negative least squares \
             (c, d ≥ 0: a time per ray can be neither negative nor fall as the tree deepens; where the free line would cross \
             zero above one triangle, c = 0), and its power-law exponent.",
            self.fit_min_triangles
        )
    }

    /// The fitted growth of each backend on each mesh.
    pub fn growth_table(&self) -> Table {
        let mut t = Table::new([
            "mesh",
            "backend",
            "build ~ N^b (R²)",
            "build = a·N·log2 N: a (R²)",
            "memory ~ N^b (R²)",
            "camera: c + d·log2 N, c, d ≥ 0 (R²)",
            "incoherent: c + d·log2 N, c, d ≥ 0 (R²)",
            "shadow: c + d·log2 N, c, d ≥ 0 (R²)",
        ]);
        let power = |p: Option<PowerLawFit>| {
            p.map_or("—".into(), |p| {
                format!("N^{:.2} ({:.3})", p.exponent, p.r2)
            })
        };
        for mesh in self.meshes() {
            for backend in self.backends(mesh) {
                let f = self.fits(mesh, backend);
                let nlogn = f.build_n_log_n.map_or("—".into(), |p| {
                    format!("{} ({:.3})", three_digits(p.coefficient * 1e6), p.r2)
                });
                let per_ray = |i: usize| match (f.per_ray[i], f.per_ray_power[i]) {
                    (Some(l), Some(p)) => format!(
                        "{:.1} + {:.2}·log2 N ({:.3}); ~N^{:.2}",
                        l.intercept, l.slope, l.r2, p.exponent
                    ),
                    _ => "—".into(),
                };
                let [cam, inc, sh] = [0, 1, 2].map(per_ray);
                t.push(vec![
                    mesh.name().into(),
                    backend.into(),
                    power(f.build_power),
                    nlogn,
                    power(f.memory_power),
                    cam,
                    inc,
                    sh,
                ]);
            }
        }
        t
    }

    /// Five log-log charts per mesh against the triangle count (build time,
    /// memory, and throughput for each ray kind), one line per backend, as
    /// `<slug>_<metric>.png` and `.svg`. Returns the stems written.
    pub fn write_charts(&self, out_dir: &Path) -> Result<Vec<PathBuf>> {
        std::fs::create_dir_all(out_dir)
            .with_context(|| format!("creating {}", out_dir.display()))?;
        let threads = self.rows.first().map_or(0, |r| r.threads);
        let mut stems = Vec::new();
        for mesh in self.meshes() {
            for metric in METRICS {
                let series: Vec<Series> = self
                    .backends(mesh)
                    .into_iter()
                    .map(|b| Series {
                        name: b.to_string(),
                        points: self.points(mesh, b, metric.value),
                    })
                    .collect();
                let title = format!(
                    "{} vs triangle count: {} ({})",
                    metric.title,
                    mesh.name(),
                    crate::names::thread_count(threads)
                );
                let spec = ChartSpec {
                    title: &title,
                    x_label: "triangles N",
                    y_label: metric.y_label,
                    log_x: true,
                    log_y: true,
                };
                let stem = out_dir.join(format!("{}_{}", mesh.slug(), metric.stem));
                write_chart_legend_outside(&stem, &spec, &series)?;
                stems.push(stem);
            }
        }
        Ok(stems)
    }
}

impl Report for ScalingReport {
    /// `scaling.csv`, `scaling.md` (the table and the growth fits) and the charts.
    fn write(&self, out_dir: &Path) -> Result<Vec<PathBuf>> {
        super::create_out_dir(out_dir)?;
        let stem = out_dir.join("scaling");
        self.table().write(&stem)?;
        let md = stem.with_extension("md");
        super::write_text(&md, &self.to_markdown())?;
        let mut files = vec![stem.with_extension("csv"), md];
        for chart in self.write_charts(out_dir)? {
            files.push(chart.with_extension("png"));
            files.push(chart.with_extension("svg"));
        }
        Ok(files)
    }

    fn summary(&self) -> String {
        self.to_markdown()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn camera_resolution_is_about_the_ray_count() {
        let (w, h) = camera_resolution(200_000);
        assert!(
            (w * h) as usize >= 200_000 && (w * h) < 200_000 + w,
            "{w}x{h}"
        );
        assert_eq!(camera_resolution(1), (1, 1));
    }
}
