//! The Embree modes part of `ember bench accel`: on one scene's camera rays, robust or
//! fast scene flags, low/medium/high build quality, and rays traced one at a time
//! (`rtcIntersect1`) or in packets of 4, 8 and 16 (`rtcIntersect4/8/16`). Each row
//! names the Embree it ran (version and ISA) and the flags it used, so the tables of
//! an `embree` (Embree 3) and an `embree4` build can be merged.

use super::measure::three_digits;
pub use super::measure::tiled_camera_rays;
use super::render_calls::{CallRates, RenderCalls, SelfHits};
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

impl RayQuery {
    /// The query flags the shim passes: Embree's default (INCOHERENT) for single rays,
    /// COHERENT for packets, which hold the camera rays of a compact pixel tile (as
    /// Embree's tutorials flag primary rays).
    pub fn flags(self) -> &'static str {
        match self {
            RayQuery::Single => "INCOHERENT (default)",
            RayQuery::Packet(_) => "COHERENT",
        }
    }
}

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
            let mode = EmbreeMode {
                quality,
                robust,
                ..EmbreeMode::default()
            };
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
            r.query.flags().into(),
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
                    ..EmbreeMode::default()
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

/// One step of issue 27: a way of driving Embree that differs from a neighbouring one
/// in one setting, so each row's figures against its neighbour's are that setting's
/// cost or gain.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EmbreeVariant {
    /// What the step changes, e.g. "single rays".
    pub step: &'static str,
    pub mode: EmbreeMode,
    /// Also measured in whole renders (`ember bench render --embree-steps`).
    pub in_renders: bool,
}

impl EmbreeVariant {
    /// The step's name, marked when it is what `--accel embree` uses.
    pub fn label(&self) -> String {
        if self.mode == EmbreeMode::robust(self.mode.quality)
            && self.mode.quality == EmbreeQuality::default()
        {
            format!("{} (default)", self.step)
        } else {
            self.step.to_string()
        }
    }
}

/// The variants measured in whole renders too, as backends (none without Embree).
pub fn render_steps() -> Vec<crate::accel::AccelKind> {
    #[cfg(any(feature = "embree", feature = "embree4"))]
    {
        let major = crate::accel::embree::info().map_or(3, |i| i.version.0);
        variants(EmbreeQuality::default(), major)
            .into_iter()
            .filter(|v| v.in_renders)
            .map(|v| crate::accel::AccelKind::Embree(v.mode))
            .collect()
    }
    #[cfg(not(any(feature = "embree", feature = "embree4")))]
    Vec::new()
}

/// The variants `ember bench accel` measures on a render's calls: from how ember drove
/// Embree before (16-lane packets, the skip filter on every spawned ray, Embree's
/// sphere primitive) one step at a time towards the default, then the default with
/// one setting changed. Streams only with Embree 3 (Embree 4 has none); a mode
/// already listed is not listed again.
pub fn variants(quality: EmbreeQuality, embree_major: i32) -> Vec<EmbreeVariant> {
    use crate::accel::{EmbreeQueries as Q, EmbreeSelfHits as H, EmbreeSpheres as S};
    let default = EmbreeMode::robust(quality);
    let with = |queries, self_hits, spheres| EmbreeMode {
        queries,
        self_hits,
        spheres,
        ..default
    };
    let steps = [
        (
            "before: rtcIntersect16 packets",
            EmbreeMode::before(quality),
            true,
        ),
        ("single rays", with(Q::Single, H::Filter, S::Embree), true),
        (
            "streams (rtcIntersect1M)",
            with(Q::Stream, H::Filter, S::Embree),
            true,
        ),
        (
            "filter only on retry",
            with(Q::Single, H::Retry, S::Embree),
            true,
        ),
        (
            "no filter (offset origins)",
            with(Q::Single, H::Offset, S::Embree),
            false,
        ),
        (
            "ember's sphere test",
            with(Q::Single, H::Retry, S::Ember),
            true,
        ),
        (
            "rtcIntersect8 packets",
            with(Q::Packet8, H::Retry, S::Ember),
            true,
        ),
        ("default", default, true),
    ];
    // The steps end at the default; the rest change one of its settings.
    let changed = [
        (
            "default, single rays",
            EmbreeMode {
                queries: Q::Single,
                ..default
            },
            false,
        ),
        (
            "default, coherent flag",
            EmbreeMode {
                queries: Q::Packet8Coherent,
                ..default
            },
            false,
        ),
        (
            "default, rtcIntersect16",
            EmbreeMode {
                queries: Q::Packet16,
                ..default
            },
            false,
        ),
        (
            "default, camera rays only in packets",
            EmbreeMode {
                queries: Q::CameraPackets,
                ..default
            },
            false,
        ),
        (
            "default, filter everywhere",
            EmbreeMode {
                self_hits: H::Filter,
                ..default
            },
            false,
        ),
        (
            "default, no filter",
            EmbreeMode {
                self_hits: H::Offset,
                ..default
            },
            false,
        ),
        (
            "default, Embree's spheres",
            EmbreeMode {
                spheres: S::Embree,
                ..default
            },
            false,
        ),
        (
            "default, no ROBUST flag",
            EmbreeMode {
                robust: false,
                ..default
            },
            true,
        ),
        (
            "default, low quality",
            EmbreeMode {
                quality: EmbreeQuality::Low,
                ..default
            },
            false,
        ),
        (
            "default, medium quality",
            EmbreeMode {
                quality: EmbreeQuality::Medium,
                ..default
            },
            false,
        ),
        (
            "default, high quality",
            EmbreeMode {
                quality: EmbreeQuality::High,
                ..default
            },
            false,
        ),
    ];
    let mut list: Vec<EmbreeVariant> = Vec::new();
    for (step, mode, in_renders) in steps.into_iter().chain(changed) {
        let unavailable = embree_major >= 4 && mode.queries == Q::Stream;
        if unavailable || list.iter().any(|v| v.mode == mode) {
            continue;
        }
        list.push(EmbreeVariant {
            step,
            mode,
            in_renders,
        });
    }
    list
}

