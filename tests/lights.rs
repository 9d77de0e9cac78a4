//! Lights: sampled irradiance matches closed forms, `pdf_li` is the density of
//! `sample_li`, and nothing arrives from behind an area light.

use crate::common;

use common::{mean_and_stderr, polygon_irradiance};
use ember::geometry::Frame;
use ember::lights::{AreaLight, Light};
use ember::sampling::{uniform_hemisphere, uniform_hemisphere_pdf, uniform_sphere, Rng};
use ember::{Color, Vec3};
use std::f64::consts::PI;

/// The Cornell-box light: 0.6 × 0.8 at height 1.49, facing down, L = 10.
fn cornell_light() -> Light {
    let (ex, ey) = (Vec3::new(0.6, 0.0, 0.0), Vec3::new(0.0, 0.0, 0.8));
    Light::Area(AreaLight {
        centre: Vec3::new(0.0, 1.49, 0.0),
        ex,
        ey,
        normal: Vec3::NEG_Y,
        radiance: Color::splat(10.0),
    })
}

/// A sheared, tilted parallelogram light (emitting along ex × ey).
fn sheared_light() -> Light {
    let (ex, ey) = (Vec3::new(0.5, 0.1, 0.0), Vec3::new(0.2, 0.05, 0.7));
    Light::Area(AreaLight {
        centre: Vec3::new(0.3, 2.0, -0.2),
        ex,
        ey,
        normal: ex.cross(ey).normalize(),
        radiance: Color::new(1.0, 2.0, 3.0),
    })
}

fn corners(light: &Light) -> [Vec3; 4] {
    let Light::Area(AreaLight { centre, ex, ey, .. }) = *light else {
        panic!("not an area light")
    };
    let (hx, hy) = (0.5 * ex, 0.5 * ey);
    [
        centre - hx - hy,
        centre + hx - hy,
        centre + hx + hy,
        centre - hx + hy,
    ]
}

/// Monte Carlo irradiance from `sample_li`, with its standard error.
fn sampled_irradiance(light: &Light, p: Vec3, n: Vec3, count: usize, seed: u64) -> (f64, f64) {
    let mut s = Rng::from_seed(seed);
    let values: Vec<f64> = (0..count)
        .map(|_| {
            light
                .sample_li(p, s.next_2d())
                .map_or(0.0, |ls| (ls.li.x * n.dot(ls.wi).max(0.0) / ls.pdf) as f64)
        })
        .collect();
    mean_and_stderr(&values)
}

#[test]
fn area_light_irradiance_matches_lambert_formula() {
    let receivers = [
        (Vec3::ZERO, Vec3::Y),
        (Vec3::new(0.5, 0.0, 0.3), Vec3::Y),
        (Vec3::new(-0.9, 0.0, 0.9), Vec3::Y),
        (Vec3::new(0.1, 1.2, -0.1), Vec3::Y),
        (
            Vec3::new(0.9, 0.5, 0.0),
            Vec3::new(-1.0, 1.0, 0.0).normalize(),
        ),
    ];
    for light in [cornell_light(), sheared_light()] {
        let vertices = corners(&light);
        for (k, &(p, n)) in receivers.iter().enumerate() {
            assert!(
                vertices.iter().all(|q| (*q - p).dot(n) > 0.0),
                "light not above receiver {k}"
            );
            let exact = polygon_irradiance(p, n, &vertices, light_radiance_x(&light));
            let (mc, se) = sampled_irradiance(&light, p, n, 100_000, 40 + k as u64);
            // 4 standard errors of the mean (fixed seed), plus f32 rounding.
            assert!(
                (mc - exact).abs() < 4.0 * se + 1e-5 * exact,
                "receiver {k}: MC {mc} ± {se} vs exact {exact}"
            );
        }
    }
}

fn light_radiance_x(light: &Light) -> f64 {
    match *light {
        Light::Area(AreaLight { radiance, .. }) => radiance.x as f64,
        _ => 0.0,
    }
}

#[test]
fn area_light_pdf_li_is_the_sampling_density() {
    let mut s = Rng::from_seed(8);
    for light in [cornell_light(), sheared_light()] {
        for p in [
            Vec3::ZERO,
            Vec3::new(0.7, 0.3, -0.4),
            Vec3::new(0.0, 1.4, 0.0),
        ] {
            for _ in 0..5000 {
                let Some(ls) = light.sample_li(p, s.next_2d()) else {
                    continue;
                };
                assert!(!ls.delta && ls.pdf > 0.0);
                let pdf = light.pdf_li(p, ls.wi);
                assert!((pdf - ls.pdf).abs() <= 1e-3 * ls.pdf, "{pdf} vs {}", ls.pdf);
                let dist = light.intersect_area(p, ls.wi).unwrap();
                assert!((dist - ls.dist).abs() < 1e-4 * ls.dist);
                assert!((p + ls.dist * ls.wi - ls.p_light).length() < 1e-4);
            }
        }
    }
}

/// `∫ pdf_li dω = 1` over the hemisphere facing the light, estimated with
/// uniform directions (4 standard errors): no direction to the light is missed.
#[test]
fn area_light_pdf_li_integrates_to_one() {
    let p = Vec3::new(0.2, 0.5, 0.1);
    let light = cornell_light();
    let frame = Frame::from_normal(Vec3::Y);
    let mut s = Rng::from_seed(12);
    let values: Vec<f64> = (0..400_000)
        .map(|_| {
            let w = frame.to_world(uniform_hemisphere(s.next_2d()));
            (light.pdf_li(p, w) / uniform_hemisphere_pdf()) as f64
        })
        .collect();
    let (mean, se) = mean_and_stderr(&values);
    assert!((mean - 1.0).abs() < 4.0 * se, "∫pdf_li = {mean} ± {se}");
}

