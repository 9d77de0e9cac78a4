//! Linear RGB radiance. Every formula of the spec applies per channel, so a
//! plain 3-vector is all a colour needs to be.

/// Linear RGB triple (radiance, irradiance, reflectance...).
pub type Color = glam::Vec3;

/// Illuminance of a linear RGB value (Rec. 709 weights, as the spec's adaptive rule uses).
#[inline]
pub fn luminance(c: Color) -> f32 {
    luminance_l(c.into())
}

/// [`luminance`] per lane.
#[inline(always)]
pub fn luminance_l<F: crate::lanes::Real>(c: crate::lanes::V3<F>) -> F {
    c.x.splat_as(0.2126) * c.x + c.y.splat_as(0.7152) * c.y + c.z.splat_as(0.0722) * c.z
}

/// True when every channel is finite.
#[inline]
pub fn is_finite(c: Color) -> bool {
    c.x.is_finite() && c.y.is_finite() && c.z.is_finite()
}

/// A vector with trailing zeros trimmed, for people: `(0, 0.75, 4.802344)`.
pub fn compact(x: glam::Vec3) -> String {
    let f = |c: f32| {
        let s = format!("{c:.6}");
        let s = s.trim_end_matches('0').trim_end_matches('.');
        // Tiny negatives such as −1e-8 would print as "-0".
        if s == "-0" {
            "0".to_string()
        } else {
            s.to_string()
        }
    };
    format!("({}, {}, {})", f(x.x), f(x.y), f(x.z))
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    #[test]
    fn vectors_print_compactly() {
        assert_eq!(
            compact(Vec3::new(-0.0, 0.75, 4.8023443)),
            "(0, 0.75, 4.802344)"
        );
        assert_eq!(compact(Vec3::new(10.0, -1.5, 100.0)), "(10, -1.5, 100)");
    }
}
