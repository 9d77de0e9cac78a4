//! Light reaching a pixel in at most one bounce, sampled apart where it is noisy.
//!
//! Where a light's outline crosses a pixel, or a glossy surface reflects a light, a
//! pixel's camera rays land on light or beside it: a bright, all-or-nothing integrand
//! that dominates the linear error. Over the course's Cornell boxes at 64 spp, 60–70 %
//! of the noise² of `-m 5` lies in what `-m 1` computes (emission seen directly and
//! direct light at the first vertex), and nearly all of that in under 1 % of the
//! pixels (BENCHMARKS §3). Those samples cost a quarter of a path or less, so in such
//! pixels the driver splits the pixel's value in two unbiased parts: its path samples
//! count only light found after more bounces (`PixelSamples::min_bounces`), and
//! `factor` times as many samples of the shallow part alone, on a stream of their own,
//! estimate the rest.
//!
//! Which pixels qualify comes from a one-sample pilot of the shallow part, independent
//! of both: a pixel whose 3 × 3 neighbourhood's values spread (standard deviation of
//! their luminance) more than `SPREAD` times the frame's mean luminance, which a sparse
//! grid of the same pilot estimates. A pixel the pilot misses keeps the plain
//! estimator; either way each pixel's estimate is unbiased.
//!
//! Every decision is a function of the pixel, the frame and the seed, and the pilot
//! covers the rectangle grown by one pixel, so shards, cells, threads and lanes give
//! the full render's pixels bit for bit.

use super::adaptive::PixelStats;
use super::PixelRect;
use crate::color::luminance;
use crate::integrators::{PathIntegrator, PixelSamples, SampleIntegrator, Tracing};
use crate::lights::Light;
use crate::scene::Scene;
use crate::Color;
use rayon::prelude::*;

/// Mixed into the render's seed for the pilot's and the split samples' streams, so
/// they share no numbers with the pixel samples or each other.
const PILOT_SEED: u64 = 0x4544_4745_0001;
const SAMPLES_SEED: u64 = 0x4544_4745_0002;

/// Split samples per block handed to the integrator (bounds its buffers), and blocks
/// per parallel task.
const BLOCK: u32 = 256;
const PAR_BLOCKS: usize = 8;

/// Pilot pixels per parallel task.
const PAR_PIXELS: usize = 1024;

/// A pixel is split where its neighbourhood's pilot values spread more than this many
/// times the frame's mean: on CBbunny and CBbunny_microfacet_cu the marked set (and
/// the noise it removes) is the same from 4 to 16 (BENCHMARKS §3).
const SPREAD: f32 = 8.0;

/// The frame's mean comes from a grid of at most this many pixels across and down.
const GRID: u32 = 64;

/// Paths split at most this deep: emission seen directly and direct light at the
/// first vertex.
pub(super) const MAX_SPLIT_BOUNCES: u32 = 1;

/// The shallow estimators of a render, and how many of their samples a pixel sample
/// is worth.
pub(super) struct DirectSplit<'a> {
    pilot: PathIntegrator<'a>,
    samples: PathIntegrator<'a>,
    factor: u32,
    /// Split pixels' paths count light found after this many bounces or more.
    pub min_bounces: u32,
    /// Neighbourhoods whose pilot values' standard deviation exceeds this are split.
    threshold: f32,
    /// The camera's frame, width and height.
    frame: (u32, u32),
}

/// Which pixels of a rectangle are split.
pub(super) struct Marks {
    rect: PixelRect,
    marked: Vec<bool>,
}

impl Marks {
    /// How many pixels of `rect` are marked.
    pub fn count_in(&self, rect: PixelRect) -> u64 {
        rect.pixels().filter(|&p| self.get(p)).count() as u64
    }

    pub fn get(&self, p: (u32, u32)) -> bool {
        self.rect.contains(p) && self.marked[self.rect.index(p)]
    }
}

impl<'a> DirectSplit<'a> {
    /// For a render traced with `t`, splitting off light of at most `max_bounces`
    /// bounces (capped by the render's depth) with `factor` samples per pixel sample:
    /// `None` when there is nothing to split (factor 0, that light does not count at
    /// this depth, or a camera ray can see no emitter).
    pub fn new(t: Tracing<'a>, factor: u32, max_bounces: u32) -> Option<Self> {
        let depth = t.s.max_depth.min(max_bounces);
        let counted = t.s.accumulate || t.s.max_depth == depth;
        if factor == 0 || !counted || (depth == 0 && !has_visible_emitters(t.scene)) {
            return None;
        }
        let shallow = |seed: u64| {
            let mut s = t.s;
            (s.max_depth, s.caustics_by_light) = (depth, false);
            PathIntegrator::new(Tracing {
                s,
                seed: t.seed ^ seed,
                ..t
            })
        };
        let mut split = DirectSplit {
            pilot: shallow(PILOT_SEED),
            samples: shallow(SAMPLES_SEED),
            factor,
            min_bounces: depth + 1,
            threshold: 0.0,
            frame: (t.camera.width, t.camera.height),
        };
        split.threshold = SPREAD * split.frame_mean();
        Some(split)
    }

