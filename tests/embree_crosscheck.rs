//! Embree against an f64 brute-force reference and against the native BVH (both
//! builders): hit/miss, primitive id, t within 1e-4 relative, and occlusion.
//!
//! Exact agreement cannot be demanded of two float implementations where rounding
//! decides: a crossing within rounding distance of an edge or vertex, a grazing or
//! tangent ray, an origin on the surface, a t that f32 cannot fix to 1e-4 (close to
//! the origin, at grazing incidence, on slivers), two primitives at the same t, and a
//! contact so close to the origin that the native test finds it only from farther back.
//! Spawned rays name the primitive they leave (`Ray::skip`); both backends skip it.
//! Each case is recognised in f64 from the geometry (`Why`), counted, and its rate
//! bounded; every other disagreement fails the test and is printed with the full ray,
//! float bits included, so it can be replayed. `EMBER_CROSSCHECK_ONLY=<scene>` runs
//! one scene, `EMBER_SHOW_EXCUSED=1` prints excused rays too.

use ember::accel::bvh::Bvh;
use ember::accel::embree::EmbreeAccel;
use ember::accel::{Accel, BvhBuilder, EmbreeQuality};
use ember::bench::meshes;
use ember::camera::Camera;
use ember::geometry::triangle::intersect_triangle;
use ember::geometry::Ray;
use ember::sampling::{uniform_sphere, Rng};
use ember::scene::{PrimHit, Scene};
use glam::{DVec3, Vec3};
use rayon::prelude::*;

/// Rays per scene for the brute-force comparison (its cost is rays × prims).
const BRUTE_FORCE_RAYS: usize = 40_000;

/// Relative tolerance on t.
const T_TOL: f32 = 1e-4;

/// A point within this fraction of the scene's scale of a primitive's boundary is
/// "on" it: 1e-5 is ~100 f32 ulps, generous for the ~10 roundings Embree, the
/// native test and ray generation each add, yet it flags only ~1e-4 of random rays.
const BOUNDARY_REL: f64 = 1e-5;

// ---------------------------------------------------------------- f64 reference

/// Every primitive tested in f64, no acceleration: the referee.
struct BruteForce<'a> {
    scene: &'a Scene,
}

fn dv(v: Vec3) -> DVec3 {
    v.as_dvec3()
}

/// Möller-Trumbore in f64: (t, b1, b2) of the plane crossing, whatever the bounds.
fn tri_f64(o: DVec3, d: DVec3, p: [DVec3; 3]) -> Option<(f64, f64, f64)> {
    let (e1, e2) = (p[1] - p[0], p[2] - p[0]);
    let pv = d.cross(e2);
    let det = e1.dot(pv);
    if det == 0.0 {
        return None;
    }
    let s = o - p[0];
    let b1 = s.dot(pv) / det;
    let q = s.cross(e1);
    let b2 = d.dot(q) / det;
    Some((e2.dot(q) / det, b1, b2))
}

/// Both roots of the sphere quadratic in f64, nearest first.
fn sphere_f64(o: DVec3, d: DVec3, c: DVec3, r: f64) -> Option<(f64, f64)> {
    let oc = o - c;
    let a = d.length_squared();
    let b = oc.dot(d);
    // Discriminant from the perpendicular distance, stable for distant origins.
    let perp = oc - (b / a) * d;
    let disc = r * r - perp.length_squared();
    if disc < 0.0 {
        return None;
    }
    let h = (a * disc).sqrt();
    Some(((-b - h) / a, (-b + h) / a))
}

