//! Adaptive sampling (`-a BATCH TOL`, spec §7) with a stopping rule that does not
//! stop on light it has not seen yet.
//!
//! The course's rule stops a pixel once `1.96·σ/√n ≤ TOL·μ`. A pixel whose samples
//! are all equal (σ = 0) passes it at once, although zero variance after `n` samples is
//! just what a light found with probability ~3/n per sample produces (the "rule of
//! three"); such a light needs about `(1.96/TOL)²·n/3 ≫ n` samples to meet the rule,
//! so a pixel of zeros cannot be called converged on its own evidence. It needs its
//! neighbours': such a pixel stops only when every pixel within `QUIET_RADIUS` was
//! constant too after a first batch (a pilot pass over the whole image). A pixel
//! constant at a non-zero value (an emitter seen directly) stops after
//! `min_samples_if_constant`; any other pixel follows the course's rule after every
//! batch, up to the `-s` cap.
//!
//! Sample `i` of a pixel draws from its own stream (`Sampler::for_sample`), as without
//! `-a`, so the pilot batch is the first samples of the fixed-count render and images
//! depend on the seed only.

use crate::color::{is_finite, luminance};
use crate::film::Image;
use crate::integrators::PathIntegrator;
use crate::render::{Adaptive, PixelRect, RenderJob, RenderOutput, RenderSettings};
use crate::sampling::Sampler;
use crate::Color;
use rayon::prelude::*;

/// Pixels (Chebyshev distance) whose pilot batch must be constant for a constant pixel to stop.
pub const QUIET_RADIUS: u32 = 5;

/// A pixel's running sums.
#[derive(Clone, Copy, Debug, Default)]
pub struct PixelStats {
    pub sum: Color,
    /// Σx and Σx² of the samples' luminance.
    pub s1: f64,
    pub s2: f64,
    pub n: u32,
    pub nonfinite: u32,
    /// Whether every sample so far had the same value.
    pub constant: bool,
    first: Color,
}

impl PixelStats {
    pub fn add(&mut self, mut v: Color) {
        if !is_finite(v) {
            self.nonfinite += 1;
            v = Color::ZERO;
        }
        if self.n == 0 {
            self.first = v;
            self.constant = true;
        } else if v != self.first {
            self.constant = false;
        }
        self.sum += v;
        let lum = luminance(v) as f64;
        self.s1 += lum;
        self.s2 += lum * lum;
        self.n += 1;
    }

    /// The course's test `1.96·σ/√n ≤ tol·μ` (false before 2 samples).
    pub fn meets_tolerance(&self, tol: f32) -> bool {
        if self.n < 2 {
            return false;
        }
        let n = self.n as f64;
        let mu = self.s1 / n;
        let var = ((self.s2 - self.s1 * self.s1 / n) / (n - 1.0)).max(0.0);
        1.96 * var.sqrt() / n.sqrt() <= tol as f64 * mu
    }

    pub fn mean(&self) -> Color {
        self.sum / self.n.max(1) as f32
    }
}

/// For each pixel: whether every pixel within `radius` had a constant pilot.
pub fn quiet_neighbourhoods(pilot: &[PixelStats], w: u32, h: u32, radius: u32) -> Vec<bool> {
    let at = |x: u32, y: u32| pilot[(y * w + x) as usize].constant;
    // Separable: first along rows, then along columns.
    let mut rows = vec![false; pilot.len()];
    for y in 0..h {
        for x in 0..w {
            let (x0, x1) = (x.saturating_sub(radius), (x + radius).min(w - 1));
            rows[(y * w + x) as usize] = (x0..=x1).all(|i| at(i, y));
        }
    }
    let mut out = vec![false; pilot.len()];
    for y in 0..h {
        for x in 0..w {
            let (y0, y1) = (y.saturating_sub(radius), (y + radius).min(h - 1));
            out[(y * w + x) as usize] = (y0..=y1).all(|j| rows[(j * w + x) as usize]);
        }
    }
    out
}

/// Whether a pixel with statistics `p` (and a quiet neighbourhood or not) may stop.
/// Constant non-zero pixels (emitters seen directly) stop after
/// `min_samples_if_constant`: missing rare light there is a relative error of that
/// light's share only, whereas a pixel of zeros that missed it is wrong by 100 %.
pub fn may_stop(p: &PixelStats, quiet: bool, a: Adaptive) -> bool {
    if !p.constant {
        p.meets_tolerance(a.tol)
    } else if p.first == Color::ZERO {
        quiet
    } else {
        p.n >= a.min_samples_if_constant
    }
}

