//! The thin lens (`-b`, `-d`) against its analytic image: a straight edge of a large
//! emitter, seen with emitted light only (`-m 0`), so every camera sample is exactly 1
//! (it hits the emitter) or 0 and a pixel's expected value is the probability of a hit.
//!
//! Camera at the origin looking down −Z; the emitter's left edge is the vertical line
//! `x = t_e·z` on the plane at depth `z`, so in the pinhole's tangent coordinates the edge
//! is at `t_e`. A lens of radius `R` focused at depth `f` makes a pixel whose pinhole ray
//! has tangent `t` see the tangents `t + ρ·X`, `X` uniform on the unit disk, with the
//! circle of confusion `ρ = R·|1/z − 1/f|` (tangent units). So a pixel's expected value is
//! the average over its width of `g((t − t_e)/ρ)`, `g(s) = 1/2 + (s·√(1−s²) + asin s)/π`
//! the fraction of the unit disk with `x < s`. All rows of a column have the same
//! expectation; a column's mean over `N` samples has variance `p(1−p)/N`.

use ember::accel::{AccelKind, BvhBuilder};
use ember::camera::{Camera, ThinLens};
use ember::film::Image;
use ember::integrators::{DirectStrategy, Estimator};
use ember::render::{RenderJob, RenderSettings};
use ember::scene::collada::parse;
use glam::Vec3;

const W: u32 = 64;
const H: u32 = 16;
const SPP: u32 = 64;
const TAN_HALF_X: f32 = 0.25;
/// The edge sits 0.3 pixel right of the image's centre line.
const EDGE_PX: f64 = 0.3;
const DEPTH: f32 = 2.0;

fn pixel_tangent() -> f64 {
    2.0 * TAN_HALF_X as f64 / W as f64
}

fn edge_tangent() -> f64 {
    EDGE_PX * pixel_tangent()
}

/// A 40 × 40 emitter of radiance 1 at depth `z`, facing the camera, its left edge at `t_e·z`.
fn edge_scene(z: f32) -> ember::scene::Scene {
    let size = 40.0;
    let x_left = edge_tangent() as f32 * z;
    let xc = x_left + size / 2.0;
    let doc = format!(
        r##"<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset><up_axis>Y_UP</up_axis></asset>
  <library_lights>
    <light id="panel"><technique_common><point><color>1 1 1</color></point></technique_common>
      <extra><technique profile="CGL"><area><color>1 1 1</color></area></technique></extra></light>
  </library_lights>
  <library_visual_scenes>
    <visual_scene id="main">
      <node id="panel-node">
        <matrix>-{size} 0 0 {xc} 0 {size} 0 0 0 0 -1 -{z} 0 0 0 1</matrix>
        <instance_light url="#panel"/>
      </node>
    </visual_scene>
  </library_visual_scenes>
  <scene><instance_visual_scene url="#main"/></scene>
</COLLADA>
"##
    );
    parse(&doc, "edge.dae").unwrap_or_else(|e| panic!("{e}"))
}

fn camera(lens: ThinLens) -> Camera {
    Camera {
        eye: Vec3::ZERO,
        forward: Vec3::NEG_Z,
        up: Vec3::Y,
        right: Vec3::X,
        tan_half_x: TAN_HALF_X,
        tan_half_y: TAN_HALF_X * H as f32 / W as f32,
        width: W,
        height: H,
        lens,
    }
}

fn render(lens: ThinLens, seed: u64) -> Image {
    let job = RenderJob::with_camera(
        edge_scene(DEPTH),
        AccelKind::Native(BvhBuilder::Sah),
        camera(lens),
    )
    .expect("accel");
    let s = RenderSettings {
        spp: SPP,
        max_depth: 0,
        strategy: Some(DirectStrategy::Light),
        seed,
        // Each pixel the mean of its SPP camera samples, as the statistics above
        // assume: no split samples (tests/direct_split.rs).
        direct_split: 0,
        ..RenderSettings::default()
    };
    let out = job.render(&s);
    assert_eq!(out.nonfinite_samples, 0);
    out.image
}

/// Mean of each column (red channel; the emitter is grey).
fn column_means(img: &Image) -> Vec<f64> {
    (0..W)
        .map(|x| (0..H).map(|y| img.get(x, y).x as f64).sum::<f64>() / H as f64)
        .collect()
}

/// Fraction of the unit disk with `x < s`.
fn disk_cdf(s: f64) -> f64 {
    if s <= -1.0 {
        0.0
    } else if s >= 1.0 {
        1.0
    } else {
        0.5 + (s * (1.0 - s * s).sqrt() + s.asin()) / std::f64::consts::PI
    }
}

