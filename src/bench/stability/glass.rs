//! Case 4: light through glass. A caustic (light reaching a diffuse floor only through
//! a glass sphere) and a light seen through a glass slab, whose radiance follows from
//! the Fresnel equations alone.

use super::measure::{block_around, Budget};
use super::scenes::{embedded, slab_in_front_of_light, GLASS_IOR};
use super::Row;
use crate::integrators::{DirectStrategy, Roulette};
use crate::materials::Material;
use crate::render::RenderSettings;
use crate::{Color, Vec3};
use anyhow::Result;

/// The caustic under the sphere against the shadow an opaque sphere casts there.
pub struct CausticCase {
    /// (mean, standard error) of the pixels around the point below the sphere.
    pub caustic: (f64, f64),
    /// The same pixels with the glass replaced by a black diffuse sphere.
    pub shadow: (f64, f64),
    /// The same number of pixels of open floor (no sphere in the way).
    pub open_floor: (f64, f64),
    pub noise: f64,
    /// Non-finite samples over every strategy's render.
    pub nonfinite: u64,
    pub all_finite: bool,
}

const CAUSTIC_DEPTH: u32 = 6;

pub fn caustic(b: &Budget) -> Result<CausticCase> {
    let glass = embedded("caustic.dae")?;
    let mut opaque = glass.clone();
    for m in &mut opaque.materials {
        if m.is_delta() {
            *m = Material::lambertian(Color::ZERO);
        }
    }
    let base = RenderSettings {
        max_depth: CAUSTIC_DEPTH,
        strategy: Some(DirectStrategy::Mis),
        roulette: Roulette::Off,
        ..Default::default()
    };
    let setup = b.job(glass)?;
    // Below the sphere (centre (0, 0.6, 0) after Z_UP) and a floor point 0.7 to its side.
    let below = setup
        .camera
        .project(Vec3::ZERO)
        .ok_or_else(|| anyhow::anyhow!("caustic.dae: floor centre not in view"))?;
    let open = setup
        .camera
        .project(Vec3::new(0.7, 0.0, 0.0))
        .ok_or_else(|| anyhow::anyhow!("caustic.dae: open floor not in view"))?;
    let spot = block_around(b.width, b.height, below, 1);
    let open = block_around(b.width, b.height, open, 1);
    let h = setup.halves(&b.settings(base.clone()));
    let mut nonfinite = h.nonfinite();
    let mut all_finite = h.a.image.all_finite() && h.b.image.all_finite();
    for s in [
        DirectStrategy::Light,
        DirectStrategy::Bsdf,
        DirectStrategy::Hemisphere,
    ] {
        let o = setup.render(&b.settings(RenderSettings {
            strategy: Some(s),
            spp: (b.spp / 4).max(1),
            ..base.clone()
        }));
        nonfinite += o.nonfinite_samples;
        all_finite &= o.image.all_finite();
    }
    let shadow_setup = b.job(opaque)?;
    let hs = shadow_setup.halves(&b.settings(base));
    Ok(CausticCase {
        caustic: h.mean_and_se(Some(&spot)),
        shadow: hs.mean_and_se(Some(&spot)),
        open_floor: h.mean_and_se(Some(&open)),
        noise: h.noise_per_pixel(),
        nonfinite,
        all_finite,
    })
}

impl CausticCase {
    pub fn rows(&self) -> Vec<Row> {
        let row = |method: &str, (mean, se): (f64, f64), note: String| Row {
            case: "4 caustic".into(),
            method: method.into(),
            mean,
            stderr: se,
            expected: None,
            noise: self.noise,
            nonfinite: self.nonfinite,
            note,
        };
        vec![
            row("MIS, glass sphere", self.caustic, format!("spot below the sphere: {} vs the opaque sphere's shadow {:.3}, ×{:.2} open floor", format_args!("{:.3}", self.caustic.0), self.shadow.0, self.caustic.0 / self.open_floor.0)),
            row("MIS, black sphere", self.shadow, "same pixels, pure shadow".into()),
            row("MIS, open floor", self.open_floor, "3×3 pixels of unshadowed floor".into()),
        ]
    }
}

/// Fresnel reflectance of a dielectric interface at normal incidence.
pub fn fresnel_normal(ior: f64) -> f64 {
    ((ior - 1.0) / (ior + 1.0)).powi(2)
}

/// Radiance seen through a slab at normal incidence with at most `max_depth` bounces:
/// entering and leaving transmit `(1−F)` each, the `(ηi/ηt)²` factors `(1/η)²·η²`
/// cancel, and each extra round trip inside (two more bounces) adds a factor `F²`.
pub fn slab_expected(radiance: f64, max_depth: u32) -> f64 {
    let f = fresnel_normal(GLASS_IOR as f64);
    if max_depth < 2 {
        return 0.0;
    }
    let trips = (max_depth - 2) / 2;
    radiance * (1.0 - f).powi(2) * (0..=trips).map(|k| f.powi(2 * k as i32)).sum::<f64>()
}

pub struct SlabCase {
    pub radiance: f64,
    /// (max depth, measured mean, standard error, expected).
    pub points: Vec<(u32, f64, f64, f64)>,
    pub noise: f64,
    pub nonfinite: u64,
}

pub fn slab(b: &Budget) -> Result<SlabCase> {
    let radiance = 1.0;
    let setup = b.job(slab_in_front_of_light(radiance as f32))?;
    let mut points = Vec::new();
    let (mut noise, mut nonfinite) = (0.0, 0);
    for depth in [1, 2, 8] {
        let s = RenderSettings {
            max_depth: depth,
            strategy: Some(DirectStrategy::Mis),
            roulette: Roulette::Off,
            ..Default::default()
        };
        let h = setup.halves(&b.settings(s));
        let (mean, se) = h.mean_and_se(None);
        points.push((depth, mean, se, slab_expected(radiance, depth)));
        noise = h.noise_per_pixel();
        nonfinite += h.nonfinite();
    }
    Ok(SlabCase {
        radiance,
        points,
        noise,
        nonfinite,
    })
}

impl SlabCase {
    pub fn rows(&self) -> Vec<Row> {
        self.points
            .iter()
            .map(|&(depth, mean, se, expected)| Row {
                case: "4 light through slab".into(),
                method: format!("MIS, m = {depth}"),
                mean,
                stderr: se,
                expected: Some(expected),
                noise: self.noise,
                nonfinite: self.nonfinite,
                note: format!(
                    "L·(1−F)²·Σ F^2k = {expected:.5}; {:.1} σ off",
                    (mean - expected).abs() / se.max(1e-12)
                ),
            })
            .collect()
    }
}