/// Renders radiance of pixels `rect` of `job` with adaptive sampling under this
/// module's rule. The pilot covers `rect` grown by `QUIET_RADIUS` (within the image),
/// so a rectangle is exactly the crop of the full image.
pub fn render(
    job: &RenderJob,
    settings: &RenderSettings,
    a: Adaptive,
    rect: PixelRect,
    progress: &(dyn Fn(u64) + Sync),
) -> RenderOutput {
    let (camera, w) = (&job.camera, job.camera.width);
    let spp = settings.spp.max(1);
    let integrator = PathIntegrator::new(
        &job.scene,
        job.accel.as_ref(),
        settings.path_settings(&job.scene),
    );
    // Sample `p.n` of pixel (x, y), added to `p`.
    let sample = |x: u32, y: u32, p: &mut PixelStats| {
        let pixel = y as u64 * w as u64 + x as u64;
        let index = settings.spp_offset as u64 + p.n as u64;
        let mut s = Sampler::for_sample(settings.seed, pixel, index);
        p.add(integrator.li(camera.sample_ray(x, y, &mut s), &mut s));
    };
    let r = QUIET_RADIUS;
    let halo = PixelRect {
        x0: rect.x0.saturating_sub(r),
        y0: rect.y0.saturating_sub(r),
        x1: (rect.x1 + r).min(w),
        y1: (rect.y1 + r).min(camera.height),
    };
    let hw = halo.width();
    let pilot: Vec<PixelStats> = (0..halo.area() as usize)
        .into_par_iter()
        .map(|i| {
            let (x, y) = (halo.x0 + i as u32 % hw, halo.y0 + i as u32 / hw);
            let mut p = PixelStats::default();
            for _ in 0..a.batch.min(spp) {
                sample(x, y, &mut p);
            }
            p
        })
        .collect();
    let quiet = quiet_neighbourhoods(&pilot, hw, halo.height(), r);
    let rows: Vec<Vec<PixelStats>> = (rect.y0..rect.y1)
        .into_par_iter()
        .map(|y| {
            let row: Vec<PixelStats> = (rect.x0..rect.x1)
                .map(|x| {
                    let i = ((y - halo.y0) * hw + (x - halo.x0)) as usize;
                    let mut p = pilot[i];
                    while p.n < spp && !may_stop(&p, quiet[i], a) {
                        for _ in 0..a.batch.min(spp - p.n) {
                            sample(x, y, &mut p);
                        }
                    }
                    p
                })
                .collect();
            progress(rect.width() as u64);
            row
        })
        .collect();
    let stats: Vec<PixelStats> = rows.into_iter().flatten().collect();
    let mut image = Image::new(rect.width(), rect.height());
    for (px, p) in image.pixels.iter_mut().zip(&stats) {
        *px = p.mean();
    }
    RenderOutput {
        image,
        samples: stats.iter().map(|p| p.n).collect(),
        nonfinite_samples: stats.iter().map(|p| p.nonfinite as u64).sum(),
        cost_scale: None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn stats(values: &[f32]) -> PixelStats {
        let mut p = PixelStats::default();
        for &v in values {
            p.add(Color::splat(v));
        }
        p
    }

    #[test]
    fn constant_pixels_stop_only_in_quiet_neighbourhoods() {
        let a = Adaptive::new(4, 0.05);
        let zeros = stats(&[0.0; 8]);
        assert!(zeros.constant && !may_stop(&zeros, false, a) && may_stop(&zeros, true, a));
        let smooth = stats(&[1.0, 1.01, 0.99, 1.0, 1.0, 1.01, 0.99, 1.0]);
        assert!(!smooth.constant && may_stop(&smooth, false, a));
        let rare = stats(&[0.0, 0.0, 0.0, 20.0, 0.0, 0.0, 0.0, 0.0]);
        assert!(!may_stop(&rare, true, a));
        let emitter = stats(&[10.0; 8]);
        assert!(!may_stop(&emitter, false, a));
        assert!(may_stop(&stats(&[10.0; 16]), false, a));
    }

    #[test]
    fn quiet_needs_the_whole_window_constant() {
        let (w, h) = (9, 5);
        let mut pilot = vec![stats(&[0.0, 0.0]); (w * h) as usize];
        pilot[(2 * w + 4) as usize] = stats(&[0.0, 1.0]);
        let q = quiet_neighbourhoods(&pilot, w, h, 2);
        assert!(!q[(2 * w + 4) as usize] && !q[2] && !q[(4 * w + 6) as usize]);
        assert!(q[(2 * w + 1) as usize] && q[(2 * w + 7) as usize]);
    }
}