/// Expected value of column `i` for a circle of confusion of `rho` tangent units.
fn expected_column(i: u32, rho: f64) -> f64 {
    let n = 4000;
    (0..n)
        .map(|k| {
            let u = (i as f64 + (k as f64 + 0.5) / n as f64) / W as f64;
            let t = (2.0 * u - 1.0) * TAN_HALF_X as f64 - edge_tangent();
            if rho == 0.0 {
                (t > 0.0) as u8 as f64
            } else {
                disk_cdf(t / rho)
            }
        })
        .sum::<f64>()
        / n as f64
}

/// Circle of confusion (tangent units) of a lens `lens` for the plane at `DEPTH`.
fn coc(lens: ThinLens) -> f64 {
    lens.radius as f64 * (1.0 / DEPTH as f64 - 1.0 / lens.focal_distance as f64).abs()
}

/// Chi-square of the columns against the analytic profile for `rho`, over the columns
/// whose expectation is strictly between 0 and 1; also the number of such columns and
/// whether every other column is exactly 0 or 1 as expected.
fn chi_square(means: &[f64], rho: f64) -> (f64, usize, bool) {
    let n = (SPP * H) as f64;
    let (mut chi2, mut k, mut exact) = (0.0, 0, true);
    for (i, &m) in means.iter().enumerate() {
        let p = expected_column(i as u32, rho);
        if p > 1e-9 && p < 1.0 - 1e-9 {
            chi2 += (m - p).powi(2) / (p * (1.0 - p) / n);
            k += 1;
        } else if (m - p.round()).abs() > 0.0 {
            exact = false;
        }
    }
    (chi2, k, exact)
}

/// Five standard deviations above the chi-square mean of `k` degrees of freedom.
fn chi_square_bound(k: usize) -> f64 {
    k as f64 + 5.0 * (2.0 * k as f64).sqrt()
}

#[test]
fn emitter_samples_are_exactly_zero_or_one() {
    let img = render(ThinLens::PINHOLE, 1);
    assert!(img.pixels.iter().all(|p| p.x == 0.0 || p.x == 1.0 || {
        // A pixel's value is the mean of SPP samples, each 0 or 1.
        let k = p.x * SPP as f32;
        (k - k.round()).abs() < 1e-3
    }));
    let means = column_means(&img);
    assert_eq!(means[0], 0.0);
    assert_eq!(means[W as usize - 1], 1.0);
}

#[test]
fn point_on_the_focal_plane_images_as_with_the_pinhole() {
    // Focused on the emitter's plane, a wide lens gives the pinhole's edge: one partly
    // covered column (70 % of it is right of the edge) and all others exactly 0 or 1.
    let lens = ThinLens {
        radius: 0.3,
        focal_distance: DEPTH,
    };
    for (name, img) in [
        ("pinhole", render(ThinLens::PINHOLE, 2)),
        ("lens", render(lens, 2)),
    ] {
        let (chi2, k, exact) = chi_square(&column_means(&img), 0.0);
        assert_eq!(k, 1, "{name}");
        assert!(exact, "{name}: a column away from the edge is not 0 or 1");
        assert!(
            chi2 < 25.0,
            "{name}: edge column off by {:.1} sigma",
            chi2.sqrt()
        );
    }
}

#[test]
fn defocus_blur_follows_the_circle_of_confusion() {
    // In front of and behind the focal plane; blur radii of about 6 and 12 pixels.
    for lens in [
        ThinLens {
            radius: 0.19,
            focal_distance: 4.0,
        },
        ThinLens {
            radius: 0.19,
            focal_distance: 1.0,
        },
    ] {
        let rho = coc(lens);
        let means = column_means(&render(lens, 3));
        let (chi2, k, exact) = chi_square(&means, rho);
        let bound = chi_square_bound(k);
        let rho_px = rho / pixel_tangent();
        assert!(
            k as f64 >= 2.0 * rho_px - 1.0,
            "{lens:?}: only {k} blurred columns for a blur radius of {rho_px:.1} px"
        );
        eprintln!(
            "{lens:?}: CoC radius {rho_px:.2} px, chi2 {chi2:.1} over {k} columns (bound {bound:.1})"
        );
        assert!(
            exact,
            "{lens:?}: blur reaches beyond the circle of confusion"
        );
        assert!(
            chi2 < bound,
            "{lens:?}: chi2 {chi2:.1} over {k} columns (bound {bound:.1})"
        );
        // The test can tell a circle of confusion 15 % too small or too large.
        for wrong in [0.85, 1.15] {
            let (chi2, k, _) = chi_square(&means, rho * wrong);
            eprintln!("  CoC x{wrong}: chi2 {chi2:.1} over {k} columns");
            assert!(
                chi2 > chi_square_bound(k),
                "{lens:?}: a CoC {wrong}x the true one fits too (chi2 {chi2:.1}, {k} columns)"
            );
        }
    }
}

#[test]
fn zero_radius_is_the_pinhole_bit_for_bit() {
    let a = render(ThinLens::PINHOLE, 4);
    let b = render(
        ThinLens {
            radius: 0.0,
            focal_distance: 1.3,
        },
        4,
    );
    assert_eq!(a.pixels, b.pixels);
}

