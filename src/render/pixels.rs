//! The pixel loop: tiles over rayon, each tile's pixel samples handed to a
//! [`SampleIntegrator`] as blocks, summed per pixel in sample order; a fixed count
//! per pixel, or adaptive sampling (`adaptive.rs`'s rule) in batches.

use super::adaptive::NEIGHBOUR_RADIUS;
use super::adaptive::{may_stop, min_samples_if_zero, neighbour_hit_rates, PixelStats};
use super::split::{DirectSplit, Marks};
use super::{Adaptive, PixelRect, RenderOutput, RenderSettings, StopRule, StopToken};
use crate::film::Image;
use crate::integrators::{PixelSamples, SampleIntegrator};
use rayon::prelude::*;

/// Tiles are `TILE × TILE` pixels.
pub(super) const TILE: u32 = 16;

/// Pixel samples and the split samples of the pixels `marks` holds.
#[derive(Clone, Copy)]
struct Sampling<'s, 'a> {
    integrator: &'s dyn SampleIntegrator,
    split: Option<(&'s DirectSplit<'a>, &'s Marks)>,
}

impl Sampling<'_, '_> {
    /// Samples `first .. first + count` of pixel `p`.
    fn block(&self, p: (u32, u32), first: u32, count: u32) -> PixelSamples {
        let min_bounces = match self.split {
            Some((split, marks)) if marks.get(p) => split.min_bounces,
            _ => 0,
        };
        PixelSamples {
            x: p.0,
            y: p.1,
            first,
            count,
            min_bounces,
        }
    }