impl BruteForce<'_> {
    fn hit_prim(&self, ray: &Ray, prim: usize) -> Option<PrimHit> {
        let (o, d) = (dv(ray.o), dv(ray.d));
        let (tmin, tmax) = (ray.t_min as f64, ray.t_max as f64);
        let ntri = self.scene.triangles.len();
        // A ray spawned from a primitive never meets that triangle again, and meets
        // that sphere only at its far side, when it left inward (`Ray::skip`).
        let from_here = prim as u32 == ray.skip;
        if prim < ntri {
            if from_here {
                return None;
            }
            let p = self.scene.triangle_positions(prim).map(dv);
            let (t, b1, b2) = tri_f64(o, d, p)?;
            let inside = b1 >= 0.0 && b2 >= 0.0 && b1 + b2 <= 1.0;
            (inside && t >= tmin && t <= tmax).then_some(PrimHit {
                t: t as f32,
                prim: prim as u32,
                b1: b1 as f32,
                b2: b2 as f32,
            })
        } else {
            let s = &self.scene.spheres[prim - ntri];
            let (t0, t1) = sphere_f64(o, d, dv(s.centre), s.radius as f64)?;
            // The spawn offset put the origin on the side the ray heads to.
            let r = s.radius as f64;
            let left_outward = (o - dv(s.centre)).length_squared() > r * r;
            let roots = match (from_here, left_outward) {
                (false, _) => vec![t0, t1],
                (true, false) => vec![t1],
                (true, true) => vec![],
            };
            let t = roots.into_iter().find(|&t| t >= tmin && t <= tmax)?;
            Some(PrimHit {
                t: t as f32,
                prim: prim as u32,
                b1: 0.0,
                b2: 0.0,
            })
        }
    }
}

impl Accel for BruteForce<'_> {
    fn intersect(&self, ray: &Ray) -> Option<PrimHit> {
        (0..self.scene.num_prims())
            .filter_map(|p| self.hit_prim(ray, p))
            .min_by(|a, b| a.t.total_cmp(&b.t))
    }
    fn occluded(&self, ray: &Ray) -> bool {
        (0..self.scene.num_prims()).any(|p| self.hit_prim(ray, p).is_some())
    }
    fn name(&self) -> String {
        "f64 brute force".into()
    }
    fn memory_bytes(&self) -> usize {
        0
    }
}

// ---------------------------------------------------------------- judging

/// Length scale of rounding errors for `ray` in `scene`: the largest coordinate
/// magnitude among the scene, the origin and the point at `t`.
fn scale(scene: &Scene, ray: &Ray, t: f64) -> f64 {
    let b = scene.bounds;
    let m = b.min.abs().max(b.max.abs()).max_element() as f64;
    let o = dv(ray.o).abs().max_element();
    let p = (dv(ray.o) + t * dv(ray.d)).abs().max_element();
    m.max(o).max(p)
}

/// Why two correct float implementations may disagree about a ray and a primitive.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Why {
    /// Crossing within rounding distance of an edge or vertex.
    Edge,
    /// Ray within rounding of the triangle's plane, or tangent to the sphere.
    Grazing,
    /// Crossing within rounding distance of the ray's origin (`t_min`): the origin is on
    /// the surface, e.g. a bounce ray whose offset is below Embree's rounding (Embree
    /// then re-hits the surface it leaves at t ≈ 1e-9).
    AtOrigin,
    /// Crossing within rounding distance of the segment's end (`t_max`).
    AtEnd,
    /// Different primitives at the same t (shared edge or vertex, coplanar overlap).
    Tie,
    /// Same primitive, t more than 1e-4 apart relatively, but the two crossings are
    /// within `CLOSE_RANGE_ABS` × scale of each other measured along the normal. The
    /// surface's position is known to ~ulps of the scale; t inherits that divided by
    /// the crossing distance and by |cos θ|, so near the origin or at grazing
    /// incidence no f32 code can meet 1e-4 relative.
    IllConditionedT,
    /// The native test missed a triangle very close to the origin that it finds from
    /// an origin backed off along the ray. It once rejected hits within its error bound
    /// δt (pbrt-v4's rule against re-hitting the surface a ray leaves; δt reached 1e-3
    /// on keenan/building's slivers, ~100 such rays per 1M). Spawned rays now skip
    /// their primitive instead; what remains (1 per 1M on keenan/building) is rounding
    /// of the shear for an origin nearly in a sliver's plane.
    NativeErrorBound,
}

const WHYS: [Why; 7] = [
    Why::Edge,
    Why::Grazing,
    Why::AtOrigin,
    Why::AtEnd,
    Why::Tie,
    Why::IllConditionedT,
    Why::NativeErrorBound,
];

/// 1e-6 of the scale is ~16 ulps of its largest coordinate.
const CLOSE_RANGE_ABS: f64 = 1e-6;

