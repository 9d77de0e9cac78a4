//! Image textures: a diffuse colour map read through the `image` crate (PNG, JPEG,
//! TGA, BMP; OpenEXR too), looked up by texture coordinates with bilinear filtering.
//!
//! Shading asks one question of a texture, `Texture::eval(uv)`, the linear colour at
//! `uv`; `Scene::albedo` combines it with the material. 8- and 16-bit images are
//! display-encoded (sRGB) and decoded to linear once at load; float images are linear.

use crate::Color;
use glam::Vec2;

/// What a coordinate outside `[0, 1]` reads (COLLADA's `wrap_s`/`wrap_t`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Wrap {
    /// The image repeats (COLLADA `WRAP`, the default).
    #[default]
    Repeat,
    /// The image repeats, every other copy mirrored (`MIRROR`).
    Mirror,
    /// The edge texels extend outward (`CLAMP`, and `BORDER`/`NONE`, whose border
    /// colour ember does not model).
    Clamp,
}

impl Wrap {
    /// The texel index for integer texel coordinate `i` of an axis `n` texels long.
    fn texel(self, i: i64, n: usize) -> usize {
        let n = n as i64;
        let k = match self {
            Wrap::Repeat => i.rem_euclid(n),
            Wrap::Mirror => {
                let m = i.rem_euclid(2 * n);
                if m < n {
                    m
                } else {
                    2 * n - 1 - m
                }
            }
            Wrap::Clamp => i.clamp(0, n - 1),
        };
        k as usize
    }

    /// COLLADA's name for the mode.
    pub fn name(self) -> &'static str {
        match self {
            Wrap::Repeat => "WRAP",
            Wrap::Mirror => "MIRROR",
            Wrap::Clamp => "CLAMP",
        }
    }
}

#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    /// Where the image came from, as the scene file names it (for messages and `ember info`).
    pub source: String,
    width: usize,
    height: usize,
    /// Linear colours, row 0 at the top of the image.
    texels: Vec<Color>,
    pub wrap_s: Wrap,
    pub wrap_t: Wrap,
}

impl Texture {
    /// A texture of `width × height` linear colours, row 0 at the top.
    pub fn from_texels(source: &str, width: usize, height: usize, texels: Vec<Color>) -> Self {
        assert!(width > 0 && height > 0 && texels.len() == width * height);
        Texture {
            source: source.to_string(),
            width,
            height,
            texels,
            wrap_s: Wrap::Repeat,
            wrap_t: Wrap::Repeat,
        }
    }

    /// Decodes an encoded image: the format from its content, else (TGA has no
    /// signature) from the extension of `source`. Alpha is ignored.
    pub fn decode(source: &str, bytes: &[u8]) -> Result<Self, String> {
        let img = match image::guess_format(bytes) {
            Ok(f) => image::load_from_memory_with_format(bytes, f),
            Err(e) => match image::ImageFormat::from_path(source) {
                Ok(f) => image::load_from_memory_with_format(bytes, f),
                Err(_) => Err(e),
            },
        }
        .map_err(|e| e.to_string())?;
        let (w, h) = (img.width() as usize, img.height() as usize);
        if w == 0 || h == 0 {
            return Err("the image is empty".into());
        }
        let float = matches!(
            img.color(),
            image::ColorType::Rgb32F | image::ColorType::Rgba32F
        );
        let texels = if float {
            img.into_rgb32f()
                .pixels()
                .map(|p| Color::new(p[0], p[1], p[2]))
                .collect()
        } else {
            img.into_rgb16()
                .pixels()
                .map(|p| Color::new(decode16(p[0]), decode16(p[1]), decode16(p[2])))
                .collect()
        };
        Ok(Texture::from_texels(source, w, h, texels))
    }

    pub fn width(&self) -> usize {
        self.width
    }

    pub fn height(&self) -> usize {
        self.height
    }

    /// The texel in column `x` from the left and row `y` from the top.
    pub fn texel(&self, x: usize, y: usize) -> Color {
        self.texels[y * self.width + x]
    }

    /// The colour at `uv` (`v` up, as in OpenGL and COLLADA: `v = 0` is the image's
    /// bottom row): bilinear between the four texels around it, texel centres at
    /// half-integer coordinates.
    pub fn eval(&self, uv: Vec2) -> Color {
        if !uv.is_finite() {
            return self.texels[0];
        }
        let x = uv.x as f64 * self.width as f64 - 0.5;
        let y = (1.0 - uv.y as f64) * self.height as f64 - 0.5;
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = ((x - x0) as f32, (y - y0) as f32);
        // Far outside the image the integer part saturates; the wrap still applies.
        let (x0, y0) = (x0 as i64, y0 as i64);
        let col = |i: i64| self.wrap_s.texel(i, self.width);
        let row = |j: i64| self.wrap_t.texel(j, self.height);
        let (c0, c1, r0, r1) = (col(x0), col(x0 + 1), row(y0), row(y0 + 1));
        let top = self.texel(c0, r0) * (1.0 - fx) + self.texel(c1, r0) * fx;
        let bottom = self.texel(c0, r1) * (1.0 - fx) + self.texel(c1, r1) * fx;
        top * (1.0 - fy) + bottom * fy
    }
}

/// The sRGB transfer function inverted: an encoded value in `[0, 1]` to linear.
pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

fn decode16(v: u16) -> f32 {
    srgb_to_linear(v as f32 / 65535.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn checker() -> Texture {
        // 2×2: top row red, green; bottom row blue, white.
        let t = vec![Color::X, Color::Y, Color::Z, Color::ONE];
        Texture::from_texels("checker", 2, 2, t)
    }

    #[test]
    fn texel_centres_read_their_texel() {
        let t = checker();
        assert_eq!(t.eval(Vec2::new(0.25, 0.75)), Color::X);
        assert_eq!(t.eval(Vec2::new(0.75, 0.75)), Color::Y);
        assert_eq!(t.eval(Vec2::new(0.25, 0.25)), Color::Z);
        assert_eq!(t.eval(Vec2::new(0.75, 0.25)), Color::ONE);
        // Repeat: a period over reads the same texel ((1.25, −0.25) is (0.25, 0.75)).
        assert_eq!(t.eval(Vec2::new(1.25, -0.25)), Color::X);
    }

    #[test]
    fn bilinear_between_centres_and_wrap_modes() {
        let mut t = checker();
        let mid = t.eval(Vec2::new(0.5, 0.75));
        assert!((mid - Color::new(0.5, 0.5, 0.0)).length() < 1e-6, "{mid}");
        // At u = 0 the repeat mode blends the left and right columns; clamp does not.
        let wrap = t.eval(Vec2::new(0.0, 0.75));
        assert!((wrap - Color::new(0.5, 0.5, 0.0)).length() < 1e-6, "{wrap}");
        t.wrap_s = Wrap::Clamp;
        assert_eq!(t.eval(Vec2::new(0.0, 0.75)), Color::X);
        assert_eq!(t.eval(Vec2::new(-3.0, 0.75)), Color::X);
        t.wrap_s = Wrap::Mirror;
        assert_eq!(t.eval(Vec2::new(1.25, 0.75)), Color::Y);
    }

    #[test]
    fn srgb_decoding() {
        assert_eq!(srgb_to_linear(0.0), 0.0);
        assert!((srgb_to_linear(1.0) - 1.0).abs() < 1e-6);
        assert!((srgb_to_linear(0.5) - 0.214_041).abs() < 1e-5);
    }
}
