//! A render as a sequence of passes, each a few samples over every pixel, summed in
//! a [`Film`]: for a time budget (`--time`), periodic checkpoints (`--checkpoint`),
//! and stopping with a whole image of fewer samples rather than missing tiles.
//!
//! Pass `k` takes [`pass_spp`]`(k)` samples per pixel with its own seed
//! ([`pass_seed`]), so the film after `n` passes is the same for a given seed
//! whatever the thread count or how long each pass took; the passes done are recorded.

use super::{PixelRect, RenderJob, RenderOutput, RenderSettings, Shading, StopReason, StopToken};
use crate::film::Image;
use crate::Color;

/// Samples per pixel of pass `k`: 1, 1, 2, 4, 8, 16, 16, ... A full noisy image
/// comes at once; later passes are long enough that their overhead is nothing,
/// and short enough that checkpoints come often.
pub fn pass_spp(k: u32) -> u32 {
    match k {
        0 => 1,
        k => 1 << (k - 1).min(4),
    }
}

/// The seed of pass `k`: pass 0 keeps the render's seed, later passes use independent
/// streams derived from it (a render of one pass is the plain render of that seed).
pub fn pass_seed(seed: u64, k: u32) -> u64 {
    if k == 0 {
        return seed;
    }
    let mut z = seed ^ (k as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Per-pixel sums of radiance and sample counts over the passes so far.
pub struct Film {
    pub width: u32,
    pub height: u32,
    sum: Vec<Color>,
    samples: Vec<u32>,
    nonfinite: u64,
    split_pixels: u64,
    /// Passes completed (a stopped pass is not counted, though its finished pixels are kept).
    pub passes: u32,
}

impl Film {
    /// The whole film, allocated up front.
    pub fn new(width: u32, height: u32) -> Self {
        let n = width as usize * height as usize;
        Film {
            width,
            height,
            sum: vec![Color::ZERO; n],
            samples: vec![0; n],
            nonfinite: 0,
            split_pixels: 0,
            passes: 0,
        }
    }

    /// Adds one pass's pixels (each weighted by its own sample count).
    fn add(&mut self, pass: &RenderOutput) {
        let pixels = pass.image.pixels.iter().zip(&pass.samples);
        for ((sum, n), (v, &k)) in self.sum.iter_mut().zip(&mut self.samples).zip(pixels) {
            *sum += *v * k as f32;
            *n += k;
        }
        self.nonfinite += pass.nonfinite_samples;
        self.split_pixels = self.split_pixels.max(pass.split_pixels);
    }

    /// Samples per pixel so far.
    pub fn samples(&self) -> &[u32] {
        &self.samples
    }

    /// The mean of each pixel's samples (black where there are none).
    pub fn image(&self) -> Image {
        let pixels = self
            .sum
            .iter()
            .zip(&self.samples)
            .map(|(s, &n)| if n == 0 { Color::ZERO } else { *s / n as f32 })
            .collect();
        Image {
            width: self.width,
            height: self.height,
            pixels,
        }
    }

    /// The film as a render's output.
    pub fn output(&self) -> RenderOutput {
        RenderOutput {
            image: self.image(),
            samples: self.samples.clone(),
            nonfinite_samples: self.nonfinite,
            split_pixels: self.split_pixels,
        }
    }
}

/// Renders passes over `rect` until every pixel has `settings.spp` samples or `stop`
/// says so, and returns the film with the reason it stopped early, if it did.
/// `after_pass` sees the film after each complete pass (for checkpoints); an error
/// from it ends the render. `progress` counts samples (pixels × pass samples).
/// Adaptive sampling and `Shading::BvhCost` (a heat map, not a mean) are single-pass only.
pub fn render_passes<E>(
    job: &RenderJob,
    settings: &RenderSettings,
    rect: PixelRect,
    progress: &(dyn Fn(u64) + Sync),
    stop: &StopToken,
    after_pass: &mut dyn FnMut(&Film) -> Result<(), E>,
) -> Result<(Film, Option<StopReason>), E> {
    assert!(
        settings.adaptive.is_none() && settings.shading != Shading::BvhCost,
        "render_passes: adaptive sampling and bvh-cost render in one pass"
    );
    let mut film = Film::new(rect.width(), rect.height());
    let mut done = 0u32;
    for k in 0.. {
        if done >= settings.spp {
            return Ok((film, None));
        }
        let spp = pass_spp(k).min(settings.spp - done);
        let pass = RenderSettings {
            spp,
            seed: pass_seed(settings.seed, k),
            ..settings.clone()
        };
        let out = job.render_rect_until(&pass, rect, &|n| progress(n * spp as u64), stop);
        film.add(&out);
        let complete = out.samples.iter().all(|&n| n == spp);
        if complete {
            film.passes += 1;
            done += spp;
        }
        match stop.reason() {
            Some(reason) if done < settings.spp => return Ok((film, Some(reason))),
            _ if complete => after_pass(&film)?,
            _ => {}
        }
    }
    unreachable!("the pass loop returns")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pass_sizes_sum_to_any_spp() {
        let total: u32 = (0..6).map(pass_spp).sum();
        assert_eq!(total, 1 + 1 + 2 + 4 + 8 + 16);
        assert_eq!(pass_spp(40), 16);
        assert_eq!(pass_seed(7, 0), 7);
        assert_ne!(pass_seed(7, 1), pass_seed(7, 2));
    }
}