/// Whether `prim` meets `ray` (or just misses it) so close to one of its boundaries
/// that float rounding decides, and which boundary.
fn boundary(scene: &Scene, ray: &Ray, prim: u32) -> Option<Why> {
    let (o, d) = (dv(ray.o), dv(ray.d));
    let dlen = d.length();
    let ntri = scene.triangles.len();
    let prim = prim as usize;
    let at_limit = |t: f64, tol: f64| {
        if (t - ray.t_min as f64).abs() * dlen <= tol {
            Some(Why::AtOrigin)
        } else if ray.t_max.is_finite() && (t - ray.t_max as f64).abs() * dlen <= tol {
            Some(Why::AtEnd)
        } else {
            None
        }
    };
    if prim < ntri {
        let p = scene.triangle_positions(prim).map(dv);
        let n = (p[1] - p[0]).cross(p[2] - p[0]);
        let nlen = n.length();
        let Some((t, b1, b2)) = tri_f64(o, d, p) else {
            return Some(Why::Grazing);
        };
        let kappa = condition(p);
        let tol = BOUNDARY_REL * kappa * scale(scene, ray, t);
        if n.dot(d).abs() <= BOUNDARY_REL * kappa * nlen * dlen {
            return Some(Why::Grazing);
        }
        // Distance from the crossing to each edge line is b_i times the opposite altitude.
        let b = [1.0 - b1 - b2, b1, b2];
        let edge_dist = (0..3)
            .map(|i| {
                let e = p[(i + 2) % 3] - p[(i + 1) % 3];
                b[i].abs() * nlen / e.length().max(f64::MIN_POSITIVE)
            })
            .fold(f64::INFINITY, f64::min);
        if edge_dist <= tol {
            return Some(Why::Edge);
        }
        at_limit(t, tol)
    } else {
        let s = &scene.spheres[prim - ntri];
        let (c, r) = (dv(s.centre), s.radius as f64);
        let oc = o - c;
        let perp = (oc - (oc.dot(d) / (dlen * dlen)) * d).length();
        let tol = BOUNDARY_REL * scale(scene, ray, oc.length() / dlen + r);
        if (perp - r).abs() <= tol {
            return Some(Why::Grazing);
        }
        if (oc.length() - r).abs() <= tol {
            return Some(Why::AtOrigin);
        }
        let (t0, t1) = sphere_f64(o, d, c, r)?;
        at_limit(t0, tol).or_else(|| at_limit(t1, tol))
    }
}

/// Whether the native triangle test rejects `prim` on `ray` only for being within its
/// error bound δt of the origin: it misses from the origin, yet hits from an origin
/// backed off along the ray by a quarter of the scene. A ray meets a plane once, so
/// that later hit is the same crossing; it must also be close (δt is a rounding bound,
/// it never reaches 1% of the scene) and inside the ray's interval.
fn native_error_bound_rejects(scene: &Scene, ray: &Ray, prim: u32) -> bool {
    let Some(&tri) = scene.triangles.get(prim as usize) else {
        return false;
    };
    let [p0, p1, p2] = tri.v.map(|k| scene.positions[k as usize]);
    let Some((t_exact, _, _)) = tri_f64(dv(ray.o), dv(ray.d), [p0, p1, p2].map(dv)) else {
        return false;
    };
    let diag = scene.bounds.diagonal().length().max(1e-3);
    let dist = t_exact * dv(ray.d).length();
    let in_interval = t_exact >= ray.t_min as f64 && t_exact <= ray.t_max as f64;
    if !in_interval || dist > 0.01 * diag as f64 || intersect_triangle(ray, p0, p1, p2).is_some() {
        return false;
    }
    let back = 0.25 * diag / ray.d.length();
    let moved = Ray {
        o: ray.o - back * ray.d,
        t_min: 0.0,
        t_max: ray.t_max + back,
        ..*ray
    };
    intersect_triangle(&moved, p0, p1, p2).is_some()
}

/// Condition number of a triangle, longest edge over smallest height (≥ 2/√3): the
/// f32 corners fix its plane's tilt only to ~ε·κ and its position to ~ε·κ·scale,
/// so every tolerance on a triangle scales with it. Slivers (keenan/building has
/// aspect ratios of 5000) get correspondingly wide, but still rounding-sized, bands.
fn condition(p: [DVec3; 3]) -> f64 {
    let twice_area = (p[1] - p[0]).cross(p[2] - p[0]).length();
    let longest = [p[1] - p[0], p[2] - p[1], p[0] - p[2]]
        .iter()
        .map(|e| e.length_squared())
        .fold(0.0, f64::max);
    if twice_area > 0.0 {
        longest / twice_area
    } else {
        f64::INFINITY
    }
}

