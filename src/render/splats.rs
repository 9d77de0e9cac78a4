//! The loop of adjoint integrators: `spp·W·H` light paths over the whole image (a
//! light path lands anywhere), traced a chunk at a time in parallel, their splats
//! added chunk by chunk in order, so the image depends on the seed only; plus what
//! only camera rays see, from the integrator's camera part.

use super::split::DirectSplit;
use super::{pixels, PixelRect, RenderOutput, RenderSettings, StopToken};
use crate::camera::Camera;
use crate::film::Image;
use crate::integrators::light_tracing::CHUNK_PATHS;
use crate::integrators::{Splat, SplatIntegrator};
use crate::Color;
use glam::DVec3;
use rayon::prelude::*;
use std::ops::Range;

/// Chunks traced in parallel before their splats are added (bounds memory: two
/// groups' splats are held at once).
const CHUNKS_PER_GROUP: u64 = 64;

/// Pixels in `camera`'s image.
pub(super) fn pixel_count(camera: &Camera) -> u64 {
    u64::from(camera.width) * u64::from(camera.height)
}

/// The light paths of `spp` per pixel, numbered from 0 (light tracing's render).
pub(super) fn paths_per_pixel(camera: &Camera, spp: u32) -> Range<u64> {
    0..u64::from(spp) * pixel_count(camera)
}

/// Renders pixels `rect` from light paths `paths` (numbered over the whole render):
/// the splats inside `rect` are kept, so a rectangle is exactly the crop of the full
/// image, at the cost of tracing every path (one full frame's work per rectangle).
/// The image is the splats' sum over the paths traced per pixel, so disjoint ranges
/// of paths average, weighted by their lengths, to the render of all of them.
/// `camera_split`: where the camera part samples emitters seen directly apart.
pub(super) fn render(
    tracer: &dyn SplatIntegrator,
    camera_split: Option<&DirectSplit>,
    camera: &Camera,
    paths: Range<u64>,
    rect: PixelRect,
    progress: &(dyn Fn(u64) + Sync),
    stop: &StopToken,
) -> RenderOutput {
    let npix = pixel_count(camera);
    // Chunks are CHUNK_PATHS-aligned, so a path's chunk does not depend on the range.
    let first_chunk = paths.start / CHUNK_PATHS;
    let end_chunk = match paths.is_empty() {
        true => first_chunk,
        false => paths.end.div_ceil(CHUNK_PATHS),
    };
    let span = |c: u64| (c * CHUNK_PATHS).max(paths.start)..((c + 1) * CHUNK_PATHS).min(paths.end);
    let chunks = end_chunk - first_chunk;
    let (rw, rh) = (rect.width(), rect.height());
    // In f64: a bright pixel takes millions of near-equal splats, and an f32 sum
    // rounds each the same way (CBempty's hot spot came out 3.5 % dark at 4096 spp).
    let mut sum = vec![DVec3::ZERO; rect.area() as usize];
    let mut nonfinite = 0u64;
    let done = |c: u64| c * rect.area() / chunks.max(1);
    let trace = |chunk: u64, mut splats: Vec<Splat>| {
        splats.clear();
        let r = span(chunk);
        let bad = tracer.trace_paths(r.start, r.end - r.start, &mut splats);
        let k = chunk - first_chunk;
        progress(done(k + 1) - done(k));
        (splats, bad)
    };
    // A group's splats are added while the next group is traced (the adding is one
    // thread's work, in order); their buffers then serve the group after.
    let mut add = |traced: Vec<(Vec<Splat>, u32)>| {
        let mut emptied = Vec::with_capacity(traced.len());
        for (splats, bad) in traced {
            nonfinite += bad as u64;
            for &(x, y, v) in &splats {
                if rect.contains((x, y)) {
                    sum[rect.index((x, y))] += v.as_dvec3();
                }
            }
            emptied.push(splats);
        }
        emptied
    };
    let mut spare: Vec<Vec<Splat>> = Vec::new();
    let mut pending = Vec::new();
    let mut group = first_chunk;
    while group < end_chunk && !stop.should_stop() {
        let end = (group + CHUNKS_PER_GROUP).min(end_chunk);
        let buffers: Vec<Vec<Splat>> = (group..end)
            .map(|_| spare.pop().unwrap_or_default())
            .collect();
        let (emptied, traced) = rayon::join(
            || add(std::mem::take(&mut pending)),
            || {
                (buffers.into_par_iter().enumerate())
                    .map(|(k, b)| trace(group + k as u64, b))
                    .collect::<Vec<_>>()
            },
        );
        spare.extend(emptied);
        pending = traced;
        group = end;
    }
    add(pending);
    // A stopped render divides by the paths it traced (the range's length when
    // complete), and sees emitters directly with as many camera samples.
    let traced = (group * CHUNK_PATHS).clamp(paths.start, paths.end) - paths.start;
    let per_pixel = traced as f64 / npix as f64;
    let spp = per_pixel.ceil() as u32;
    let mut image = Image::new(rw, rh);
    for (p, s) in image.pixels.iter_mut().zip(&sum) {
        *p = if traced == 0 {
            Color::ZERO
        } else {
            (*s / per_pixel).as_vec3()
        };
    }
    let mut split_pixels = 0;
    if let (Some(direct), true) = (tracer.camera_part(), spp > 0) {
        let settings = RenderSettings {
            spp,
            ..RenderSettings::default()
        };
        let frame = (camera.width, camera.height);
        let seen = pixels::render(
            direct,
            camera_split,
            &settings,
            None,
            frame,
            rect,
            &|_| {},
            stop,
        );
        for (p, d) in image.pixels.iter_mut().zip(&seen.image.pixels) {
            *p += *d;
        }
        nonfinite += seen.nonfinite_samples;
        split_pixels = seen.split_pixels;
    }
    RenderOutput {
        image,
        samples: vec![spp; rect.area() as usize],
        nonfinite_samples: nonfinite,
        split_pixels,
    }
}
