//! The Embree modes part of `ember bench accel`: on one scene's camera rays, robust or
//! fast scene flags, low/medium/high build quality, and rays traced one at a time
//! (`rtcIntersect1`) or in packets of 4, 8 and 16 (`rtcIntersect4/8/16`). Each row
//! names the Embree it ran (version and ISA) and the flags it used, so the tables of
//! an `embree` (Embree 3) and an `embree4` build can be merged.

use super::measure::three_digits;
pub use super::measure::tiled_camera_rays;
use super::table::Table;
use crate::accel::{AccelBuilder, AccelError, EmbreeMode, EmbreeQuality};
use crate::geometry::Ray;
use crate::scene::Scene;

/// How camera rays reach Embree.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RayQuery {
    Single,
    /// Packets of this many rays (4, 8 or 16) over compact pixel tiles.
    Packet(usize),
}

impl RayQuery {
    pub const ALL: [RayQuery; 4] = [
        RayQuery::Single,
        RayQuery::Packet(4),
        RayQuery::Packet(8),
        RayQuery::Packet(16),
    ];

    pub fn call(self) -> String {
        match self {
            RayQuery::Single => "rtcIntersect1".into(),
            RayQuery::Packet(n) => format!("rtcIntersect{n}"),
        }
    }
}

/// The ray query flags of every row: the shim passes Embree's defaults
/// (`rtcInitIntersectContext` in 3, `rtcInitIntersectArguments` in 4), which are
/// INCOHERENT in both.
pub const QUERY_FLAGS: &str = "INCOHERENT (default)";

#[derive(Clone, Debug, PartialEq)]
pub struct EmbreeModeRow {
    pub scene: String,
    /// [`build_label`]: version and ISA, e.g. "Embree 4.4.0 AVX2".
    pub embree: String,
    pub mode: EmbreeMode,
    /// `rtcSetSceneFlags` as Embree reports it back: "ROBUST" or "NONE".
    pub scene_flags: String,
    pub query: RayQuery,
    pub threads: usize,
    pub build_ms: f64,
    pub camera_mrays: f64,
}

/// The Embree of this build as rows name it ("Embree 4.4.0 AVX2"), "none" without one.
pub fn build_label(builder: &AccelBuilder) -> Result<String, AccelError> {
    #[cfg(any(feature = "embree", feature = "embree4"))]
    {
        let info = builder.embree_device()?.info();
        let (a, b, c) = info.version;
        Ok(format!("Embree {a}.{b}.{c} {}", info.isa()))
    }
    #[cfg(not(any(feature = "embree", feature = "embree4")))]
    {
        let _ = builder;
        Ok("none".into())
    }
}

/// Measures every mode on `scene`'s `camera` rays (in tiled order) with `builder`'s
/// device on `pool`; each figure is the median of `repeats` runs. Errors when this
/// build has no Embree.
#[cfg(any(feature = "embree", feature = "embree4"))]
pub fn embree_modes(
    scene: &Scene,
    scene_name: &str,
    camera: &[Ray],
    pool: &rayon::ThreadPool,
    builder: &AccelBuilder,
    repeats: usize,
) -> Result<Vec<EmbreeModeRow>, AccelError> {
    use super::median;
    use std::time::Instant;

    let embree = build_label(builder)?;
    let mut rows = Vec::new();
    for robust in [true, false] {
        for quality in EmbreeQuality::ALL {
            let mode = EmbreeMode { quality, robust };
            let mut build_s = Vec::new();
            let mut accel = None;
            for _ in 0..repeats.max(1) {
                drop(accel.take());
                let start = Instant::now();
                accel = Some(pool.install(|| builder.build_embree(scene, mode))?);
                build_s.push(start.elapsed().as_secs_f64());
            }
            let accel = accel.expect("built at least once");
            let mut times = [(); 4].map(|_| Vec::new());
            trace(pool, &accel, camera, RayQuery::Single); // warm-up
            for _ in 0..repeats.max(1) {
                for (q, query) in RayQuery::ALL.into_iter().enumerate() {
                    times[q].push(trace(pool, &accel, camera, query));
                }
            }
            for (q, query) in RayQuery::ALL.into_iter().enumerate() {
                rows.push(EmbreeModeRow {
                    scene: scene_name.to_string(),
                    embree: embree.clone(),
                    mode,
                    scene_flags: accel.scene_flags().to_string(),
                    query,
                    threads: pool.current_num_threads(),
                    build_ms: 1e3 * median(&mut build_s.clone()),
                    camera_mrays: camera.len() as f64 / median(&mut times[q]) / 1e6,
                });
            }
        }
    }
    Ok(rows)
}

/// Measures every mode on `scene`. Errors when this build has no Embree.
#[cfg(not(any(feature = "embree", feature = "embree4")))]
pub fn embree_modes(
    _scene: &Scene,
    _scene_name: &str,
    _camera: &[Ray],
    _pool: &rayon::ThreadPool,
    _builder: &AccelBuilder,
    _repeats: usize,
) -> Result<Vec<EmbreeModeRow>, AccelError> {
    Err(AccelError::EmbreeUnavailable)
}