/// |cos| of the angle between `ray` and the surface normal of `prim` where it crosses.
fn incidence_cos(scene: &Scene, ray: &Ray, prim: u32, t: f32) -> f64 {
    let d = dv(ray.d).normalize();
    let ntri = scene.triangles.len();
    let n = if (prim as usize) < ntri {
        let p = scene.triangle_positions(prim as usize).map(dv);
        (p[1] - p[0]).cross(p[2] - p[0]).normalize()
    } else {
        let s = &scene.spheres[prim as usize - ntri];
        (dv(ray.at(t)) - dv(s.centre)).normalize()
    };
    n.dot(d).abs()
}

fn t_close(a: f32, b: f32) -> bool {
    (a - b).abs() <= T_TOL * a.abs().max(b.abs())
}

/// `Ok(())` when the nearest hits agree; `Ok(Some(why))` for an excused difference;
/// `Err(())` for a real one.
fn judge(
    scene: &Scene,
    ray: &Ray,
    a: Option<PrimHit>,
    b: Option<PrimHit>,
) -> Result<Option<Why>, ()> {
    let excuse = |h: PrimHit| {
        // The probe names a specific mechanism, so it is asked first.
        (native_error_bound_rejects(scene, ray, h.prim).then_some(Why::NativeErrorBound))
            .or_else(|| boundary(scene, ray, h.prim))
            .map(Some)
            .ok_or(())
    };
    match (a, b) {
        (None, None) => Ok(None),
        (Some(x), Some(y)) if x.prim == y.prim && t_close(x.t, y.t) => Ok(None),
        (Some(x), Some(y)) if x.prim == y.prim => {
            // Rounding moves the surface by ~ulps of the scale along its normal, which
            // moves t by that over |cos θ|: compare in that direction.
            let along_normal = (x.t - y.t).abs() as f64
                * dv(ray.d).length()
                * incidence_cos(scene, ray, x.prim, x.t);
            let kappa = match scene.triangles.get(x.prim as usize) {
                Some(_) => condition(scene.triangle_positions(x.prim as usize).map(dv)),
                None => 1.0,
            };
            if along_normal <= CLOSE_RANGE_ABS * kappa * scale(scene, ray, x.t as f64) {
                Ok(Some(Why::IllConditionedT))
            } else {
                excuse(x)
            }
        }
        (Some(x), Some(y)) if t_close(x.t, y.t) => Ok(Some(Why::Tie)),
        // The side that went further missed the nearer primitive.
        (Some(x), Some(y)) => excuse(if x.t < y.t { x } else { y }),
        (Some(x), None) | (None, Some(x)) => excuse(x),
    }
}

/// Occlusion answers differ. Excused only by the boundary of a primitive the segment
/// meets: one of the nearest hits, or any primitive (f64, bounds-filtered) at its
/// boundary, since an any-hit query may stop at a primitive the nearest-hit query
/// never reports.
fn judge_occluded(scene: &Scene, ray: &Ray, hits: [Option<PrimHit>; 2]) -> Result<Why, ()> {
    let mut prims = hits.iter().flatten().map(|h| h.prim).collect::<Vec<_>>();
    prims.extend((0..scene.num_prims() as u32).filter(|&p| ray_meets_bounds(scene, ray, p)));
    prims
        .into_iter()
        .find_map(|p| boundary(scene, ray, p))
        .ok_or(())
}

fn ray_meets_bounds(scene: &Scene, ray: &Ray, prim: u32) -> bool {
    let b = scene.prim_bounds(prim);
    let pad = Vec3::splat(BOUNDARY_REL as f32 * 4.0 * b.diagonal().max_element().max(1.0));
    let (lo, hi) = (b.min - pad, b.max + pad);
    let inv = ray.d.recip();
    let (t0, t1) = ((lo - ray.o) * inv, (hi - ray.o) * inv);
    let tn = t0.min(t1).max_element().max(ray.t_min);
    let tf = t0.max(t1).min_element().min(ray.t_max);
    tn <= tf * 1.0001
}

// ---------------------------------------------------------------- tallying

#[derive(Default)]
struct Tally {
    rays: usize,
    /// Excused differences by `Why` (index into `WHYS`), intersect and occluded together.
    excused: [usize; 7],
    mismatches: usize,
    examples: Vec<String>,
}