/// One variant on one scene's render calls, against the native SAH tree on the same
/// calls, with what it gives up.
#[derive(Clone, Debug, PartialEq)]
pub struct EmbreeVariantRow {
    pub scene: String,
    /// [`build_label`].
    pub embree: String,
    pub step: String,
    pub mode: EmbreeMode,
    pub threads: usize,
    pub build_ms: f64,
    pub calls: CallRates,
    /// The native SAH tree's seconds for the same calls in the same rounds, over this
    /// variant's.
    pub native_over_embree: f64,
    /// The render's spawned rays on which it broke the skip contract.
    pub self_hits: SelfHits,
    /// Case 6's grazing ray queries (≥ 2e-4 rad, and 1e-5 to 1e-4 rad): rays, misses.
    pub grazing: [(u64, u64); 2],
}

/// Measures every variant of [`variants`] on `calls` (a render of `scene`), with the
/// native SAH tree in the same rounds. Errors when this build has no Embree.
#[cfg(any(feature = "embree", feature = "embree4"))]
pub fn embree_variants(
    scene: &Scene,
    scene_name: &str,
    calls: &RenderCalls,
    pool: &rayon::ThreadPool,
    builder: &AccelBuilder,
    repeats: usize,
) -> Result<Vec<EmbreeVariantRow>, AccelError> {
    use crate::accel::{Accel, AccelKind, BvhBuilder};
    use crate::bench::stability::robust::grid_queries_with;
    use std::time::Instant;

    let embree = build_label(builder)?;
    let major = builder.embree_device()?.info().version.0;
    let native = pool.install(|| builder.build(scene, AccelKind::Native(BvhBuilder::Sah)))?;
    let mut rows = Vec::new();
    for variant in variants(EmbreeQuality::default(), major) {
        // Each variant on a device of its own, dropped before the next: with Embree 4's
        // TBB, a scene of Embree's own spheres leaves a worker yielding in a loop for as
        // long as its device lives, which would slow every variant measured after it.
        let own = AccelBuilder::new(pool.current_num_threads());
        let start = Instant::now();
        let accel = pool.install(|| own.build_embree(scene, variant.mode))?;
        let build_ms = 1e3 * start.elapsed().as_secs_f64();
        let both: [&dyn Accel; 2] = [native.as_ref(), &accel];
        let rates = calls.measure(&both, pool, repeats);
        let grid = grid_queries_with(AccelKind::Embree(variant.mode), 1)
            .map_err(|e| AccelError::Embree(format!("case 6 queries: {e}")))?;
        rows.push(EmbreeVariantRow {
            scene: scene_name.to_string(),
            embree: embree.clone(),
            step: variant.label(),
            mode: variant.mode,
            threads: pool.current_num_threads(),
            build_ms,
            calls: rates[1],
            native_over_embree: rates[0].seconds / rates[1].seconds,
            self_hits: pool.install(|| calls.self_hits(&accel, native.as_ref())),
            grazing: [
                (grid.rays, grid.holes),
                (grid.extreme_rays, grid.extreme_holes),
            ],
        });
    }
    Ok(rows)
}

/// Measures every variant. Errors when this build has no Embree.
#[cfg(not(any(feature = "embree", feature = "embree4")))]
pub fn embree_variants(
    _scene: &Scene,
    _scene_name: &str,
    _calls: &RenderCalls,
    _pool: &rayon::ThreadPool,
    _builder: &AccelBuilder,
    _repeats: usize,
) -> Result<Vec<EmbreeVariantRow>, AccelError> {
    Err(AccelError::EmbreeUnavailable)
}

