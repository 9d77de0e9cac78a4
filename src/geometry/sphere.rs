//! Ray-sphere intersection, robust for rays starting inside and for rays spawned
//! from the sphere's own surface.
//!
//! The discriminant is computed from the component of `o − c` perpendicular to
//! the ray (Ray Tracing Gems ch. 7), which does not cancel for distant origins,
//! and the roots use the stable `q`-form. Which roots may count is decided by
//! where the origin is, not by comparing tiny `t` values: the sign of
//! `c = |o − c|² − r²` is only trusted outside its rounding error. Inside that
//! band the origin is taken to be on the surface, whose only hit is the far root
//! `−2b/a`, and only when the ray clearly heads inward. `sphere_spawn_origin` puts a
//! ray leaving the sphere strictly on its side as this test computes it (within an
//! ulp of the surface point), so it never re-hits its own point at `t ≈ 0`.

use super::ray::gamma;
use super::Ray;
use crate::lanes::{F32s, LaneBits, Mask, Simd, Vec3s};
use glam::Vec3;

/// Whether a sphere can ever be hit.
pub fn sphere_is_hittable(centre: Vec3, radius: f32) -> bool {
    centre.is_finite() && radius.is_finite() && radius > 0.0
}

/// Nearest `t ∈ [t_min, t_max]`, `t > 0`, where `ray` meets the sphere's surface.
pub fn intersect_sphere(ray: &Ray, centre: Vec3, radius: f32) -> Option<f32> {
    intersect(ray, centre, radius, false)
}

/// `c = |o − centre|² − r²` as the intersection test computes it (> 0 outside), and the
/// bound on its rounding error within which `o` counts as on the surface.
#[inline(always)]
fn side(o: Vec3, centre: Vec3, radius: f32) -> (f32, f32) {
    let ff = (o - centre).length_squared();
    let r2 = radius * radius;
    // A few operations, taken generously.
    (ff - r2, gamma(8) * (ff + r2))
}

#[inline(always)]
fn intersect(ray: &Ray, centre: Vec3, radius: f32, leaving: bool) -> Option<f32> {
    if !sphere_is_hittable(centre, radius) {
        return None;
    }
    let f = ray.o - centre;
    let d = ray.d;
    let a = d.length_squared();
    let b = f.dot(d);
    let r2 = radius * radius;
    let (c, c_err) = side(ray.o, centre, radius);
    // Bound on the rounding error of b.
    let b_err = gamma(5) * f.abs().dot(d.abs());
    let accept = |t: f32| t > 0.0 && t >= ray.t_min && t <= ray.t_max;
    if c.abs() <= c_err {
        // Origin on the surface: the other root is exactly −2b/a.
        if b < -b_err {
            let t = -2.0 * b / a;
            return accept(t).then_some(t);
        }
        return None;
    }
    let outside = c > 0.0;
    if outside && (leaving || b >= 0.0) {
        // Outside and heading away, both roots behind; or left outward.
        return None;
    }
    let f_perp = f - (b / a) * d;
    let disc = a * (r2 - f_perp.length_squared());
    if disc.is_nan() || disc < 0.0 {
        return None;
    }
    let q = -(b + disc.sqrt().copysign(b));
    let (t0, t1) = (q / a, c / q);
    let (near, far) = if t0 <= t1 { (t0, t1) } else { (t1, t0) };
    if outside && accept(near) {
        return Some(near);
    }
    // From inside only the far root lies ahead.
    accept(far).then_some(far)
}

/// The hit of a ray spawned from this sphere's own surface (the sphere is the
/// ray's `skip`). `sphere_spawn_origin` put its origin strictly on the side the ray
/// heads to: an origin found outside (beyond the rounding of
/// `c`) left outward, and a convex sphere is never met again; otherwise the ray
/// heads inward and [`intersect_sphere`] gives the far side. The plain test cannot
/// tell: far from the world origin a grazing outward ray may clip a sliver of the
/// sphere near its offset origin, a real crossing of the f32 sphere but a self-hit.
pub fn intersect_sphere_leaving(ray: &Ray, centre: Vec3, radius: f32) -> Option<f32> {
    intersect(ray, centre, radius, true)
}