impl Tally {
    fn merge(mut self, o: Tally) -> Tally {
        self.rays += o.rays;
        for (a, b) in self.excused.iter_mut().zip(o.excused) {
            *a += b;
        }
        self.mismatches += o.mismatches;
        self.examples.extend(o.examples);
        self.examples.truncate(12);
        self
    }

    fn count(&mut self, why: Why) {
        self.excused[WHYS.iter().position(|&w| w == why).expect("listed")] += 1;
    }

    fn excused_total(&self) -> usize {
        self.excused.iter().sum()
    }

    fn summary(&self) -> String {
        let parts: Vec<String> = WHYS
            .iter()
            .zip(self.excused)
            .map(|(w, n)| format!("{w:?} {n}"))
            .collect();
        format!(
            "{} rays, {} mismatches, excused: {}",
            self.rays,
            self.mismatches,
            parts.join(", ")
        )
    }
}

fn bits(v: Vec3) -> String {
    format!(
        "[{:#010x}, {:#010x}, {:#010x}]",
        v.x.to_bits(),
        v.y.to_bits(),
        v.z.to_bits()
    )
}

fn describe(ray: &Ray, what: &str, a: &dyn std::fmt::Debug, b: &dyn std::fmt::Debug) -> String {
    format!(
        "{what}: Ray {{ o: {:?}, d: {:?}, t_min: {:e}, t_max: {:e} }} (bits o {} d {} t_min {:#010x} t_max {:#010x}): {a:?} vs {b:?}",
        ray.o,
        ray.d,
        ray.t_min,
        ray.t_max,
        bits(ray.o),
        bits(ray.d),
        ray.t_min.to_bits(),
        ray.t_max.to_bits()
    )
}

fn show_excused() -> bool {
    std::env::var_os("EMBER_SHOW_EXCUSED").is_some()
}

fn compare_ray(scene: &Scene, ray: &Ray, a: &dyn Accel, b: &dyn Accel) -> Tally {
    let mut t = Tally {
        rays: 1,
        ..Tally::default()
    };
    let (ha, hb) = (a.intersect(ray), b.intersect(ray));
    let verdict = judge(scene, ray, ha, hb);
    match verdict {
        Ok(None) => {}
        Ok(Some(why)) => {
            t.count(why);
            if show_excused() {
                t.examples
                    .push(describe(ray, &format!("{why:?}"), &ha, &hb));
            }
        }
        Err(()) => {
            t.mismatches += 1;
            t.examples.push(describe(ray, "intersect", &ha, &hb));
        }
    }
    let (oa, ob) = (a.occluded(ray), b.occluded(ray));
    if oa != ob {
        match verdict {
            // Already counted under the same cause.
            Ok(Some(_)) | Err(()) => {}
            Ok(None) => match judge_occluded(scene, ray, [ha, hb]) {
                Ok(why) => t.count(why),
                Err(()) => {
                    t.mismatches += 1;
                    t.examples
                        .push(describe(ray, "occluded", &(oa, ha), &(ob, hb)));
                }
            },
        }
    }
    t
}

// ---------------------------------------------------------------- rays

fn point_in(scene: &Scene, rng: &mut Rng) -> Vec3 {
    let u = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
    scene.bounds.min + u * scene.bounds.diagonal()
}

/// Ray `i` of the mix: camera rays, random rays inside and outside the bounds (some
/// with non-unit directions), and bounce rays and shadow segments spawned with
/// `SurfaceInteraction::spawn_ray`/`spawn_segment` (offset origin, the primitive
/// left as `skip`) from where `spawn_from` hits a primary ray.
fn make_ray(scene: &Scene, cam: &Camera, spawn_from: &dyn Accel, seed: u64, i: usize) -> Ray {
    let mut rng = Rng::new(seed, i as u64, 0);
    let centre = scene.bounds.centre();
    let diag = scene.bounds.diagonal().length().max(1e-3);
    let primary = |rng: &mut Rng, kind: usize| match kind {
        0 => {
            let (px, py) = (rng.next_f32(), rng.next_f32());
            let (x, y) = (
                (px * cam.width as f32) as u32,
                (py * cam.height as f32) as u32,
            );
            cam.generate_ray(x.min(cam.width - 1), y.min(cam.height - 1), rng.next_2d())
        }
        1 => Ray::new(point_in(scene, rng), uniform_sphere(rng.next_2d())),
        _ => {
            let o = centre + 1.5 * diag * uniform_sphere(rng.next_2d());
            let scale = 0.25 + 4.0 * rng.next_f32();
            Ray::new(o, (point_in(scene, rng) - o).normalize() * scale)
        }
    };
    let kind = i % 5;
    if kind < 3 {
        return primary(&mut rng, kind);
    }
    let first_kind = (rng.next_f32() * 3.0) as usize;
    let first = primary(&mut rng, first_kind.min(2));
    let Some(hit) = spawn_from.intersect(&first) else {
        return first;
    };
    let si = scene.interaction(&first, &hit);
    if kind == 3 {
        si.spawn_ray(uniform_sphere(rng.next_2d()))
    } else {
        si.spawn_segment(point_in(scene, &mut rng), 1.0)
    }
}

