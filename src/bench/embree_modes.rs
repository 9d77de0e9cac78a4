//! Every Embree mode this build can run, on one scene's camera rays: robust or fast
//! scene flags, low/medium/high build quality, and rays traced one at a time
//! (`rtcIntersect1`) or in packets of 4, 8 and 16 (`rtcIntersect4/8/16`). Each row
//! names the Embree it ran (version and ISA) and the flags it used, so tables of an
//! `embree` (Embree 3) and an `embree4` build can be merged.

use super::measure::{quality_name, three_digits};
use crate::accel::{AccelError, EmbreeQuality};
use crate::camera::Camera;
use crate::geometry::Ray;
use crate::scene::Scene;
use glam::Vec2;
use std::fmt::Write as _;

#[derive(Clone, Debug)]
pub struct EmbreeModesOptions {
    pub width: u32,
    pub height: u32,
    /// Tracing threads, and Embree's build threads.
    pub threads: usize,
    /// Each figure is the median of this many runs.
    pub repeats: usize,
}

impl Default for EmbreeModesOptions {
    fn default() -> Self {
        EmbreeModesOptions {
            width: 480,
            height: 360,
            threads: 2,
            repeats: 7,
        }
    }
}

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

#[derive(Clone, Debug, PartialEq)]
pub struct EmbreeModeRow {
    /// Version and ISA, e.g. "Embree 4.4.0 (AVX2, native ray packets of 8)".
    pub embree: String,
    pub quality: EmbreeQuality,
    /// `rtcSetSceneFlags` as Embree reports it back: "ROBUST" or "NONE".
    pub scene_flags: &'static str,
    pub query: RayQuery,
    /// The ray query flags: the shim passes Embree's defaults (`rtcInitIntersectContext`
    /// in 3, `rtcInitIntersectArguments` in 4), which are INCOHERENT in both.
    pub query_flags: &'static str,
    pub threads: usize,
    pub build_ms: f64,
    pub camera_mrays: f64,
}

/// Camera rays through the pixel centres, ordered by 4×4 pixel tiles and inside a
/// tile in Morton order, so every run of 4, 8 or 16 rays covers a 2×2, 4×2 or 4×4
/// block: the coherent packets Embree's packet kernels are made for.
pub fn tiled_camera_rays(scene: &Scene, width: u32, height: u32) -> Vec<Ray> {
    let cam = Camera::new(&scene.camera, &scene.bounds, width, height);
    let mut rays = Vec::with_capacity(width as usize * height as usize);
    for ty in (0..height).step_by(4) {
        for tx in (0..width).step_by(4) {
            for k in 0..16u32 {
                // Bits 0 and 2 of k give x, bits 1 and 3 give y.
                let (x, y) = (
                    tx + (k & 1) + ((k >> 1) & 2),
                    ty + ((k >> 1) & 1) + ((k >> 2) & 2),
                );
                if x < width && y < height {
                    rays.push(cam.generate_ray(x, y, Vec2::splat(0.5)));
                }
            }
        }
    }
    rays
}