/// Seconds to trace `rays` in chunks of 256 (whole packets of every width) on `pool`.
#[cfg(any(feature = "embree", feature = "embree4"))]
fn trace(
    pool: &rayon::ThreadPool,
    accel: &crate::accel::embree::EmbreeAccel,
    rays: &[Ray],
    query: RayQuery,
) -> f64 {
    use crate::accel::embree::PacketWidth;
    use crate::accel::Accel;
    use rayon::prelude::*;

    let start = std::time::Instant::now();
    let hits: usize = pool.install(|| {
        rays.par_chunks(256)
            .map(|chunk| {
                let width = match query {
                    RayQuery::Single => {
                        return chunk
                            .iter()
                            .filter(|r| accel.intersect(r).is_some())
                            .count()
                    }
                    RayQuery::Packet(4) => PacketWidth::W4,
                    RayQuery::Packet(8) => PacketWidth::W8,
                    RayQuery::Packet(_) => PacketWidth::W16,
                };
                let mut out = vec![None; chunk.len()];
                accel.intersect_packets(width, chunk, &mut out);
                out.iter().filter(|h| h.is_some()).count()
            })
            .sum()
    });
    std::hint::black_box(hits);
    start.elapsed().as_secs_f64()
}

const HEADER: [&str; 10] = [
    "scene",
    "Embree",
    "quality",
    "scene flags",
    "query",
    "query flags",
    "threads",
    "build (ms)",
    "camera (Mrays/s)",
    "vs rtcIntersect1",
];

/// The rows as a table, one line per mode, with the flags each used and the packet
/// query's speed-up over single rays of the same build.
pub fn table(rows: &[EmbreeModeRow]) -> Table {
    let mut t = Table::new(HEADER);
    for r in rows {
        let single = rows.iter().find(|s| {
            s.query == RayQuery::Single
                && s.scene == r.scene
                && s.embree == r.embree
                && s.mode == r.mode
                && s.threads == r.threads
        });
        t.push(vec![
            r.scene.clone(),
            r.embree.clone(),
            r.mode.quality.to_string(),
            r.scene_flags.clone(),
            r.query.call(),
            QUERY_FLAGS.into(),
            r.threads.to_string(),
            three_digits(r.build_ms),
            three_digits(r.camera_mrays),
            single.map_or("—".into(), |s| {
                format!("{:.2}×", r.camera_mrays / s.camera_mrays)
            }),
        ]);
    }
    t
}

/// Reads back rows [`table`] wrote (its CSV), for merging the tables of two builds.
pub fn rows_from_table(t: &Table) -> Result<Vec<EmbreeModeRow>, String> {
    if t.header != HEADER {
        return Err(format!("not an Embree modes table: header {:?}", t.header));
    }
    t.rows
        .iter()
        .map(|c| {
            let quality: EmbreeQuality = c[2].parse().map_err(|e| format!("{e}"))?;
            let query = match c[4].strip_prefix("rtcIntersect").map(str::parse) {
                Some(Ok(1)) => RayQuery::Single,
                Some(Ok(n @ (4 | 8 | 16))) => RayQuery::Packet(n),
                _ => return Err(format!("unknown query {:?}", c[4])),
            };
            let num = |i: usize| {
                c[i].parse::<f64>()
                    .map_err(|_| format!("{}: not a number: {:?}", HEADER[i], c[i]))
            };
            Ok(EmbreeModeRow {
                scene: c[0].clone(),
                embree: c[1].clone(),
                mode: EmbreeMode {
                    quality,
                    robust: c[3] == "ROBUST",
                },
                scene_flags: c[3].clone(),
                query,
                threads: num(6)? as usize,
                build_ms: num(7)?,
                camera_mrays: num(8)?,
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(query: RayQuery, mrays: f64) -> EmbreeModeRow {
        EmbreeModeRow {
            scene: "s".into(),
            embree: "Embree 4.4.0 (AVX2, native ray packets of 8)".into(),
            mode: EmbreeMode {
                quality: EmbreeQuality::High,
                robust: false,
            },
            scene_flags: "NONE".into(),
            query,
            threads: 2,
            build_ms: 42.0,
            camera_mrays: mrays,
        }
    }

    #[test]
    fn table_names_the_flags_of_each_row_and_reads_back() {
        let rows = vec![row(RayQuery::Single, 20.0), row(RayQuery::Packet(8), 35.4)];
        let t = table(&rows);
        let md = t.to_markdown();
        assert!(
            md.contains(
                "| high | NONE | rtcIntersect8 | INCOHERENT (default) | 2 | 42.0 | 35.4 | 1.77× |"
            ),
            "{md}"
        );
        let back = rows_from_table(&Table::from_csv(&t.to_csv()).expect("csv")).expect("rows");
        assert_eq!(back, rows);
    }

    #[cfg(any(feature = "embree", feature = "embree4"))]
    #[test]
    fn every_mode_gets_a_row() {
        let scene = crate::bench::meshes::displaced_sphere(2_000);
        let camera = tiled_camera_rays(&scene, 32, 16);
        let pool = crate::accel::tracing_pool(Some(1)).expect("pool");
        let builder = AccelBuilder::new(1);
        let rows = embree_modes(&scene, "sphere", &camera, &pool, &builder, 1).expect("Embree");
        assert_eq!(rows.len(), 2 * 3 * 4);
        assert_eq!(
            rows.iter().filter(|r| r.scene_flags == "ROBUST").count(),
            12
        );
        assert!(rows
            .iter()
            .all(|r| r.camera_mrays > 0.0 && r.build_ms > 0.0));
    }
}
