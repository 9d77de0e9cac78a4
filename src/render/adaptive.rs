//! Adaptive sampling (`-a BATCH TOL`, spec §7) with a stopping rule that does not
//! stop on light it has not seen yet.
//!
//! The course's rule stops a pixel once `1.96·σ/√n ≤ TOL·μ`. A pixel whose samples
//! are all zero passes it at once, although zero variance after `n` samples is just
//! what a light found with probability ~3/n per sample produces (the "rule of three"),
//! so a pixel of zeros cannot be called converged on its own evidence. Its neighbours
//! say how rare light is there: a first batch over the whole image (the pilot) gives
//! `p̂`, the share of non-zero samples among the pilots of the pixels within
//! `NEIGHBOUR_RADIUS` (the pixel itself left out). A pixel of zeros stops once `n`
//! zeros would be unlikely if light reached it at least `RELATIVE_RATE` as often as
//! it reaches its neighbours: `(1 − RELATIVE_RATE·p̂)ⁿ ≤ MISS_PROBABILITY`; where no
//! neighbour saw light (`p̂ = 0`) that is after the pilot. A pixel constant at a
//! non-zero value (an emitter seen directly) stops after `min_samples_if_constant`;
//! any other pixel follows the course's rule after every batch, up to the `-s` cap.
//!
//! `StopRule::PerPixel` (the course's rule with a minimum count for constant
//! pixels, kept for comparison) is the same test with that minimum for pixels of
//! zeros too, whatever their neighbours. Sample `i` of a pixel is the same sample with
//! or without `-a`, so the pilot batch is the first samples of the fixed-count render
//! and images depend on the seed only.

use super::{Adaptive, StopRule};
use crate::color::{is_finite, luminance};
use crate::integrators::SampleValue;
use crate::Color;

/// Pixels (Chebyshev distance) whose pilot batches say how often light is found near a pixel.
pub const NEIGHBOUR_RADIUS: u32 = 5;
/// A pixel of zeros may have missed light found this much less often than around it…
pub const RELATIVE_RATE: f64 = 0.25;
/// …with at most this probability.
pub const MISS_PROBABILITY: f64 = 0.01;

/// A pixel's running sums.
#[derive(Clone, Copy, Debug, Default)]
pub struct PixelStats {
    pub sum: Color,
    /// Σx and Σx² of the samples' luminance.
    pub s1: f64,
    pub s2: f64,
    pub n: u32,
    pub nonfinite: u32,
    /// Samples with a non-zero value.
    pub nonzero: u32,
    /// Whether every sample so far had the same value.
    pub constant: bool,
    /// Whether a camera ray of the pixel met a surface (followed only while every
    /// sample is zero: `PixelStats::is_empty`).
    pub met_surface: bool,
    /// The pixel's split samples (light of few bounces), whose mean adds to its
    /// samples' mean (`render::split`; none elsewhere).
    pub split: SplitSums,
    first: Color,
}

/// A pixel's split samples: their sum and count, and how many of the pixel's own
/// samples they stand in for (`factor` each).
#[derive(Clone, Copy, Debug, Default)]
pub struct SplitSums {
    pub sum: Color,
    pub n: u32,
    pub covers: u32,
}

impl SplitSums {
    pub fn mean(&self) -> Color {
        self.sum / self.n.max(1) as f32
    }
}

impl PixelStats {
    /// Adds one sample's value to the sum alone (`mean`, `n` and `nonfinite`), for
    /// renders that do not decide when to stop.
    #[inline]
    pub fn add_to_sum(&mut self, v: &SampleValue) {
        if is_finite(v.radiance) {
            self.sum += v.radiance;
        } else {
            self.nonfinite += 1;
        }
        self.n += 1;
    }