/// [`intersect_sphere`] (or, in lanes `leaving`, [`intersect_sphere_leaving`])
/// for sixteen rays from `o` along `d` with `t_min = 0`, one per lane, operation
/// for operation: the lanes in `active` that hit, and their `t`. The sphere must
/// be hittable.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub fn intersect_sphere_lanes<S: Simd>(
    s: S,
    o: Vec3s<S>,
    d: Vec3s<S>,
    centre: Vec3,
    radius: f32,
    t_max: F32s<S>,
    leaving: Mask<S>,
    active: LaneBits,
) -> (LaneBits, F32s<S>) {
    let f = o - Vec3s::splat(s, centre);
    let a = d.length_squared();
    let b = f.dot(d);
    let r2 = radius * radius;
    let ff = f.length_squared();
    let c = ff - F32s::splat(s, r2);
    let c_err = F32s::splat(s, gamma(8)) * (ff + F32s::splat(s, r2));
    let b_err = F32s::splat(s, gamma(5)) * f.abs().dot(d.abs());
    let zero = F32s::splat(s, 0.0);
    // Origin on the surface: only the far root −2b/a, heading inward.
    let on_surface = c.abs().le(c_err);
    let t_surface = F32s::splat(s, -2.0) * b / a;
    let surface_hit = on_surface & b.lt(-b_err) & t_surface.gt(zero) & t_surface.le(t_max);
    let outside = c.gt(zero);
    let away = outside & (leaving | b.ge(zero));
    let f_perp = f - d * (b / a);
    let disc = a * (F32s::splat(s, r2) - f_perp.length_squared());
    // NaN fails `ge`.
    let real = disc.ge(zero);
    let q = -(b + disc.sqrt().copysign(b));
    let (t0, t1) = (q / a, c / q);
    let ordered = t0.le(t1);
    let near = F32s::select(ordered, t0, t1);
    let far = F32s::select(ordered, t1, t0);
    let take_near = outside & near.gt(zero) & near.le(t_max);
    let t_roots = F32s::select(take_near, near, far);
    let roots_hit = real & !away & (take_near | (far.gt(zero) & far.le(t_max)));
    let t = F32s::select(on_surface, t_surface, t_roots);
    let hit = (on_surface & surface_hit) | (!on_surface & roots_hit);
    (hit.bits() & active, t)
}