#[test]
fn nothing_arrives_from_behind_an_area_light() {
    let light = cornell_light();
    let above = Vec3::new(0.0, 2.0, 0.0);
    let mut s = Rng::from_seed(2);
    for _ in 0..1000 {
        assert!(light.sample_li(above, s.next_2d()).is_none());
    }
    assert_eq!(light.pdf_li(above, Vec3::NEG_Y), 0.0);
    assert_eq!(light.intersect_area(above, Vec3::NEG_Y), None);
    // In the light's plane, or missing it.
    assert!(light
        .sample_li(Vec3::new(2.0, 1.49, 0.0), s.next_2d())
        .is_none());
    assert_eq!(light.pdf_li(Vec3::ZERO, Vec3::X), 0.0);
    assert_eq!(
        light.pdf_li(Vec3::ZERO, Vec3::new(0.5, 0.5, 0.0).normalize()),
        0.0
    );
    assert!(light.pdf_li(Vec3::ZERO, Vec3::Y) > 0.0);
}

#[test]
fn point_light_falls_off_as_inverse_square() {
    let light = Light::Point {
        position: Vec3::new(0.0, 2.0, 0.0),
        intensity: Color::splat(5.0),
    };
    for d in [0.5f32, 1.0, 2.0] {
        let p = Vec3::new(0.0, 2.0 - d, 0.0);
        let ls = light.sample_li(p, Default::default()).unwrap();
        assert!(ls.delta && ls.pdf == 1.0);
        assert!((ls.li.x - 5.0 / (d * d)).abs() < 1e-5 * ls.li.x);
        assert!((ls.wi - Vec3::Y).length() < 1e-6 && (ls.dist - d).abs() < 1e-6);
        assert_eq!(light.pdf_li(p, ls.wi), 0.0);
    }
    assert!(light
        .sample_li(Vec3::new(0.0, 2.0, 0.0), Default::default())
        .is_none());
}

#[test]
fn directional_light_comes_from_minus_direction() {
    let direction = Vec3::new(0.0, -1.0, 1.0).normalize();
    let light = Light::Directional {
        direction,
        irradiance: Color::new(1.0, 2.0, 3.0),
    };
    let ls = light.sample_li(Vec3::ZERO, Default::default()).unwrap();
    assert!((ls.wi + direction).length() < 1e-6);
    assert!(ls.delta && ls.pdf == 1.0 && ls.dist.is_infinite());
    assert_eq!(ls.li, Color::new(1.0, 2.0, 3.0));
    assert_eq!(light.pdf_li(Vec3::ZERO, ls.wi), 0.0);
}

#[test]
fn ambient_light_gives_pi_c_on_an_upward_surface() {
    let c = Color::new(0.5, 1.0, 2.0);
    let light = Light::Ambient { radiance: c };
    let mut s = Rng::from_seed(4);
    let mut values = Vec::new();
    for _ in 0..50_000 {
        let ls = light.sample_li(Vec3::ZERO, s.next_2d()).unwrap();
        assert!(ls.wi.y > 0.0 && ls.dist.is_infinite() && !ls.delta);
        assert!((light.pdf_li(Vec3::ZERO, ls.wi) - ls.pdf).abs() < 1e-5 * ls.pdf);
        values.push((ls.li.z * ls.wi.y / ls.pdf) as f64);
    }
    let (mean, se) = mean_and_stderr(&values);
    assert!(
        (mean - PI * 2.0).abs() < 4.0 * se + 1e-4,
        "E = {mean} ± {se}"
    );
    assert_eq!(light.pdf_li(Vec3::ZERO, Vec3::NEG_Y), 0.0);
    assert_eq!(light.pdf_li(Vec3::ZERO, Vec3::X), 0.0);
}

/// A surface tilted by β sees the sky hemisphere's `π·c·(1 + cos β)/2`
/// (estimated from `le_escaped` with uniform directions, 4 standard errors),
/// and `pdf_li` integrates to 1 over the sphere.
#[test]
fn ambient_light_on_tilted_surface_and_pdf_mass() {
    let light = Light::Ambient {
        radiance: Color::ONE,
    };
    let beta = 1.0f32;
    let n = Vec3::new(beta.sin(), beta.cos(), 0.0);
    let mut s = Rng::from_seed(6);
    let (mut irradiance, mut mass) = (Vec::new(), Vec::new());
    for _ in 0..200_000 {
        let w = uniform_sphere(s.next_2d());
        irradiance.push((light.le_escaped(w).x * n.dot(w).max(0.0)) as f64 * 4.0 * PI);
        mass.push(light.pdf_li(Vec3::ZERO, w) as f64 * 4.0 * PI);
    }
    let (e, se) = mean_and_stderr(&irradiance);
    let exact = PI * (1.0 + (beta as f64).cos()) / 2.0;
    assert!((e - exact).abs() < 4.0 * se, "E = {e} ± {se} vs {exact}");
    let (m, se) = mean_and_stderr(&mass);
    assert!((m - 1.0).abs() < 4.0 * se, "∫pdf_li = {m} ± {se}");
}

#[test]
fn power_is_positive_and_finite() {
    let lights = [
        cornell_light(),
        Light::Point {
            position: Vec3::ZERO,
            intensity: Color::ONE,
        },
        Light::Directional {
            direction: Vec3::NEG_Y,
            irradiance: Color::ONE,
        },
        Light::Ambient {
            radiance: Color::ONE,
        },
    ];
    for l in lights {
        let p = l.power(2.0);
        assert!(p.is_finite() && p > 0.0, "{l:?}: {p}");
    }
    // A Lambertian emitter sends π·L per unit area.
    assert!((cornell_light().power(1.0) - std::f32::consts::PI * 0.48 * 10.0).abs() < 1e-3);
}
