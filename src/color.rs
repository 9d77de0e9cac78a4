//! Linear RGB radiance. Every formula of the spec applies per channel, so a
//! plain 3-vector is all a colour needs to be.

/// Linear RGB triple (radiance, irradiance, reflectance...).
pub type Color = glam::Vec3;

/// Illuminance of a linear RGB value (Rec. 709 weights, as the spec's adaptive rule uses).
#[inline]
pub fn luminance(c: Color) -> f32 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

/// True when every channel is finite.
#[inline]
pub fn is_finite(c: Color) -> bool {
    c.x.is_finite() && c.y.is_finite() && c.z.is_finite()
}