    /// Gives the marked pixels of `rect` (`stats` in its row-major order) split
    /// samples for the samples they have (numbered from `first`) beyond those their
    /// split samples cover already: `factor` per sample.
    fn add_split(&self, rect: PixelRect, stats: &mut [PixelStats], first: u32) {
        let Some((split, marks)) = self.split else {
            return;
        };
        let pixels: Vec<(u32, u32)> = rect.pixels().collect();
        let todo: Vec<usize> = (0..pixels.len())
            .filter(|&i| marks.get(pixels[i]) && stats[i].n > stats[i].split.covers)
            .collect();
        if todo.is_empty() {
            return;
        }
        let asked: Vec<_> = todo
            .iter()
            .map(|&i| {
                let (covers, n) = (stats[i].split.covers, stats[i].n);
                (pixels[i], first + covers, n - covers)
            })
            .collect();
        for (&i, (sum, n, bad)) in todo.iter().zip(split.estimate(&asked)) {
            let s = &mut stats[i];
            (s.split.sum, s.split.n) = (s.split.sum + sum, s.split.n + n);
            s.split.covers = s.n;
            s.nonfinite += bad;
        }
    }
}

/// Renders pixels `rect` with `integrator`: `settings.spp` samples per pixel from
/// `settings.spp_offset`, or adaptively; with `split`, light of few bounces apart
/// where it is noisy (`split.rs`). `progress` is called with the number of pixels
/// finished; once `stop` says so, pixels not started are left black with 0 samples.
#[allow(clippy::too_many_arguments)]
pub(super) fn render(
    integrator: &dyn SampleIntegrator,
    split: Option<&DirectSplit>,
    settings: &RenderSettings,
    adaptive: Option<Adaptive>,
    frame: (u32, u32),
    rect: PixelRect,
    progress: &(dyn Fn(u64) + Sync),
    stop: &StopToken,
) -> RenderOutput {
    let spp = settings.spp.max(1);
    // Adaptive sampling's first batch covers its halo, whose pixels need their marks.
    let marked_rect = adaptive.map_or(rect, |a| halo(a, frame, rect));
    let marks = split.map(|s| s.marks(marked_rect));
    let s = Sampling {
        integrator,
        split: split.zip(marks.as_ref()),
    };
    let stats = match adaptive {
        None => fixed(s, spp, settings.spp_offset, false, rect, progress, stop),
        Some(a) => adaptively(s, spp, a, frame, rect, progress, stop),
    };
    let split_pixels = marks.map_or(0, |m| m.count_in(rect));
    let mut image = Image::new(rect.width(), rect.height());
    for (px, p) in image.pixels.iter_mut().zip(&stats) {
        *px = p.mean();
    }
    RenderOutput {
        image,
        samples: stats.iter().map(|p| p.n).collect(),
        nonfinite_samples: stats.iter().map(|p| p.nonfinite as u64).sum(),
        split_pixels,
    }
}

/// Every pixel of `rect`, `spp` samples from `first`: each pixel's statistics (all
/// of them when `stats`, else only the sum), in the rectangle's row-major order.
fn fixed(
    sampling: Sampling,
    spp: u32,
    first: u32,
    stats: bool,
    rect: PixelRect,
    progress: &(dyn Fn(u64) + Sync),
    stop: &StopToken,
) -> Vec<PixelStats> {
    let tiles = tiles(rect);
    // Every tile's slot is allocated up front, so memory does not grow while rendering.
    let mut by_tile = vec![PixelStats::default(); tiles.len() * (TILE * TILE) as usize];
    by_tile
        .par_chunks_mut((TILE * TILE) as usize)
        .zip(tiles.par_iter())
        .for_each(|(pixels, &tile)| {
            let coords: Vec<(u32, u32)> = tile_pixels(rect, tile).collect();
            let blocks: Vec<PixelSamples> = coords
                .iter()
                .map(|&p| sampling.block(p, first, spp))
                .collect();
            let mut n = 0;
            let stopping = &|| stop.should_stop();
            sampling
                .integrator
                .render_blocks(&blocks, stopping, &mut |i, values| {
                    let p = &mut pixels[i];
                    match stats {
                        true => values.iter().for_each(|v| p.add_sample(v)),
                        false => values.iter().for_each(|v| p.add_to_sum(v)),
                    }
                    n += 1;
                });
            progress(n);
        });
    let mut out = in_rect_order(rect, &tiles, &by_tile);
    if !stats {
        // Apart from the tiles, spread over the threads: the split pixels crowd into
        // a few tiles (a light's outline, a highlight).
        sampling.add_split(rect, &mut out, first);
    }
    out
}

/// Adaptive sampling of `rect` in batches, up to `spp` per pixel: a first batch (the
/// pilot) over the rectangle grown by `NEIGHBOUR_RADIUS` (within the `frame`, so a
/// rectangle is exactly the crop of the full image) gives each pixel its neighbours'
/// rate of finding light; then each tile samples its pixels a batch at a time until
/// `may_stop` lets each go.
fn adaptively(
    sampling: Sampling,
    spp: u32,
    a: Adaptive,
    frame: (u32, u32),
    rect: PixelRect,
    progress: &(dyn Fn(u64) + Sync),
    stop: &StopToken,
) -> Vec<PixelStats> {
    let halo = halo(a, frame, rect);
    let r = neighbour_radius(a);
    let batch = a.batch.min(spp);
    let mut pilot = fixed(sampling, batch, 0, true, halo, &|_| {}, stop);
    // Before the stopping rule reads the pixels' means: `factor` per sample of the
    // first batch.
    sampling.add_split(halo, &mut pilot, 0);
    let min_if_zero: Vec<u32> = neighbour_hit_rates(&pilot, halo.width(), halo.height(), r)
        .into_iter()
        .map(min_samples_if_zero)
        .collect();
    let at = |p: (u32, u32)| halo.index(p);
    let tiles = tiles(rect);
    let mut by_tile = vec![PixelStats::default(); tiles.len() * (TILE * TILE) as usize];
    by_tile
        .par_chunks_mut((TILE * TILE) as usize)
        .zip(tiles.par_iter())
        .for_each(|(stats, &tile)| {
            let pixels: Vec<(u32, u32)> = tile_pixels(rect, tile).collect();
            for (s, &p) in stats.iter_mut().zip(&pixels) {
                *s = pilot[at(p)];
            }
            loop {
                // Once stopped, a pixel keeps the samples it has.
                let active: Vec<usize> = (0..pixels.len())
                    .filter(|&i| {
                        let p = &stats[i];
                        p.n < spp && !may_stop(p, min_if_zero[at(pixels[i])], a)
                    })
                    .collect();
                if active.is_empty() || stop.should_stop() {
                    break;
                }
                let blocks: Vec<PixelSamples> = active
                    .iter()
                    .map(|&i| sampling.block(pixels[i], stats[i].n, batch.min(spp - stats[i].n)))
                    .collect();
                let stopping = &|| stop.should_stop();
                sampling
                    .integrator
                    .render_blocks(&blocks, stopping, &mut |k, values| {
                        values.iter().for_each(|v| stats[active[k]].add_sample(v));
                    });
            }
            progress(pixels.len() as u64);
        });
    let mut out = in_rect_order(rect, &tiles, &by_tile);
    // Pixels that went on past the first batch: split samples for the rest too, so a
    // pixel that ran to the cap is the fixed-count render's.
    sampling.add_split(rect, &mut out, 0);
    out
}

/// How far adaptive sampling's stopping rule looks for neighbours.
fn neighbour_radius(a: Adaptive) -> u32 {
    match a.rule {
        StopRule::Neighbourhood => NEIGHBOUR_RADIUS,
        StopRule::PerPixel => 0,
    }
}

/// `rect` grown by the neighbour radius, within the frame: the pixels adaptive
/// sampling's first batch covers.
fn halo(a: Adaptive, frame: (u32, u32), rect: PixelRect) -> PixelRect {
    rect.grown(neighbour_radius(a), frame)
}

/// The tiles covering `rect`, as their top-left pixels, in a scattered order: every
/// stretch of the list samples the whole image, so progress (and its ETA) measured in
/// pixels tracks the work, and a stopped render is spread over the frame, not
/// a band of background at the top. The image does not depend on the order.
fn tiles(rect: PixelRect) -> Vec<(u32, u32)> {
    let rows: Vec<(u32, u32)> = (rect.y0..rect.y1)
        .step_by(TILE as usize)
        .flat_map(|y| {
            (rect.x0..rect.x1)
                .step_by(TILE as usize)
                .map(move |x| (x, y))
        })
        .collect();
    scattered(rows.len()).map(|i| rows[i]).collect()
}

/// `0..n` in a scattered order (every index once).
fn scattered(n: usize) -> impl Iterator<Item = usize> {
    let stride = scatter_stride(n);
    (0..n).map(move |i| i * stride % n)
}

/// A step near `n / φ` with no factor in common with `n`, so `i · step mod n` visits
/// every index once, jumping across the image.
fn scatter_stride(n: usize) -> usize {
    let gcd = |mut a: usize, mut b: usize| {
        while b != 0 {
            (a, b) = (b, a % b);
        }
        a
    };
    (((n as f64) * 0.618_034) as usize..n.max(1))
        .find(|&s| s > 0 && gcd(s, n) == 1)
        .unwrap_or(1)
}

/// The pixels of the tile at `(x0, y0)` inside `rect`, row by row.
fn tile_pixels(rect: PixelRect, (x0, y0): (u32, u32)) -> impl Iterator<Item = (u32, u32)> {
    (y0..(y0 + TILE).min(rect.y1))
        .flat_map(move |y| (x0..(x0 + TILE).min(rect.x1)).map(move |x| (x, y)))
}

/// The tiles' pixel statistics in `rect`'s row-major order.
fn in_rect_order(rect: PixelRect, tiles: &[(u32, u32)], by_tile: &[PixelStats]) -> Vec<PixelStats> {
    let mut out = vec![PixelStats::default(); rect.area() as usize];
    for (&tile, stats) in tiles.iter().zip(by_tile.chunks((TILE * TILE) as usize)) {
        for ((x, y), p) in tile_pixels(rect, tile).zip(stats) {
            out[rect.index((x, y))] = *p;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scattered_tiles_cover_every_tile_once_and_jump_across_the_image() {
        for (w, h) in [(1, 1), (16, 16), (480, 360), (100, 37)] {
            let rect = PixelRect::full(w, h);
            let t = tiles(rect);
            let mut sorted = t.clone();
            sorted.sort_unstable();
            sorted.dedup();
            assert_eq!(sorted.len(), t.len());
            assert_eq!(t.len() as u32, w.div_ceil(TILE) * h.div_ceil(TILE));
        }
        // The first tenth of a 480x360 frame's tiles reaches its bottom half.
        let t = tiles(PixelRect::full(480, 360));
        assert!(t[..t.len() / 10].iter().any(|&(_, y)| y >= 180));
    }
}
