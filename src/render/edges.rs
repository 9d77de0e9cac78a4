//! Emitters seen directly, sampled apart where their edges cross pixels.
//!
//! A pixel that a light's outline crosses is partly light and partly what lies beside
//! it, and its camera rays land on one or the other: a bright, all-or-nothing
//! integrand that dominates the linear error of a diffuse Cornell box (63 % of
//! CBbunny's noise² at 64 spp sits in the 1 % of pixels on the light's silhouette;
//! BENCHMARKS §3). Camera rays that only look for emitters cost about a sixth of a
//! path, so in such pixels the driver splits the pixel's value in two unbiased parts:
//! its path samples leave out emission seen directly, and `factor` times as many
//! emitter-only samples (`-m 0`, a stream of their own) estimate it. Which pixels
//! qualify comes from a one-sample pilot, independent of both: a pixel whose 3 × 3
//! neighbourhood saw different emission from surfaces. A pixel the pilot misses keeps
//! the plain estimator; either way each pixel's estimate is unbiased.
//!
//! Every decision is a function of the pixel and the seed, and the pilot covers the
//! rectangle grown by one pixel, so shards, cells, threads and lanes give the full
//! render's pixels bit for bit.

use super::adaptive::PixelStats;
use super::PixelRect;
use crate::integrators::{PathIntegrator, PixelSamples, SampleIntegrator, Tracing};
use crate::lights::Light;
use crate::scene::Scene;
use crate::Color;

/// Mixed into the render's seed for the pilot's and the emitter samples' streams, so
/// they share no numbers with the pixel samples or each other.
const PILOT_SEED: u64 = 0x4544_4745_0001;
const SAMPLES_SEED: u64 = 0x4544_4745_0002;

/// Emitter-only samples per block handed to the integrator (bounds its buffers).
const BLOCK: u32 = 256;

/// The emitter-only estimators of a render, and how many of their samples a pixel
/// sample is worth.
pub(super) struct EmitterEdges<'a> {
    pilot: PathIntegrator<'a>,
    samples: PathIntegrator<'a>,
    factor: u32,
}

/// Which pixels of a rectangle take emitter-only samples.
pub(super) struct Marks {
    rect: PixelRect,
    marked: Vec<bool>,
}

impl Marks {
    /// How many pixels of `rect` are marked.
    pub fn count_in(&self, rect: PixelRect) -> u64 {
        rect.pixels().filter(|&p| self.get(p)).count() as u64
    }

    pub fn get(&self, (x, y): (u32, u32)) -> bool {
        let r = self.rect;
        (r.x0..r.x1).contains(&x)
            && (r.y0..r.y1).contains(&y)
            && self.marked[((y - r.y0) * r.width() + (x - r.x0)) as usize]
    }
}

impl<'a> EmitterEdges<'a> {
    /// For a render traced with `t` and `factor` emitter samples per pixel sample:
    /// `None` when there is nothing to split (factor 0, no surface emitter, or
    /// emission seen directly does not count at this depth).
    pub fn new(t: Tracing<'a>, factor: u32) -> Option<Self> {
        let counts_zero = t.s.accumulate || t.s.max_depth == 0;
        if factor == 0 || !counts_zero || !has_surface_emitters(t.scene) {
            return None;
        }
        let emitters_only = |seed: u64| {
            let mut s = t.s;
            (s.max_depth, s.accumulate, s.caustics_by_light) = (0, true, false);
            PathIntegrator::new(Tracing {
                s,
                seed: t.seed ^ seed,
                ..t
            })
        };
        Some(EmitterEdges {
            pilot: emitters_only(PILOT_SEED),
            samples: emitters_only(SAMPLES_SEED),
            factor,
        })
    }

    /// The pixels of `rect` (within the `frame`) that an emitter's edge crosses, as
    /// the pilot sees it.
    pub fn marks(&self, frame: (u32, u32), rect: PixelRect) -> Marks {
        let halo = rect.grown(1, frame);
        let seen = self.pilot_values(halo);
        let at = |(x, y): (u32, u32)| seen[((y - halo.y0) * halo.width() + (x - halo.x0)) as usize];
        let differs = |(x, y): (u32, u32)| {
            let own = PixelRect {
                x0: x,
                y0: y,
                x1: x + 1,
                y1: y + 1,
            };
            own.grown(1, frame).pixels().any(|n| at(n) != at((x, y)))
        };
        let marked = rect.pixels().map(differs).collect();
        Marks { rect, marked }
    }

    /// One pilot sample per pixel of `rect`: the emission it saw on a surface (escaped
    /// rays count as none, so an environment map does not mark the whole frame).
    fn pilot_values(&self, rect: PixelRect) -> Vec<[u32; 3]> {
        let blocks: Vec<PixelSamples> = rect
            .pixels()
            .map(|(x, y)| PixelSamples {
                x,
                y,
                first: 0,
                count: 1,
                camera_emission: true,
            })
            .collect();
        let mut seen = vec![[0; 3]; blocks.len()];
        self.pilot
            .render_blocks(&blocks, &|| false, &mut |i, values| {
                let v = values[0];
                let c = if v.met_surface {
                    v.radiance
                } else {
                    Color::ZERO
                };
                seen[i] = [c.x.to_bits(), c.y.to_bits(), c.z.to_bits()];
            });
        seen
    }

    /// The emitter-only estimates of `pixels`, each `((x, y), first, count)` for its
    /// pixel samples `first .. first + count`: `factor` times as many samples, numbered
    /// alike. Per pixel the mean (non-finite samples count as black) and how many
    /// were not finite.
    pub fn estimate(&self, pixels: &[((u32, u32), u32, u32)]) -> Vec<(Color, u32)> {
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
                    camera_emission: true,
                });
                owner.push(k);
            }
        }
        let mut sums = vec![PixelStats::default(); blocks.len()];
        self.samples
            .render_blocks(&blocks, &|| false, &mut |b, values| {
                values.iter().for_each(|v| sums[b].add_to_sum(v))
            });
        // Summed in block order, whatever order the blocks finished in.
        let mut out = vec![(Color::ZERO, 0u32, 0u32); pixels.len()];
        for (b, s) in owner.iter().zip(&sums) {
            let o = &mut out[*b];
            (o.0, o.1, o.2) = (o.0 + s.sum, o.1 + s.n, o.2 + s.nonfinite);
        }
        out.into_iter()
            .map(|(sum, n, bad)| (sum / n.max(1) as f32, bad))
            .collect()
    }
}

/// Emitters that are surfaces: area lights and emissive materials.
fn has_surface_emitters(scene: &Scene) -> bool {
    scene.lights.iter().any(|l| matches!(l, Light::Area(_)))
        || scene.materials.iter().any(|m| m.emits())
}