fn crosscheck(label: &str, scene: &Scene, rays: usize, a: &dyn Accel, b: &dyn Accel) -> Tally {
    let cam = Camera::new(&scene.camera, &scene.bounds, 640, 480);
    let tally = (0..rays)
        .into_par_iter()
        .map(|i| {
            let ray = make_ray(scene, &cam, a, 0x5eed, i);
            compare_ray(scene, &ray, a, b)
        })
        .reduce(Tally::default, Tally::merge);
    eprintln!("{label}: {} vs {}: {}", a.name(), b.name(), tally.summary());
    for e in &tally.examples {
        eprintln!("  {e}");
    }
    tally
}

fn generated_small() -> Vec<(&'static str, Scene)> {
    vec![
        ("grid 24x24", meshes::shared_edge_grid(24)),
        ("degenerate soup", meshes::degenerate_soup(600, 3)),
        ("sphere cluster", meshes::sphere_cluster(120, 5)),
        ("displaced sphere 2k", meshes::displaced_sphere(2000)),
    ]
}

#[test]
fn embree_matches_f64_brute_force_on_generated_meshes() {
    let mut total = Tally::default();
    for (label, scene) in generated_small() {
        let embree = EmbreeAccel::build(&scene, EmbreeQuality::Medium).expect("Embree builds");
        let brute = BruteForce { scene: &scene };
        let t = crosscheck(label, &scene, BRUTE_FORCE_RAYS, &brute, &embree);
        assert_eq!(t.mismatches, 0, "{label}: see the rays above");
        total = total.merge(t);
    }
    let rate = total.excused_total() as f64 / total.rays as f64;
    assert!(rate < MAX_EXCUSED_RATE, "boundary cases at rate {rate}");
}

// ---------------------------------------------------------------- native BVH

/// Bound on the rate of excused differences: ~1.5× the worst scene observed (5.6e-4,
/// the sphere cluster and keenan/building), so a change that makes boundary cases
/// common fails.
const MAX_EXCUSED_RATE: f64 = 8.5e-4;

/// Rays per scene against the native BVH.
const NATIVE_RAYS: usize = 1_000_000;

/// Embree against both native builders over one ray set: Embree traces each ray once.
fn crosscheck_native(label: &str, scene: &Scene) -> Tally {
    let embree = EmbreeAccel::build(scene, EmbreeQuality::Medium).expect("Embree builds");
    let natives = [BvhBuilder::Midpoint, BvhBuilder::Sah].map(|b| Bvh::build(scene, b));
    let cam = Camera::new(&scene.camera, &scene.bounds, 640, 480);
    let tallies = (0..NATIVE_RAYS)
        .into_par_iter()
        .map(|i| {
            let ray = make_ray(scene, &cam, &natives[1], 0xc0ffee, i);
            let tally = |native: &Bvh| compare_ray(scene, &ray, &embree, native);
            [tally(&natives[0]), tally(&natives[1])]
        })
        .reduce(
            || [Tally::default(), Tally::default()],
            |[a0, a1], [b0, b1]| [a0.merge(b0), a1.merge(b1)],
        );
    for (native, tally) in natives.iter().zip(&tallies) {
        eprintln!("{label}: Embree vs {}: {}", native.name(), tally.summary());
        for e in &tally.examples {
            eprintln!("  {e}");
        }
    }
    let [a, b] = tallies;
    a.merge(b)
}