    /// Adds one sample's value.
    pub fn add_sample(&mut self, v: &SampleValue) {
        self.add(v.radiance);
        if self.is_zero() && !self.met_surface {
            self.met_surface = v.met_surface;
        }
    }

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
        self.nonzero += (v != Color::ZERO) as u32;
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
        // The split estimate is part of the pixel's value, its (factor times smaller)
        // error not in σ.
        let mu = self.s1 / n + luminance(self.split.mean()) as f64;
        let var = ((self.s2 - self.s1 * self.s1 / n) / (n - 1.0)).max(0.0);
        1.96 * var.sqrt() / n.sqrt() <= tol as f64 * mu
    }

    /// All samples zero, every camera ray having left the scene without meeting anything.
    pub fn is_empty(&self) -> bool {
        self.is_zero() && !self.met_surface
    }

    /// All samples (at least one) zero.
    pub fn is_zero(&self) -> bool {
        self.n > 0 && self.constant && self.first == Color::ZERO
    }

    pub fn mean(&self) -> Color {
        self.sum / self.n.max(1) as f32 + self.split.mean()
    }
}

/// For each pixel: `p̂`, the share of non-zero samples in the pilots of the pixels
/// within `radius` (Chebyshev), the pixel itself left out (0 where there are none).
pub fn neighbour_hit_rates(pilot: &[PixelStats], w: u32, h: u32, radius: u32) -> Vec<f64> {
    let counts = |p: &PixelStats| (p.nonzero as u64, p.n as u64);
    let add = |a: (u64, u64), b: (u64, u64)| (a.0 + b.0, a.1 + b.1);
    // Box sums, separable: first along rows, then along columns.
    let mut rows = vec![(0, 0); pilot.len()];
    for y in 0..h {
        for x in 0..w {
            let (x0, x1) = (x.saturating_sub(radius), (x + radius).min(w - 1));
            rows[(y * w + x) as usize] = (x0..=x1)
                .map(|i| counts(&pilot[(y * w + i) as usize]))
                .fold((0, 0), add);
        }
    }
    let mut rates = vec![0.0; pilot.len()];
    for y in 0..h {
        for x in 0..w {
            let i = (y * w + x) as usize;
            let (y0, y1) = (y.saturating_sub(radius), (y + radius).min(h - 1));
            let all = (y0..=y1)
                .map(|j| rows[(j * w + x) as usize])
                .fold((0, 0), add);
            let (own_hits, own_n) = counts(&pilot[i]);
            let (hits, n) = (all.0 - own_hits, all.1 - own_n);
            rates[i] = if n == 0 { 0.0 } else { hits as f64 / n as f64 };
        }
    }
    rates
}

/// Samples a pixel of zeros takes before it may stop, where its neighbours find light
/// in a share `p̂` of their samples: the least `n` with
/// `(1 − RELATIVE_RATE·p̂)ⁿ ≤ MISS_PROBABILITY` (0 when `p̂ = 0`).
pub fn min_samples_if_zero(p_hat: f64) -> u32 {
    let q = 1.0 - RELATIVE_RATE * p_hat.clamp(0.0, 1.0);
    if q >= 1.0 {
        return 0;
    }
    (MISS_PROBABILITY.ln() / q.ln()).ceil().min(u32::MAX as f64) as u32
}

