//! Environment light (`-e FILE.exr`, course project 3-2 part 3): radiance arriving
//! from infinitely far away in every direction, read from a latitude-longitude map.
//!
//! The mapping is the course's (`EnvironmentLight::dir_to_theta_phi` /
//! `theta_phi_to_xy` in the CS184 skeleton), so a course map looks the same in ember:
//! `θ = acos(ω·Y)` from world +Y (the hemisphere light's "up") gives the row, `v = θ/π`
//! (the top row is +Y); `φ = atan2(−ω_z, ω_x) + π` gives the column, `u = φ/2π`, so
//! u = 0 is −X, u = ¼ is +Z, u = ½ is +X and u = ¾ is −Z.
//!
//! Each texel's radiance is constant over its patch of the sphere (no filtering), and
//! directions are drawn texel by texel in proportion to luminance × sin θ (pbrt's
//! `PiecewiseConstant2D` over the map, as pbrt-v3's `InfiniteAreaLight`), which is
//! the texel's share of the light arriving from the whole sphere.

use super::LightSample;
use crate::color::luminance;
use crate::distribution::PiecewiseConstant2D;
use crate::film::Image;
use crate::sampling::{uniform_sphere, uniform_sphere_pdf};
use crate::Color;
use glam::{Vec2, Vec3};
use std::f32::consts::PI;
use std::path::Path;

/// How `sample_li` draws directions.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EnvSampling {
    /// In proportion to luminance × sin θ (the default).
    Importance,
    /// Uniformly over the sphere (the course's first step; kept for comparisons).
    Uniform,
}

#[derive(Clone, PartialEq)]
pub struct EnvironmentMap {
    /// Where the map came from, for messages.
    pub source: String,
    width: u32,
    height: u32,
    texels: Vec<Color>,
    distribution: PiecewiseConstant2D,
    sampling: EnvSampling,
}

impl std::fmt::Debug for EnvironmentMap {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "EnvironmentMap({}, {}x{}, {:?})",
            self.source, self.width, self.height, self.sampling
        )
    }
}

#[derive(Debug, thiserror::Error)]
pub enum EnvMapError {
    #[error("{path}: cannot read environment map: {msg}")]
    Read { path: String, msg: String },
    #[error("{path}: not an OpenEXR file; -e takes a latitude-longitude .exr map")]
    NotExr { path: String },
    #[error("{path}: environment map has no texels ({width}x{height})")]
    Empty {
        path: String,
        width: u32,
        height: u32,
    },
    #[error(
        "{path}: texel ({x}, {y}) is {value}; environment radiance must be finite and non-negative"
    )]
    BadTexel {
        path: String,
        x: u32,
        y: u32,
        value: String,
    },
}

/// The four bytes every OpenEXR file starts with.
const EXR_MAGIC: [u8; 4] = [0x76, 0x2f, 0x31, 0x01];

impl EnvironmentMap {
    /// Reads a latitude-longitude EXR map.
    pub fn load(path: &Path) -> Result<Self, EnvMapError> {
        let name = path.display().to_string();
        let read = |msg: String| EnvMapError::Read {
            path: name.clone(),
            msg: msg.replace('\n', " "),
        };
        let bytes = std::fs::read(path).map_err(|e| read(e.to_string()))?;
        if !bytes.starts_with(&EXR_MAGIC) {
            return Err(EnvMapError::NotExr { path: name });
        }
        let img = image::load_from_memory_with_format(&bytes, image::ImageFormat::OpenExr)
            .map_err(|e| read(e.to_string()))?
            .to_rgb32f();
        let (width, height) = img.dimensions();
        let pixels = img.pixels().map(|p| Color::new(p[0], p[1], p[2])).collect();
        Self::from_image(
            Image {
                width,
                height,
                pixels,
            },
            &name,
        )
    }

    /// A map from linear radiance texels (row 0 is +Y); `source` names it in errors.
    pub fn from_image(img: Image, source: &str) -> Result<Self, EnvMapError> {
        let (w, h) = (img.width, img.height);
        if w == 0 || h == 0 || img.pixels.len() != w as usize * h as usize {
            return Err(EnvMapError::Empty {
                path: source.into(),
                width: w,
                height: h,
            });
        }
        if let Some(i) = img
            .pixels
            .iter()
            .position(|c| !crate::color::is_finite(*c) || c.min_element() < 0.0)
        {
            let c = img.pixels[i];
            return Err(EnvMapError::BadTexel {
                path: source.into(),
                x: i as u32 % w,
                y: i as u32 / w,
                value: format!("({}, {}, {})", c.x, c.y, c.z),
            });
        }
        let func: Vec<f32> = img
            .pixels
            .iter()
            .enumerate()
            .map(|(i, &c)| {
                let v = ((i as u32 / w) as f32 + 0.5) / h as f32;
                luminance(c) * (PI * v).sin()
            })
            .collect();
        Ok(EnvironmentMap {
            source: source.into(),
            width: w,
            height: h,
            distribution: PiecewiseConstant2D::new(&func, w as usize, h as usize),
            texels: img.pixels,
            sampling: EnvSampling::Importance,
        })
    }

