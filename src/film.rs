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

/// What the sample-rate map's legend calls its colours, shorter for narrower maps.
pub const RATE_LEGEND_TITLES: [&str; 3] = ["samples per pixel", "samples/pixel", "spp"];

/// The adaptive sample-rate map as the PNG shows it: every pixel coloured by its
/// sample count (blue none, red `spp`, the most a pixel may take), with a legend
/// below the `width × height` map saying so (see [`with_heat_legend`]).
pub fn sample_rate_map(width: u32, height: u32, samples: &[u32], spp: u32) -> Image {
    let counts: Vec<f32> = samples.iter().map(|&s| s as f32).collect();
    let map = heat_map(width, height, &counts, spp as f32);
    with_heat_legend(&map, spp as f32, &RATE_LEGEND_TITLES)
}

/// `map` (made by [`heat_map`] with `scale`) with a legend strip added below it: the
/// colour ramp from 0 to `scale`, labelled 0, `scale`/2 and `scale`, and above the ramp
/// the first of `titles` that fits (longest first). Text is drawn with 8×8 glyphs,
/// doubled from 640 pixels wide; what does not fit a narrow map is left out (the ramp
/// last).
pub fn with_heat_legend(map: &Image, scale: f32, titles: &[&str]) -> Image {
    let px = if map.width >= 640 { 2 } else { 1 };
    let glyph = 8 * px;
    let pad = 3 * px;
    let legend_h = pad + glyph + pad + glyph + pad + glyph + pad;
    let mut out = Image::new(map.width, map.height + legend_h);
    out.pixels[..map.pixels.len()].copy_from_slice(&map.pixels);
    let fill = Color::splat(0.02);
    for p in &mut out.pixels[map.pixels.len()..] {
        *p = fill;
    }
    let margin = pad.min(map.width / 8);
    let text_y = map.height + pad;
    let bar_y = text_y + glyph + pad;
    let label_y = bar_y + glyph + pad;
    let fits = |t: &&str| t.chars().count() as u32 * glyph <= map.width;
    if let Some(title) = titles.iter().copied().find(fits) {
        draw_text_centred(&mut out, title, map.width / 2, text_y, px);
    }
    let bar = margin..map.width.saturating_sub(margin);
    let span = (bar.end - bar.start).max(2) - 1;
    for x in bar.clone() {
        let c = heat_color((x - bar.start) as f32 / span as f32);
        for y in bar_y..bar_y + glyph {
            out.pixels[(y * out.width + x) as usize] = c;
        }
    }
    let label = |v: f32| match v.fract() == 0.0 {
        true => format!("{v:.0}"),
        false => format!("{v:.1}"),
    };
    let half = label(scale / 2.0);
    let top = label(scale);
    // The end labels sit inside the ramp's ends; the middle one only when all three fit.
    let width_of = |s: &str| s.len() as u32 * glyph;
    if width_of("0") + width_of(&half) + width_of(&top) + 4 * glyph <= map.width {
        draw_text_centred(&mut out, &half, map.width / 2, label_y, px);
    }
    if width_of("0") + width_of(&top) + glyph <= map.width {
        draw_text(&mut out, "0", bar.start, label_y, px);
        let right = bar.end.saturating_sub(width_of(&top));
        draw_text(&mut out, &top, right, label_y, px);
    }
    out
}

/// `text` centred on column `cx`, if it fits in the image's width.
fn draw_text_centred(img: &mut Image, text: &str, cx: u32, y: u32, px: u32) {
    let w = text.chars().count() as u32 * 8 * px;
    if w <= img.width {
        draw_text(
            img,
            text,
            cx.saturating_sub(w / 2).min(img.width - w),
            y,
            px,
        );
    }
}

/// White ASCII `text` (8×8 glyphs, each dot `px × px` pixels) from pixel (x, y) down
/// and right; dots outside the image are dropped.
fn draw_text(img: &mut Image, text: &str, x: u32, y: u32, px: u32) {
    for (i, c) in text.chars().enumerate() {
        let rows = font8x8::legacy::BASIC_LEGACY
            .get(c as usize)
            .copied()
            .unwrap_or(font8x8::legacy::NOTHING_TO_DISPLAY);
        let gx = x + i as u32 * 8 * px;
        for (r, bits) in rows.iter().enumerate() {
            for b in (0..8).filter(|b| bits >> b & 1 == 1) {
                for (dy, dx) in (0..px).flat_map(|dy| (0..px).map(move |dx| (dy, dx))) {
                    let (px_x, px_y) = (gx + b * px + dx, y + r as u32 * px + dy);
                    if px_x < img.width && px_y < img.height {
                        img.pixels[(px_y * img.width + px_x) as usize] = Color::ONE;
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_rate_map_keeps_its_pixels_and_adds_a_labelled_ramp() {
        let (w, h) = (160, 120);
        let samples: Vec<u32> = (0..w * h).map(|i| i % 257).collect();
        let map = sample_rate_map(w, h, &samples, 256);
        assert_eq!(map.width, w);
        assert!(map.height > h + 24, "a legend strip below: {}", map.height);
        let counts: Vec<f32> = samples.iter().map(|&s| s as f32).collect();
        let plain = heat_map(w, h, &counts, 256.0);
        assert_eq!(&map.pixels[..plain.pixels.len()], &plain.pixels[..]);
        let legend = &map.pixels[plain.pixels.len()..];
        // The ramp runs from blue to red, and there is white text.
        assert!(legend.contains(&heat_color(0.0)) && legend.contains(&heat_color(1.0)));
        let white = legend.iter().filter(|&&p| p == Color::ONE).count();
        assert!(white > 100, "{white} white pixels of text");
    }

    #[test]
    fn a_narrow_map_names_its_colours_in_fewer_letters() {
        // `ember report --quick` draws 120-pixel-wide maps: too narrow for
        // "samples per pixel" in 8-pixel glyphs, wide enough for "samples/pixel".
        let (w, h) = (120, 90);
        let map = sample_rate_map(w, h, &vec![3; (w * h) as usize], 8);
        let title_rows = &map.pixels[((h + 3) * w) as usize..((h + 3 + 8) * w) as usize];
        let white = title_rows.iter().filter(|&&p| p == Color::ONE).count();
        assert!(white > 100, "{white} white pixels in the title row");
    }

    #[test]
    fn a_tiny_map_still_gets_its_ramp_without_overflowing() {
        let map = sample_rate_map(4, 3, &[1; 12], 8);
        assert_eq!(map.width, 4);
        assert!(map.pixels.iter().all(|p| p.is_finite()));
    }
}