    /// The frame's mean luminance from the pilot on a grid of pixels (non-finite
    /// values left out).
    fn frame_mean(&self) -> f32 {
        let (w, h) = self.frame;
        let (sx, sy) = (w.div_ceil(GRID).max(1), h.div_ceil(GRID).max(1));
        let grid: Vec<(u32, u32)> = (0..h)
            .step_by(sy as usize)
            .flat_map(|y| (0..w).step_by(sx as usize).map(move |x| (x, y)))
            .collect();
        let (n, sum) = self
            .pilot_values(grid.into_iter())
            .into_iter()
            .filter(|v| v.is_finite())
            .fold((0u32, 0.0f64), |(n, sum), v| (n + 1, sum + f64::from(v)));
        (sum / f64::from(n.max(1))) as f32
    }

    /// The pixels of `rect` to split, as the pilot sees them.
    pub fn marks(&self, rect: PixelRect) -> Marks {
        let frame = self.frame;
        let halo = rect.grown(1, frame);
        let seen = self.pilot_values(halo.pixels());
        let at = |p: (u32, u32)| seen[halo.index(p)];
        let spread = |(x, y): (u32, u32)| {
            let own = PixelRect {
                x0: x,
                y0: y,
                x1: x + 1,
                y1: y + 1,
            };
            let (mut n, mut s1, mut s2) = (0.0, 0.0, 0.0);
            for v in own.grown(1, frame).pixels().map(|p| f64::from(at(p))) {
                (n, s1, s2) = (n + 1.0, s1 + v, s2 + v * v);
            }
            let mean = s1 / n;
            (s2 / n - mean * mean).max(0.0).sqrt() as f32
        };
        // A NaN spread (a non-finite pilot value) does not mark.
        let marked = rect.pixels().map(|p| spread(p) > self.threshold).collect();
        Marks { rect, marked }
    }

    /// One pilot sample per pixel of `pixels`: its luminance (in parallel, a chunk of
    /// pixels per task).
    fn pilot_values(&self, pixels: impl Iterator<Item = (u32, u32)>) -> Vec<f32> {
        let blocks: Vec<PixelSamples> = pixels
            .map(|(x, y)| PixelSamples {
                x,
                y,
                first: 0,
                count: 1,
                min_bounces: 0,
            })
            .collect();
        let mut seen = vec![0.0; blocks.len()];
        seen.par_chunks_mut(PAR_PIXELS)
            .zip(blocks.par_chunks(PAR_PIXELS))
            .for_each(|(seen, blocks)| {
                self.pilot
                    .render_blocks(blocks, &|| false, &mut |i, values| {
                        seen[i] = luminance(values[0].radiance)
                    })
            });
        seen
    }

    /// The shallow estimates of `pixels`, each `((x, y), first, count)` for its pixel
    /// samples `first .. first + count`: `factor` times as many samples, numbered
    /// alike. Per pixel their sum (non-finite samples count as black), how many there
    /// were, and how many were not finite.
    pub fn estimate(&self, pixels: &[((u32, u32), u32, u32)]) -> Vec<(Color, u32, u32)> {
        let mut blocks = Vec::new();
        let mut owner = Vec::new();
        for (k, &((x, y), first, count)) in pixels.iter().enumerate() {
            // Sample indices are 32-bit: near the top of their range fewer per sample
            // (any count is unbiased).
            let last = u64::from(first) + u64::from(count);
            let factor = u64::from(self.factor).min(u64::from(u32::MAX) / last.max(1));
            let (start, end) = ((u64::from(first) * factor) as u32, (last * factor) as u32);
            for f in (start..end).step_by(BLOCK as usize) {
                blocks.push(PixelSamples {
                    x,
                    y,
                    first: f,
                    count: BLOCK.min(end - f),
                    min_bounces: 0,
                });
                owner.push(k);
            }
        }
        let mut sums = vec![PixelStats::default(); blocks.len()];
        sums.par_chunks_mut(PAR_BLOCKS)
            .zip(blocks.par_chunks(PAR_BLOCKS))
            .for_each(|(sums, blocks)| {
                self.samples
                    .render_blocks(blocks, &|| false, &mut |b, values| {
                        values.iter().for_each(|v| sums[b].add_to_sum(v))
                    })
            });
        // Summed in block order, whatever order the blocks finished in.
        let mut out = vec![(Color::ZERO, 0u32, 0u32); pixels.len()];
        for (b, s) in owner.iter().zip(&sums) {
            let o = &mut out[*b];
            (o.0, o.1, o.2) = (o.0 + s.sum, o.1 + s.n, o.2 + s.nonfinite);
        }
        out
    }
}

/// Whether a camera ray can see an emitter: area lights, emissive materials, lights
/// at infinity.
fn has_visible_emitters(scene: &Scene) -> bool {
    scene
        .lights
        .iter()
        .any(|l| matches!(l, Light::Area(_)) || l.is_environment())
        || scene.materials.iter().any(|m| m.emits())
}