fn course_scenes() -> Vec<std::path::PathBuf> {
    let root = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/cs184");
    let mut files: Vec<_> = ["sky", "meshedit", "keenan"]
        .iter()
        .flat_map(|dir| std::fs::read_dir(format!("{root}/{dir}")).expect("cs184 scenes present"))
        .map(|e| e.expect("readable dir entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "dae"))
        .collect();
    files.sort();
    files
}

/// Every course scene and larger generated meshes, 1M rays each, against both native
/// builders. No unexplained difference is allowed; excused ones must stay below
/// `MAX_EXCUSED_RATE` per comparison in every scene. Observed per 1M rays and builder
/// (Embree 3.13.5), nearly all ill-conditioned t of close contacts: meshes and Cornell
/// boxes 6-29, Cornell boxes with spheres 99, the degenerate soup 105, the sphere
/// cluster 559 (Embree's sphere test is itself 8e-4 off the f64 reference there),
/// keenan/building 557 (slivers of aspect 5000, whose f32 planes are uncertain by κ·ε;
/// 660 while the native test still rejected hits within δt).
#[test]
fn embree_matches_native_bvh_on_course_and_generated_scenes() {
    let mut scenes: Vec<(String, Scene)> = course_scenes()
        .into_iter()
        .map(|p| {
            let scene = ember::scene::collada::load(&p).expect("course scene loads");
            (p.file_stem().unwrap().to_string_lossy().into_owned(), scene)
        })
        .collect();
    scenes.extend([
        ("grid 200x200".to_string(), meshes::shared_edge_grid(200)),
        (
            "degenerate soup 20k".to_string(),
            meshes::degenerate_soup(20_000, 11),
        ),
        (
            "sphere cluster 400".to_string(),
            meshes::sphere_cluster(400, 13),
        ),
        (
            "displaced sphere 100k".to_string(),
            meshes::displaced_sphere(100_000),
        ),
    ]);
    assert!(
        scenes.len() >= 20,
        "expected the course scenes, found {}",
        scenes.len()
    );
    // EMBER_CROSSCHECK_ONLY=substring replays one scene when chasing a report.
    if let Ok(only) = std::env::var("EMBER_CROSSCHECK_ONLY") {
        scenes.retain(|(label, _)| label.contains(&only));
    }
    let mut failures = Vec::new();
    for (label, scene) in &scenes {
        let t = crosscheck_native(label, scene);
        let rate = t.excused_total() as f64 / t.rays as f64;
        if t.mismatches > 0 || rate >= MAX_EXCUSED_RATE {
            failures.push(format!("{label}: {}", t.summary()));
        }
    }
    assert!(
        failures.is_empty(),
        "disagreements (rays printed above):\n{}",
        failures.join("\n")
    );
}

/// Camera rays of every course scene, traced by `rtcIntersect4/8/16` packets over
/// compact pixel tiles, hit what single rays hit: triangles bit for bit, spheres the
/// same sphere at a t within 1e-6 (Embree's packet sphere kernels round differently).
#[test]
fn camera_packets_hit_what_single_rays_hit_on_course_scenes() {
    use ember::accel::embree::PacketWidth;
    use ember::bench::embree_modes::tiled_camera_rays;
    for path in course_scenes() {
        let scene = ember::scene::collada::load(&path).expect("course scene loads");
        let embree = EmbreeAccel::build(&scene, EmbreeQuality::Medium).expect("Embree builds");
        let rays = tiled_camera_rays(&scene, 160, 120);
        let single: Vec<_> = rays.iter().map(|r| embree.intersect(r)).collect();
        let ntri = scene.triangles.len() as u32;
        for width in PacketWidth::ALL {
            let mut packed = vec![None; rays.len()];
            embree.intersect_packets(width, &rays, &mut packed);
            let differ = (0..rays.len())
                .filter(|&i| match (packed[i], single[i]) {
                    (Some(p), Some(s)) if p.prim >= ntri => {
                        p.prim != s.prim || (p.t - s.t).abs() > 1e-6 * s.t
                    }
                    (p, s) => p != s,
                })
                .map(|i| describe(&rays[i], "packet vs single", &packed[i], &single[i]))
                .collect::<Vec<_>>();
            assert!(
                differ.is_empty(),
                "{} {width:?}: {} of {} rays differ, e.g. {}",
                path.display(),
                differ.len(),
                rays.len(),
                differ[0]
            );
        }
    }
}
