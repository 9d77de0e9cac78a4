//! Budgets and statistics shared by the stability cases; the renders, and their two
//! independent halves, come from `RenderJob`.

use crate::accel::{AccelKind, BvhBuilder};
use crate::color::luminance;
use crate::film::Image;
pub use crate::render::Halves;
use crate::render::{RenderJob, RenderSettings};
use crate::scene::Scene;
use anyhow::Result;

/// Image size, samples per pixel and seed of one case's renders.
#[derive(Clone, Copy, Debug)]
pub struct Budget {
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    pub seed: u64,
}

impl Budget {
    /// Settings of this budget for the rest of `base`.
    pub fn settings(&self, base: RenderSettings) -> RenderSettings {
        RenderSettings {
            spp: self.spp,
            seed: self.seed,
            ..base
        }
    }

    /// `scene` through the native BVH, seen by its own camera at this budget's image size.
    pub fn job(&self, scene: Scene) -> Result<RenderJob> {
        Ok(RenderJob::new(scene, NATIVE, self.width, self.height)?)
    }
}

/// The backend every stability case renders with.
pub const NATIVE: AccelKind = AccelKind::Native(BvhBuilder::Sah);

#[inline]
pub fn lum(img: &Image, i: usize) -> f64 {
    luminance(img.pixels[i]) as f64
}

/// Luminance mean of `img` over `pixels`.
pub fn mean_over(img: &Image, pixels: &[usize]) -> f64 {
    pixels.iter().map(|&i| lum(img, i)).sum::<f64>() / pixels.len().max(1) as f64
}

/// Pixels of a `w × h` image within `r` pixels (Chebyshev) of `(x, y)`.
pub fn block_around(w: u32, h: u32, (x, y): (u32, u32), r: u32) -> Vec<usize> {
    let mut v = Vec::new();
    for j in y.saturating_sub(r)..=(y + r).min(h - 1) {
        for i in x.saturating_sub(r)..=(x + r).min(w - 1) {
            v.push((j * w + i) as usize);
        }
    }
    v
}

/// How many standard errors apart two independent estimates are.
pub fn z_score(a: (f64, f64), b: (f64, f64)) -> f64 {
    let se = (a.1 * a.1 + b.1 * b.1).sqrt();
    if se > 0.0 {
        (a.0 - b.0).abs() / se
    } else if a.0 == b.0 {
        0.0
    } else {
        f64::INFINITY
    }
}