/// The origin of a ray leaving the sphere's surface point `p` (outward unit normal
/// `n`) to the outside (`outward`) or into it: `p` itself if the intersection test
/// already finds it strictly on that side, else `p + δ·(±n)` for the first `δ` of
/// half an ulp of `p`'s largest coordinate (or the test's band, if wider), doubled
/// until it is (`None` if that takes more than 16 doublings).
///
/// `offset_ray_origin` moves every origin by the point's error bound, 2–3 ulps of the
/// coordinates once rounded away: 2–3 cm at 1e5, where a ball resting on a floor is
/// that close to it over a disc of ~10 cm, so rays leaving the ball's underside started
/// below the floor (stability case 5). Here the origin is within about an ulp of `p`,
/// on the side the sphere test (`intersect_sphere_leaving`, and Embree's skip filter,
/// which shares its `c` and band) needs: outside the band, nothing of the sphere is
/// ahead of an outward ray; inside it, only the far side of an inward one.
pub fn sphere_spawn_origin(
    p: Vec3,
    n: Vec3,
    outward: bool,
    centre: Vec3,
    radius: f32,
) -> Option<Vec3> {
    let towards = if outward { n } else { -n };
    let on_side = |o: Vec3| {
        let (c, c_err) = side(o, centre, radius);
        if outward {
            c > c_err
        } else {
            c < -c_err
        }
    };
    if on_side(p) {
        return Some(p);
    }
    let band = side(p, centre, radius).1 / (2.0 * radius);
    let mut delta = (gamma(1) * p.abs().max_element()).max(band);
    for _ in 0..16 {
        let o = p + delta * towards;
        if on_side(o) {
            return Some(o);
        }
        delta *= 2.0;
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn outside_inside_and_behind() {
        let c = Vec3::new(1.0, 2.0, 3.0);
        let r = Ray::new(Vec3::new(1.0, 2.0, -7.0), Vec3::Z);
        assert!((intersect_sphere(&r, c, 2.0).unwrap() - 8.0).abs() < 1e-5);
        let inside = Ray::new(c, Vec3::Z * 0.5);
        assert!((intersect_sphere(&inside, c, 2.0).unwrap() - 4.0).abs() < 1e-5);
        let away = Ray::new(Vec3::new(1.0, 2.0, -7.0), -Vec3::Z);
        assert!(intersect_sphere(&away, c, 2.0).is_none());
        let miss = Ray::new(Vec3::new(3.5, 2.0, -7.0), Vec3::Z);
        assert!(intersect_sphere(&miss, c, 2.0).is_none());
        let mut short = r;
        short.t_max = 7.0;
        assert!(intersect_sphere(&short, c, 2.0).is_none());
        short.t_max = 100.0;
        short.t_min = 9.0;
        assert!((intersect_sphere(&short, c, 2.0).unwrap() - 12.0).abs() < 1e-5);
    }

    #[test]
    fn degenerate_input_is_a_miss() {
        let r = Ray::new(Vec3::new(0.0, 0.0, -5.0), Vec3::Z);
        assert!(intersect_sphere(&r, Vec3::ZERO, 0.0).is_none());
        assert!(intersect_sphere(&r, Vec3::ZERO, -1.0).is_none());
        assert!(intersect_sphere(&Ray::new(r.o, Vec3::ZERO), Vec3::ZERO, 1.0).is_none());
    }

    #[test]
    fn distant_origin_keeps_precision() {
        let r = Ray::new(Vec3::new(0.0, 0.0, -1e6), Vec3::Z);
        let t = intersect_sphere(&r, Vec3::ZERO, 1.0).unwrap();
        assert!((t - (1e6 - 1.0)).abs() <= 0.125, "{t}");
        // Grazing ray at distance 0.999 from the centre still hits.
        let g = Ray::new(Vec3::new(0.999, 0.0, -1e4), Vec3::Z);
        assert!(intersect_sphere(&g, Vec3::ZERO, 1.0).is_some());
    }

    /// Rays spawned from the surface (offset as the integrators do) and treated as
    /// leaving it: outward never a hit, inward the far side, even at grazing angles
    /// and far from the origin, where the plain test's on-surface band is too narrow.
    #[test]
    fn rays_leaving_the_surface_reach_only_the_far_side() {
        let mut rng = crate::sampling::Rng::from_seed(3);
        for (centre, radius) in [(Vec3::ZERO, 1.0), (Vec3::splat(1e4), 0.5)] {
            for _ in 0..20000 {
                let n = crate::sampling::uniform_sphere(rng.next_2d());
                let p = centre + radius * n;
                let p_error = gamma(5) * (centre.abs() + Vec3::splat(radius)) + gamma(5) * p.abs();
                let mut w = crate::sampling::uniform_sphere(rng.next_2d());
                if rng.next_f32() < 0.3 {
                    // Grazing: within 1e-3 rad of the tangent plane.
                    w = (w - w.dot(n) * n).normalize() + n * (rng.next_f32() - 0.5) * 2e-3;
                }
                let o = super::super::offset_ray_origin(p, p_error, n, w);
                let t = intersect_sphere_leaving(&Ray::new(o, w), centre, radius);
                let cos = w.normalize().dot(n);
                if cos > 0.0 {
                    assert_eq!(t, None, "outward from {p} along {w}");
                } else if cos < -1e-3 {
                    let chord = 2.0 * radius * -cos / w.length();
                    let t = t.expect("inward ray must reach the far side");
                    // Moving the origin δ along the normal moves the far side by ≤ δ/|cos|.
                    let slack = 1e-3 * radius + (o - p).length() / -cos;
                    assert!((t - chord).abs() <= slack, "{t} vs chord {chord}");
                }
            }
        }
    }

    /// Origins from `sphere_spawn_origin`, as the integrators spawn them, near the
    /// origin and at 1e5 (where an ulp is 8e-3): within four ulps of the rounded surface
    /// point (or of twice the test's band), outward rays never meet their sphere, inward ones
    /// reach its far side.
    #[test]
    fn spawn_origins_are_within_a_few_ulps_and_on_the_rays_side() {
        let mut rng = crate::sampling::Rng::from_seed(5);
        for (centre, radius) in [(Vec3::new(0.3, -0.2, 0.1), 0.4), (Vec3::splat(1e5), 0.35)] {
            let ulp = |v: f32| super::super::ray::next_float_up(v.abs()) - v.abs();
            for _ in 0..20000 {
                let n = crate::sampling::uniform_sphere(rng.next_2d());
                let p = centre + radius * n;
                let mut w = crate::sampling::uniform_sphere(rng.next_2d());
                if rng.next_f32() < 0.3 {
                    w = (w - w.dot(n) * n).normalize() + n * (rng.next_f32() - 0.5) * 2e-3;
                }
                let cos = w.normalize().dot(n);
                let o = sphere_spawn_origin(p, n, cos > 0.0, centre, radius)
                    .expect("a few doublings reach the ray's side");
                let near = 4.0 * ulp(p.abs().max_element()).max(gamma(8) * radius);
                assert!((o - p).length() <= near, "{o} from {p}");
                let t = intersect_sphere_leaving(&Ray::new(o, w), centre, radius);
                if cos > 0.0 {
                    assert_eq!(t, None, "outward from {o} along {w}");
                } else if cos < -1e-3 {
                    // The far root from `o` itself, in f64.
                    let (f, d) = ((o - centre).as_dvec3(), w.as_dvec3());
                    let (a, b, c) = (d.length_squared(), f.dot(d), f.length_squared());
                    let far = (-b + (b * b - a * (c - (radius as f64).powi(2))).sqrt()) / a;
                    let t = t.expect("inward ray must reach the far side");
                    assert!(
                        (t as f64 - far).abs() <= 1e-3 * radius as f64,
                        "{t} vs {far}"
                    );
                }
            }
        }
    }

    /// Points computed on a sphere near the origin (not offset) are within
    /// rounding of its surface on either side; the on-surface band must treat them
    /// as on it: no hit going out, the far side going in. (Far from the origin the
    /// point's own error exceeds the band; there `offset_ray_origin` is needed,
    /// which tests/bvh_brute_force.rs checks.)
    #[test]
    fn rays_from_unoffset_surface_points() {
        let mut rng = crate::sampling::Rng::from_seed(9);
        let dir = |rng: &mut crate::sampling::Rng| crate::sampling::uniform_sphere(rng.next_2d());
        let spheres = [
            (Vec3::ZERO, 1.0),
            (Vec3::new(1.0, -0.5, 0.25), 2.0),
            (Vec3::ZERO, 1e-4),
        ];
        for (centre, radius) in spheres {
            for _ in 0..20000 {
                let n = dir(&mut rng);
                let p = centre + radius * n;
                let w = dir(&mut rng);
                let t = intersect_sphere(&Ray::new(p, w), centre, radius);
                let cos = w.dot(n);
                if cos > 0.0 {
                    assert_eq!(t, None, "outward from {p} along {w}");
                } else if cos < -1e-3 {
                    let chord = 2.0 * radius * -cos;
                    let t = t.expect("inward ray must cross the sphere");
                    assert!((t - chord).abs() <= 1e-3 * radius, "{t} vs chord {chord}");
                }
            }
        }
    }
}
