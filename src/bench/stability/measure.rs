//! Rendering and statistics shared by the stability cases: a scene with its BVH and
//! camera, renders in two independent halves, and the noise estimates they give.

use crate::accel::{self, Accel, AccelKind, BvhBuilder};
use crate::camera::Camera;
use crate::color::luminance;
use crate::film::Image;
use crate::render::{render, RenderOutput, RenderSettings};
use crate::scene::Scene;
use crate::Vec3;
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
            width: self.width,
            height: self.height,
            spp: self.spp,
            seed: self.seed,
            ..base
        }
    }
}

/// A scene ready to render: its BVH and the camera of `Budget`'s image size.
pub struct Setup {
    pub scene: Scene,
    pub accel: Box<dyn Accel>,
    pub camera: Camera,
}

impl Setup {
    /// The scene's own camera (spec §4: derived from the bounds).
    pub fn new(scene: Scene, width: u32, height: u32) -> Result<Setup> {
        let camera = Camera::new(&scene.camera, &scene.bounds, width, height);
        Self::with_camera(scene, camera)
    }

    pub fn with_camera(scene: Scene, camera: Camera) -> Result<Setup> {
        let accel = accel::build(&scene, AccelKind::Native(BvhBuilder::Sah))?;
        Ok(Setup {
            scene,
            accel,
            camera,
        })
    }

    pub fn render(&self, s: &RenderSettings) -> RenderOutput {
        render(&self.scene, self.accel.as_ref(), &self.camera, s, &|_| {})
    }

    /// Two renders of `s.spp / 2` samples with independent seeds derived from `s.seed`.
    pub fn halves(&self, s: &RenderSettings) -> Halves {
        let mut h = s.clone();
        h.spp = (s.spp / 2).max(1);
        h.seed = s.seed.wrapping_mul(2).wrapping_add(1);
        let a = self.render(&h);
        h.seed = s.seed.wrapping_mul(2).wrapping_add(2);
        let b = self.render(&h);
        Halves { a, b }
    }

    /// Pixel `(x, y)` whose centre sees world point `p`, if it is in front of the camera and in the image.
    pub fn project(&self, p: Vec3) -> Option<(u32, u32)> {
        let c = &self.camera;
        let d = p - c.eye;
        let depth = d.dot(c.forward);
        if depth <= 0.0 {
            return None;
        }
        let sx = d.dot(c.right) / depth / c.tan_half_x;
        let sy = d.dot(c.up) / depth / c.tan_half_y;
        let u = 0.5 * (sx + 1.0) * c.width as f32;
        let v = 0.5 * (1.0 - sy) * c.height as f32;
        (u >= 0.0 && v >= 0.0 && u < c.width as f32 && v < c.height as f32)
            .then_some((u as u32, v as u32))
    }
}

/// Two independent renders of the same settings. Their difference is pure noise:
/// for a pixel with per-half variance σ², `Var(a − b) = 2σ²` and the average has
/// variance `σ²/2 = E[(a − b)²]/4`, so every standard error below comes from the halves.
pub struct Halves {
    pub a: RenderOutput,
    pub b: RenderOutput,
}

impl Halves {
    pub fn average(&self) -> Image {
        let pixels = self
            .a
            .image
            .pixels
            .iter()
            .zip(&self.b.image.pixels)
            .map(|(x, y)| 0.5 * (*x + *y))
            .collect();
        Image {
            pixels,
            ..self.a.image.clone()
        }
    }

    pub fn nonfinite(&self) -> u64 {
        self.a.nonfinite_samples + self.b.nonfinite_samples
    }

    /// Samples taken per pixel by both halves together, averaged over the image.
    pub fn mean_samples(&self) -> f64 {
        (self.a.total_samples() + self.b.total_samples()) as f64
            / self.a.samples.len().max(1) as f64
    }

    /// Luminance mean of the averaged image over `pixels` (all when None) and its standard error.
    pub fn mean_and_se(&self, pixels: Option<&[usize]>) -> (f64, f64) {
        let all: Vec<usize>;
        let idx = match pixels {
            Some(p) => p,
            None => {
                all = (0..self.a.image.pixels.len()).collect();
                &all
            }
        };
        let n = idx.len().max(1) as f64;
        let (mut sum, mut var) = (0.0, 0.0);
        for &i in idx {
            let (la, lb) = (lum(&self.a.image, i), lum(&self.b.image, i));
            sum += 0.5 * (la + lb);
            var += 0.25 * (la - lb).powi(2);
        }
        (sum / n, (var / n).sqrt() / n.sqrt())
    }

    /// RMS noise of one pixel of the averaged image (luminance), over `pixels` or all.
    pub fn noise_per_pixel(&self) -> f64 {
        let n = self.a.image.pixels.len().max(1) as f64;
        let s: f64 = (0..self.a.image.pixels.len())
            .map(|i| 0.25 * (lum(&self.a.image, i) - lum(&self.b.image, i)).powi(2))
            .sum();
        (s / n).sqrt()
    }
}

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
