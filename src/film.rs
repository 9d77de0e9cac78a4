//! The image being rendered, and the false-colour maps made from per-pixel counts.

use crate::color::{is_finite, luminance};
use crate::Color;

/// A linear RGB image, row 0 at the top.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<Color>,
}

impl Image {
    pub fn new(width: u32, height: u32) -> Self {
        Image {
            width,
            height,
            pixels: vec![Color::ZERO; (width as usize) * (height as usize)],
        }
    }

    #[inline]
    pub fn get(&self, x: u32, y: u32) -> Color {
        self.pixels[(y * self.width + x) as usize]
    }

    /// Per-channel image mean.
    pub fn mean(&self) -> Color {
        let n = self.pixels.len().max(1) as f64;
        let s = self.pixels.iter().fold([0f64; 3], |a, p| {
            [a[0] + p.x as f64, a[1] + p.y as f64, a[2] + p.z as f64]
        });
        Color::new((s[0] / n) as f32, (s[1] / n) as f32, (s[2] / n) as f32)
    }

    /// Mean after clamping every channel to [0, 1] (what a PNG can show).
    pub fn mean_clamped(&self) -> Color {
        let clamped = Image {
            pixels: self
                .pixels
                .iter()
                .map(|p| p.clamp(Color::ZERO, Color::ONE))
                .collect(),
            ..*self
        };
        clamped.mean()
    }

    pub fn all_finite(&self) -> bool {
        self.pixels.iter().all(|p| is_finite(*p))
    }

    /// Average over `b × b` blocks (partial blocks at the border are dropped).
    pub fn block_average(&self, b: u32) -> Image {
        let (w, h) = (self.width / b, self.height / b);
        let mut out = Image::new(w, h);
        let inv = 1.0 / (b * b) as f32;
        for by in 0..h {
            for bx in 0..w {
                let mut s = Color::ZERO;
                for y in 0..b {
                    for x in 0..b {
                        s += self.get(bx * b + x, by * b + y);
                    }
                }
                out.pixels[(by * w + bx) as usize] = s * inv;
            }
        }
        out
    }

    /// RMSE over all channels against `other` (same size).
    pub fn rmse(&self, other: &Image) -> f64 {
        assert_eq!(
            (self.width, self.height),
            (other.width, other.height),
            "rmse of images of different sizes"
        );
        let se: f64 = self
            .pixels
            .iter()
            .zip(&other.pixels)
            .map(|(a, b)| {
                let d = *a - *b;
                (d.x as f64).powi(2) + (d.y as f64).powi(2) + (d.z as f64).powi(2)
            })
            .sum();
        (se / (3 * self.pixels.len().max(1)) as f64).sqrt()
    }

    /// Relative MSE, mean of (a−b)²/(b²+0.01) over all channels, with `other` the reference.
    pub fn rel_mse(&self, reference: &Image) -> f64 {
        let s: f64 = self
            .pixels
            .iter()
            .zip(&reference.pixels)
            .map(|(a, b)| {
                let f = |a: f32, b: f32| ((a - b) as f64).powi(2) / ((b as f64).powi(2) + 0.01);
                f(a.x, b.x) + f(a.y, b.y) + f(a.z, b.z)
            })
            .sum();
        s / (3 * self.pixels.len().max(1)) as f64
    }

    /// Mean illuminance.
    pub fn mean_luminance(&self) -> f32 {
        luminance(self.mean())
    }
}

/// A blue → cyan → green → yellow → red ramp for `t ∈ [0, 1]` (the course's "jet"-like map).
pub fn heat_color(t: f32) -> Color {
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let r = (1.5 - (4.0 * t - 3.0).abs()).clamp(0.0, 1.0);
    let g = (1.5 - (4.0 * t - 2.0).abs()).clamp(0.0, 1.0);
    let b = (1.5 - (4.0 * t - 1.0).abs()).clamp(0.0, 1.0);
    Color::new(r, g, b)
}

/// False-colour image of per-pixel counts scaled so that `scale` maps to red.
pub fn heat_map(width: u32, height: u32, counts: &[f32], scale: f32) -> Image {
    let s = if scale > 0.0 { scale } else { 1.0 };
    Image {
        width,
        height,
        pixels: counts.iter().map(|&c| heat_color(c / s)).collect(),
    }
}