/// Whether a pixel with statistics `p` may stop, where a pixel of zeros needs
/// `min_if_zero` samples (`min_samples_if_zero` of its neighbours' rate). An empty
/// pixel (no camera ray met anything) needs no more than `min_samples_if_zero(1)`:
/// it has missed a surface covering `RELATIVE_RATE` of it with probability at most
/// `MISS_PROBABILITY`, and until it meets one, rare light cannot reach it.
/// Constant non-zero pixels (emitters seen directly) stop after
/// `min_samples_if_constant`: missing rare light there is a relative error of that
/// light's share only, whereas a pixel of zeros that missed it is wrong by 100 %.
/// Under `StopRule::PerPixel` every constant pixel needs `min_samples_if_constant`.
pub fn may_stop(p: &PixelStats, min_if_zero: u32, a: Adaptive) -> bool {
    if !p.constant {
        p.meets_tolerance(a.tol)
    } else if a.rule == StopRule::PerPixel {
        p.n >= a.min_samples_if_constant.max(2)
    } else if p.is_empty() {
        p.n >= min_if_zero.min(min_samples_if_zero(1.0))
    } else if p.is_zero() {
        p.n >= min_if_zero
    } else {
        p.n >= a.min_samples_if_constant
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::Adaptive;

    fn stats(values: &[f32]) -> PixelStats {
        let mut p = PixelStats::default();
        for &v in values {
            p.add(Color::splat(v));
        }
        p
    }

    #[test]
    fn pixels_of_zeros_stop_after_the_count_their_neighbours_rate_asks() {
        let a = Adaptive::new(4, 0.05);
        let zeros = stats(&[0.0; 8]);
        assert!(zeros.constant && may_stop(&zeros, 0, a) && !may_stop(&zeros, 9, a));
        assert!(may_stop(&zeros, 8, a));
        let smooth = stats(&[1.0, 1.01, 0.99, 1.0, 1.0, 1.01, 0.99, 1.0]);
        assert!(!smooth.constant && may_stop(&smooth, u32::MAX, a));
        let rare = stats(&[0.0, 0.0, 0.0, 20.0, 0.0, 0.0, 0.0, 0.0]);
        assert!(!may_stop(&rare, 0, a));
        let emitter = stats(&[10.0; 8]);
        assert!(!may_stop(&emitter, 0, a));
        // Camera rays that met nothing: at most 17 zeros, whatever the neighbours.
        assert!(zeros.is_empty() && !may_stop(&zeros, u32::MAX, a));
        assert!(may_stop(&stats(&[0.0; 17]), u32::MAX, a));
        let floor = PixelStats {
            met_surface: true,
            ..stats(&[0.0; 24])
        };
        assert!(!may_stop(&floor, 25, a) && may_stop(&floor, 24, a));
        assert!(may_stop(&stats(&[10.0; 16]), u32::MAX, a));
    }

    #[test]
    fn the_minimum_bounds_the_chance_of_missing_a_quarter_of_the_neighbours_rate() {
        assert_eq!(min_samples_if_zero(0.0), 0);
        for p_hat in [1.0, 0.5, 0.05, 1e-3] {
            let n = min_samples_if_zero(p_hat);
            let miss = |n: u32| (1.0 - RELATIVE_RATE * p_hat).powi(n as i32);
            assert!(miss(n) <= MISS_PROBABILITY && miss(n - 1) > MISS_PROBABILITY);
        }
        // Light everywhere around: 17 zeros; light in 1 sample of 20 around (case 7): 367.
        assert_eq!(min_samples_if_zero(1.0), 17);
        assert_eq!(min_samples_if_zero(0.05), 367);
    }

    #[test]
    fn the_rate_counts_the_neighbours_but_not_the_pixel() {
        let (w, h) = (9, 5);
        let mut pilot = vec![stats(&[0.0, 0.0]); (w * h) as usize];
        pilot[(2 * w + 4) as usize] = stats(&[0.0, 1.0]);
        let p = neighbour_hit_rates(&pilot, w, h, 2);
        assert_eq!(p[(2 * w + 4) as usize], 0.0);
        // (2, 2): 5×5 window of 25 pixels, 24 neighbours, 48 samples, one of them non-zero.
        assert_eq!(p[(2 * w + 2) as usize], 1.0 / 48.0);
        // (6, 4) is 2 away at the bottom edge: 5×3 window, 14 neighbours, 28 samples.
        assert_eq!(p[(4 * w + 6) as usize], 1.0 / 28.0);
        assert_eq!(p[(2 * w + 1) as usize], 0.0);
        assert_eq!(p[(4 * w + 7) as usize], 0.0);
    }
}