    /// The same map drawing its light samples by `sampling`.
    pub fn with_sampling(mut self, sampling: EnvSampling) -> Self {
        self.sampling = sampling;
        self
    }

    pub fn sampling(&self) -> EnvSampling {
        self.sampling
    }

    pub fn width(&self) -> u32 {
        self.width
    }

    pub fn height(&self) -> u32 {
        self.height
    }

    /// Radiance arriving from unit direction `w` (travelling along `−w`).
    pub fn le(&self, w: Vec3) -> Color {
        self.texel(dir_to_uv(w))
    }

    /// Radiance of the texel holding map coordinates `uv ∈ [0,1]²`.
    pub fn texel(&self, uv: Vec2) -> Color {
        let x = ((uv.x * self.width as f32) as u32).min(self.width - 1);
        let y = ((uv.y * self.height as f32) as u32).min(self.height - 1);
        self.texels[(y * self.width + x) as usize]
    }

    pub fn sample_li(&self, u: Vec2) -> Option<LightSample> {
        let (wi, pdf) = match self.sampling {
            EnvSampling::Uniform => (uniform_sphere(u), uniform_sphere_pdf()),
            EnvSampling::Importance => {
                let (uv, pdf_uv) = self.distribution.sample(u);
                let sin_theta = (PI * uv.y).sin();
                if pdf_uv <= 0.0 || sin_theta <= 0.0 {
                    return None;
                }
                (uv_to_dir(uv), pdf_uv / (2.0 * PI * PI * sin_theta))
            }
        };
        Some(LightSample {
            wi,
            dist: f32::INFINITY,
            p_light: Vec3::INFINITY,
            li: self.le(wi),
            pdf,
            delta: false,
        })
    }

    /// Solid-angle density of `sample_li` at unit `wi`.
    pub fn pdf_li(&self, wi: Vec3) -> f32 {
        match self.sampling {
            EnvSampling::Uniform => uniform_sphere_pdf(),
            EnvSampling::Importance => {
                let uv = dir_to_uv(wi);
                // From x and z: accurate near the poles, where 1 − y² cancels.
                let sin_theta = (wi.x * wi.x + wi.z * wi.z).sqrt();
                if sin_theta <= 0.0 {
                    return 0.0;
                }
                self.distribution.pdf(uv) / (2.0 * PI * PI * sin_theta)
            }
        }
    }

    /// `∫ luminance(L) dω` over the sphere (texel-centre sin θ, as the sampler).
    pub fn luminance_integral(&self) -> f32 {
        2.0 * PI * PI * self.distribution.integral()
    }
}

/// Map coordinates of unit direction `w`: `u = φ/2π` with `φ = atan2(−w_z, w_x) + π`,
/// `v = θ/π` with `θ = acos(w_y)` (the course's convention).
pub fn dir_to_uv(w: Vec3) -> Vec2 {
    let theta = w.y.clamp(-1.0, 1.0).acos();
    let phi = (-w.z).atan2(w.x) + PI;
    Vec2::new((phi / (2.0 * PI)).clamp(0.0, 1.0), theta / PI)
}

/// The unit direction at map coordinates `uv` (inverse of `dir_to_uv`).
pub fn uv_to_dir(uv: Vec2) -> Vec3 {
    let (sin_t, cos_t) = (PI * uv.y).sin_cos();
    let (sin_p, cos_p) = (2.0 * PI * uv.x).sin_cos();
    Vec3::new(-sin_t * cos_p, cos_t, sin_t * sin_p)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mapping_follows_the_course_and_round_trips() {
        let at = |u: f32, v: f32| uv_to_dir(Vec2::new(u, v));
        assert!(at(0.0, 0.5).abs_diff_eq(Vec3::NEG_X, 1e-6));
        assert!(at(0.25, 0.5).abs_diff_eq(Vec3::Z, 1e-6));
        assert!(at(0.5, 0.5).abs_diff_eq(Vec3::X, 1e-6));
        assert!(at(0.75, 0.5).abs_diff_eq(Vec3::NEG_Z, 1e-6));
        assert!(at(0.3, 0.0).abs_diff_eq(Vec3::Y, 1e-6));
        for (u, v) in [(0.1, 0.2), (0.6, 0.7), (0.95, 0.45)] {
            let uv = dir_to_uv(at(u, v));
            assert!(uv.abs_diff_eq(Vec2::new(u, v), 1e-5), "{u} {v}: {uv}");
        }
    }

    #[test]
    fn sampled_pdf_matches_pdf_li_and_texel() {
        let mut img = Image::new(8, 4);
        img.pixels[9] = Color::new(5.0, 1.0, 0.5);
        img.pixels[20] = Color::splat(0.25);
        let env = EnvironmentMap::from_image(img, "test").unwrap();
        for k in 0..64 {
            let u = Vec2::new((k as f32 * 0.618_034).fract(), (k as f32 + 0.5) / 64.0);
            let s = env.sample_li(u).unwrap();
            let rel = (s.pdf - env.pdf_li(s.wi)).abs() / s.pdf;
            assert!(rel < 1e-3, "{u}: {} vs {}", s.pdf, env.pdf_li(s.wi));
            assert!(s.li != Color::ZERO, "sampled a black texel");
        }
    }
}