const VARIANT_HEADER: [&str; 18] = [
    "scene",
    "Embree",
    "step",
    "quality",
    "scene flags",
    "queries",
    "self-hits",
    "spheres",
    "threads",
    "build (ms)",
    "render calls: intersect (Mrays/s)",
    "occluded (Mrays/s)",
    "render calls (s)",
    "native ÷ Embree time",
    "own primitive hit (of spawned)",
    "extra occlusions (of spawned shadow)",
    "case 6 misses ≥ 2e-4 rad",
    "case 6 misses 1e-5..1e-4 rad",
];

/// The variant rows as a table: speed on the render's calls beside what each gives up.
pub fn variants_table(rows: &[EmbreeVariantRow]) -> Table {
    let mut t = Table::new(VARIANT_HEADER);
    for r in rows {
        let s = &r.self_hits;
        t.push(vec![
            r.scene.clone(),
            r.embree.clone(),
            r.step.clone(),
            r.mode.quality.to_string(),
            r.mode.scene_flags().into(),
            r.mode.queries.to_string(),
            r.mode.self_hits.to_string(),
            r.mode.spheres.to_string(),
            r.threads.to_string(),
            three_digits(r.build_ms),
            format!("{:.2}", r.calls.intersect_mrays),
            format!("{:.2}", r.calls.occluded_mrays),
            format!("{:.4}", r.calls.seconds),
            format!("{:.2}", r.native_over_embree),
            format!("{} of {}", s.own_hits, s.spawned),
            format!("{} of {}", s.extra_occlusions, s.spawned_shadow),
            format!("{} of {}", r.grazing[0].1, r.grazing[0].0),
            format!("{} of {}", r.grazing[1].1, r.grazing[1].0),
        ]);
    }
    t
}

/// Reads back rows [`variants_table`] wrote (its CSV), for merging two builds' tables.
/// The spawned rays' disagreements other than own hits and extra occlusions are not in
/// the table and read back as 0.
pub fn variant_rows_from_table(t: &Table) -> Result<Vec<EmbreeVariantRow>, String> {
    use crate::accel::{EmbreeQueries, EmbreeSelfHits, EmbreeSpheres};
    use crate::names::Named;
    if t.header != VARIANT_HEADER {
        return Err(format!(
            "not an Embree variants table: header {:?}",
            t.header
        ));
    }
    t.rows
        .iter()
        .map(|c| {
            let num = |i: usize| {
                c[i].parse::<f64>()
                    .map_err(|_| format!("{}: not a number: {:?}", VARIANT_HEADER[i], c[i]))
            };
            let pair = |i: usize| -> Result<(u64, u64), String> {
                let bad = || format!("{}: not \"N of M\": {:?}", VARIANT_HEADER[i], c[i]);
                let (a, b) = c[i].split_once(" of ").ok_or_else(bad)?;
                Ok((a.parse().map_err(|_| bad())?, b.parse().map_err(|_| bad())?))
            };
            let name = |e: crate::names::UnknownName| e.to_string();
            let (own, spawned) = pair(14)?;
            let (extra, shadow) = pair(15)?;
            let (g0, g1) = (pair(16)?, pair(17)?);
            Ok(EmbreeVariantRow {
                scene: c[0].clone(),
                embree: c[1].clone(),
                step: c[2].clone(),
                mode: EmbreeMode {
                    quality: EmbreeQuality::from_name(&c[3]).map_err(name)?,
                    robust: c[4] == "ROBUST",
                    queries: EmbreeQueries::from_name(&c[5]).map_err(name)?,
                    self_hits: EmbreeSelfHits::from_name(&c[6]).map_err(name)?,
                    spheres: EmbreeSpheres::from_name(&c[7]).map_err(name)?,
                },
                threads: num(8)? as usize,
                build_ms: num(9)?,
                calls: CallRates {
                    intersect_mrays: num(10)?,
                    occluded_mrays: num(11)?,
                    seconds: num(12)?,
                },
                native_over_embree: num(13)?,
                self_hits: SelfHits {
                    spawned,
                    own_hits: own,
                    spawned_shadow: shadow,
                    extra_occlusions: extra,
                    differ: 0,
                },
                grazing: [(g0.1, g0.0), (g1.1, g1.0)],
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
            mode: EmbreeMode::fast(EmbreeQuality::High),
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
            md.contains("| high | NONE | rtcIntersect8 | COHERENT | 2 | 42.0 | 35.4 | 1.77× |"),
            "{md}"
        );
        let back = rows_from_table(&Table::from_csv(&t.to_csv()).expect("csv")).expect("rows");
        assert_eq!(back, rows);
    }
}
