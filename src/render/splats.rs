//! The loop of adjoint integrators: `spp·W·H` light paths over the whole image (a
//! light path lands anywhere), traced a chunk at a time in parallel, their splats
//! added chunk by chunk in order, so the image depends on the seed only; plus what
//! only camera rays see, from the integrator's camera part.

use super::{pixels, PixelRect, RenderOutput, RenderSettings, StopToken};
use crate::camera::Camera;
use crate::film::Image;
use crate::integrators::light_tracing::CHUNK_PATHS;
use crate::integrators::{Splat, SplatIntegrator};
use crate::Color;
use rayon::prelude::*;

/// Chunks traced in parallel before their splats are added (bounds memory).
const CHUNKS_PER_GROUP: u64 = 64;

/// Renders pixels `rect`: the splats inside it are kept, so a rectangle is exactly the
/// crop of the full image, at the cost of tracing every path (one full frame's work
/// per rectangle).
pub(super) fn render(
    tracer: &dyn SplatIntegrator,
    camera: &Camera,
    spp: u32,
    rect: PixelRect,
    progress: &(dyn Fn(u64) + Sync),
    stop: &StopToken,
) -> RenderOutput {
    let npix = camera.width as u64 * camera.height as u64;
    let total = spp as u64 * npix;
    let chunks = total.div_ceil(CHUNK_PATHS);
    let (rw, rh) = (rect.width(), rect.height());
    let mut sum = vec![Color::ZERO; rect.area() as usize];
    let mut nonfinite = 0u64;
    let done = |c: u64| c * rect.area() / chunks.max(1);
    let mut group = 0;
    while group < chunks && !stop.should_stop() {
        let end = (group + CHUNKS_PER_GROUP).min(chunks);
        let results: Vec<(Vec<Splat>, u32)> = (group..end)
            .into_par_iter()
            .map(|c| {
                let mut splats = Vec::new();
                let first = c * CHUNK_PATHS;
                let bad = tracer.trace_paths(first, CHUNK_PATHS.min(total - first), &mut splats);
                progress(done(c + 1) - done(c));
                (splats, bad)
            })
            .collect();
        for (splats, bad) in results {
            nonfinite += bad as u64;
            for (x, y, v) in splats {
                if (rect.x0..rect.x1).contains(&x) && (rect.y0..rect.y1).contains(&y) {
                    sum[((y - rect.y0) * rw + (x - rect.x0)) as usize] += v;
                }
            }
        }
        group = end;
    }
    // A stopped render divides by the paths it traced (`spp · pixels` when complete),
    // and sees emitters directly with as many camera samples.
    let traced = (group * CHUNK_PATHS).min(total);
    let per_pixel = traced as f64 / npix as f64;
    let spp = per_pixel.ceil() as u32;
    let mut image = Image::new(rw, rh);
    for (p, s) in image.pixels.iter_mut().zip(&sum) {
        *p = if traced == 0 {
            Color::ZERO
        } else {
            *s / per_pixel as f32
        };
    }
    if let (Some(direct), true) = (tracer.camera_part(), spp > 0) {
        let settings = RenderSettings {
            spp,
            ..RenderSettings::default()
        };
        let frame = (camera.width, camera.height);
        let seen = pixels::render(direct, &settings, None, frame, rect, &|_| {}, stop);
        for (p, d) in image.pixels.iter_mut().zip(&seen.image.pixels) {
            *p += *d;
        }
        nonfinite += seen.nonfinite_samples;
    }
    RenderOutput {
        image,
        samples: vec![spp; rect.area() as usize],
        nonfinite_samples: nonfinite,
    }
}