/// A grey (albedo 0.3) Lambertian quad at depth `DEPTH` facing the camera, its left edge
/// at `t_e·DEPTH`, lit head-on by a directional light of irradiance 1: where the camera
/// sees it, its radiance is `0.3/π`, elsewhere 0. Small, so that light paths started
/// over the scene's bounds mostly land on it.
fn lit_edge_scene() -> ember::scene::Scene {
    let (x0, x1, y) = (edge_tangent() as f32 * DEPTH, 0.9, 0.45);
    let z = -DEPTH;
    let doc = format!(
        r##"<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset><up_axis>Y_UP</up_axis></asset>
  <library_lights>
    <light id="sun"><technique_common><directional><color>1 1 1</color></directional></technique_common></light>
  </library_lights>
  <library_effects>
    <effect id="grey-fx"><profile_COMMON><technique sid="common"><lambert>
      <diffuse><color>0.3 0.3 0.3 1</color></diffuse>
    </lambert></technique></profile_COMMON></effect>
  </library_effects>
  <library_materials><material id="grey"><instance_effect url="#grey-fx"/></material></library_materials>
  <library_geometries>
    <geometry id="quad"><mesh>
      <source id="pos"><float_array id="pos-a" count="12">{x0} -{y} {z} {x1} -{y} {z} {x1} {y} {z} {x0} {y} {z}</float_array>
        <technique_common><accessor source="#pos-a" count="4" stride="3"/></technique_common></source>
      <vertices id="vtx"><input semantic="POSITION" source="#pos"/></vertices>
      <triangles material="m" count="2"><input semantic="VERTEX" source="#vtx" offset="0"/><p>0 1 2 0 2 3</p></triangles>
    </mesh></geometry>
  </library_geometries>
  <library_visual_scenes>
    <visual_scene id="main">
      <node id="q"><instance_geometry url="#quad"><bind_material><technique_common>
        <instance_material symbol="m" target="#grey"/></technique_common></bind_material></instance_geometry></node>
      <node id="sun-node"><instance_light url="#sun"/></node>
    </visual_scene>
  </library_visual_scenes>
  <scene><instance_visual_scene url="#main"/></scene>
</COLLADA>
"##
    );
    parse(&doc, "lit_edge.dae").unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn light_tracing_sees_through_the_lens_as_path_tracing_does() {
    // Light paths connect to a point on the lens; the edge must blur by the same circle
    // of confusion as camera paths see. Rows of a column are independent and alike, so
    // a column mean's variance is estimated from its rows.
    let lens = ThinLens {
        radius: 0.19,
        focal_distance: 1.0,
    };
    let rho = coc(lens);
    let l0 = 0.3 / std::f64::consts::PI;
    let cam = Camera {
        height: 32,
        tan_half_y: TAN_HALF_X * 32.0 / W as f32,
        ..camera(lens)
    };
    for estimator in [Estimator::Path, Estimator::LightTracing] {
        let job = RenderJob::with_camera(lit_edge_scene(), AccelKind::Native(BvhBuilder::Sah), cam)
            .expect("accel");
        let s = RenderSettings {
            spp: 64,
            max_depth: 1,
            estimator: Some(estimator),
            strategy: Some(DirectStrategy::Light),
            roulette: ember::integrators::Roulette::Off,
            seed: 9,
            ..RenderSettings::default()
        };
        let img = job.render(&s).image;
        let mut worst: f64 = 0.0;
        for x in 0..W {
            let v: Vec<f64> = (0..cam.height).map(|y| img.get(x, y).y as f64).collect();
            let n = v.len() as f64;
            let mean = v.iter().sum::<f64>() / n;
            let var = v.iter().map(|a| (a - mean).powi(2)).sum::<f64>() / (n - 1.0);
            let want = l0 * expected_column(x, rho);
            let se = (var / n).sqrt();
            if se == 0.0 {
                // Every row saw the same value: all lit (l0) or all dark (0). Near the
                // blur's edge that happens when no sample of the column fell in the
                // sliver of the other kind, whose share is p. With a pixel's samples
                // stratified (a row sees it with probability spp·p at most) that has
                // probability (1 − spp·p)^rows; reject below 1e-3.
                let p = ((mean - want) / l0).abs();
                let all_missed = (1.0 - s.spp as f64 * p).max(0.0).powi(cam.height as i32);
                assert!(
                    (mean - want).abs() < 1e-6 * l0 || all_missed > 1e-3,
                    "{estimator:?} column {x}: {mean} vs {want}"
                );
            } else {
                worst = worst.max((mean - want).abs() / se);
            }
        }
        eprintln!("{estimator:?}: worst column {worst:.2} standard errors from the analytic edge");
        // Student t with 31 degrees of freedom over 64 columns.
        assert!(
            worst < 5.5,
            "{estimator:?}: a column is {worst:.1} standard errors off"
        );
    }
}