/// Measures every mode on `scene`. Errors when this build has no Embree.
#[cfg(any(feature = "embree", feature = "embree4"))]
pub fn embree_modes(
    scene: &Scene,
    opts: &EmbreeModesOptions,
) -> Result<Vec<EmbreeModeRow>, AccelError> {
    use super::measure::tracing_pool;
    use super::median;
    use crate::accel::embree::{EmbreeAccel, EmbreeDevice, EmbreeMode};
    use std::sync::Arc;
    use std::time::Instant;

    let pool = tracing_pool(opts.threads).map_err(|e| AccelError::Embree(e.to_string()))?;
    let device = Arc::new(EmbreeDevice::new(opts.threads)?);
    let embree = device.info().to_string();
    let rays = tiled_camera_rays(scene, opts.width, opts.height);
    let mut rows = Vec::new();
    for robust in [true, false] {
        for quality in [
            EmbreeQuality::Low,
            EmbreeQuality::Medium,
            EmbreeQuality::High,
        ] {
            let mode = EmbreeMode { quality, robust };
            let mut build_s = Vec::new();
            let mut accel = None;
            for _ in 0..opts.repeats.max(1) {
                drop(accel.take());
                let start = Instant::now();
                accel = Some(EmbreeAccel::build_mode(device.clone(), scene, mode)?);
                build_s.push(start.elapsed().as_secs_f64());
            }
            let accel = accel.expect("built at least once");
            for query in RayQuery::ALL {
                trace(&pool, &accel, &rays, query); // warm-up
                let mut times: Vec<f64> = (0..opts.repeats.max(1))
                    .map(|_| trace(&pool, &accel, &rays, query))
                    .collect();
                rows.push(EmbreeModeRow {
                    embree: embree.clone(),
                    quality,
                    scene_flags: accel.scene_flags(),
                    query,
                    query_flags: "INCOHERENT (default)",
                    threads: opts.threads,
                    build_ms: 1e3 * median(&mut build_s.clone()),
                    camera_mrays: rays.len() as f64 / median(&mut times) / 1e6,
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
    _opts: &EmbreeModesOptions,
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

/// A Markdown table of `rows`, one line per mode, with the flags each used.
pub fn markdown(rows: &[EmbreeModeRow]) -> String {
    let mut out = String::from(
        "| Embree | quality | scene flags | query | query flags | threads | build (ms) | camera (Mrays/s) |\n\
         |---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        // Writing into a String cannot fail.
        let _ = writeln!(
            out,
            "| {} | {} | {} | {} | {} | {} | {} | {} |",
            r.embree,
            quality_name(r.quality),
            r.scene_flags,
            r.query.call(),
            r.query_flags,
            r.threads,
            three_digits(r.build_ms),
            three_digits(r.camera_mrays),
        );
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bench::meshes;

    #[test]
    fn tiles_put_every_pixel_once_and_packets_on_compact_blocks() {
        let scene = meshes::displaced_sphere(200);
        let (w, h) = (10, 6);
        let rays = tiled_camera_rays(&scene, w, h);
        let cam = Camera::new(&scene.camera, &scene.bounds, w, h);
        let mut pixels: Vec<(u32, u32)> = Vec::new();
        for r in &rays {
            let p = (0..h)
                .flat_map(|y| (0..w).map(move |x| (x, y)))
                .find(|&(x, y)| cam.generate_ray(x, y, Vec2::splat(0.5)) == *r)
                .expect("a pixel centre's ray");
            pixels.push(p);
        }
        let mut sorted = pixels.clone();
        sorted.sort();
        sorted.dedup();
        assert_eq!(sorted.len(), (w * h) as usize);
        // The first packet of 8 is the 4×2 block at the origin.
        let mut first8 = pixels[..8].to_vec();
        first8.sort();
        let block: Vec<(u32, u32)> = (0..4).flat_map(|x| (0..2).map(move |y| (x, y))).collect();
        assert_eq!(first8, block);
    }

    #[test]
    fn markdown_names_the_flags_of_each_row() {
        let row = EmbreeModeRow {
            embree: "Embree 4.4.0 (AVX2, native ray packets of 8)".into(),
            quality: EmbreeQuality::High,
            scene_flags: "NONE",
            query: RayQuery::Packet(8),
            query_flags: "INCOHERENT (default)",
            threads: 2,
            build_ms: 42.0,
            camera_mrays: 35.4,
        };
        let md = markdown(&[row]);
        assert!(
            md.contains("| high | NONE | rtcIntersect8 | INCOHERENT (default) | 2 | 42.0 | 35.4 |"),
            "{md}"
        );
    }

    #[cfg(any(feature = "embree", feature = "embree4"))]
    #[test]
    fn every_mode_gets_a_row() {
        let scene = meshes::displaced_sphere(2_000);
        let opts = EmbreeModesOptions {
            width: 32,
            height: 16,
            threads: 1,
            repeats: 1,
        };
        let rows = embree_modes(&scene, &opts).expect("Embree runs");
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
