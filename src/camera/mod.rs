//! The camera of spec §4: direction from the file, eye from the bounds (or the file's own
//! camera position, `CameraDesc::placement`), field of view
//! independent of the pixel count; a pinhole unless a thin lens is set (course project
//! 3-2 part 4, README "Thin lens"). `course_file` reads and writes the course's camera
//! settings files (`-c`).

pub mod course_file;

use crate::geometry::{Aabb, Ray};
use crate::lanes::math::sin_cos_turns;
use crate::lanes::{LaneBits, LaneMask, Lanes, One, Real, V3};
use crate::sampling::{SampleStream, LENS_PAIR, PIXEL_PAIR};
use crate::scene::CameraDesc;
use glam::{Vec2, Vec3};

/// The course's focal distance when none is given (its `AppConfig` default).
pub const COURSE_FOCAL_DISTANCE: f32 = 4.7;

/// A thin lens centred on the eye, in the plane spanned by `right` and `up`.
/// Everything at depth `focal_distance` (measured along `forward`) is in focus;
/// radius 0 is the pinhole.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ThinLens {
    pub radius: f32,
    pub focal_distance: f32,
}

impl ThinLens {
    /// No lens; the focal distance is the course's default, kept for `-c` files.
    pub const PINHOLE: ThinLens = ThinLens {
        radius: 0.0,
        focal_distance: COURSE_FOCAL_DISTANCE,
    };

    pub fn is_pinhole(&self) -> bool {
        self.radius == 0.0
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    pub eye: Vec3,
    pub forward: Vec3,
    pub up: Vec3,
    pub right: Vec3,
    /// `tan(hfov/2)` and `tan(vfov/2)` of the output image.
    pub tan_half_x: f32,
    pub tan_half_y: f32,
    pub width: u32,
    pub height: u32,
    pub lens: ThinLens,
}

impl Camera {
    /// Camera for a `width × height` image of a scene with bounds `bounds`.
    pub fn new(desc: &CameraDesc, bounds: &Aabb, width: u32, height: u32) -> Camera {
        let f = desc.forward;
        let u = desc.up;
        let r = f.cross(u);
        let (c, d) = if bounds.is_empty() {
            (Vec3::ZERO, 1.0)
        } else {
            (bounds.centre(), bounds.diagonal().length())
        };
        let eye = match (desc.placement, desc.position) {
            (crate::scene::Placement::File, Some(p)) => p,
            _ => c - 1.5 * d * f,
        };
        let (tx, ty) = output_fov(
            desc.tan_half_x,
            desc.tan_half_y,
            width as f32 / height as f32,
        );
        Camera {
            eye,
            forward: f,
            up: u,
            right: r,
            tan_half_x: tx,
            tan_half_y: ty,
            width,
            height,
            lens: ThinLens::PINHOLE,
        }
    }

    /// Horizontal and vertical field of view in degrees.
    pub fn fov_degrees(&self) -> (f32, f32) {
        (
            2.0 * self.tan_half_x.atan().to_degrees(),
            2.0 * self.tan_half_y.atan().to_degrees(),
        )
    }

    /// Rays through pixels `(x, y)` (column from the left, row from the top, as
    /// floats) at offsets `xi ∈ [0,1)²` in them, and (only with a lens) from lens
    /// points `u_lens ∈ [0,1)²`, per lane: origins and unit directions. A lens ray
    /// passes through the point where the pinhole ray of the same `xi` meets the
    /// focal plane.
    #[inline(always)]
    pub fn rays<L: Lanes>(
        &self,
        l: L,
        (x, y): (L::F, L::F),
        xi: (L::F, L::F),
        u_lens: (L::F, L::F),
    ) -> (V3<L::F>, V3<L::F>) {
        let (one, two) = (l.f(1.0), l.f(2.0));
        let u = (x + xi.0) / l.f(self.width as f32);
        let v = (y + xi.1) / l.f(self.height as f32);
        let sx = (two * u - one) * l.f(self.tan_half_x);
        let sy = (one - two * v) * l.f(self.tan_half_y);
        let (right, up, forward) = (
            V3::splat(l, self.right),
            V3::splat(l, self.up),
            V3::splat(l, self.forward),
        );
        let eye = V3::splat(l, self.eye);
        if self.lens.is_pinhole() {
            return (eye, ((right * sx + up * sy) + forward).normalize());
        }
        let (lx, ly) = self.lens_offset(l, u_lens);
        let fd = l.f(self.lens.focal_distance);
        // Camera space: lens point (lx, ly, 0), focus point (sx·fd, sy·fd, fd along forward).
        let d = (right * (sx * fd - lx) + up * (sy * fd - ly)) + forward * fd;
        ((eye + right * lx) + up * ly, d.normalize())
    }

    /// The camera rays of pixel samples `stream` of pixels `(x, y)`: the offset in the
    /// pixel from pair [`PIXEL_PAIR`], the lens point (only with a lens) from
    /// [`LENS_PAIR`].
    #[inline(always)]
    pub fn sample_rays<L: Lanes>(
        &self,
        l: L,
        pixel: (L::F, L::F),
        stream: &SampleStream<L>,
    ) -> (V3<L::F>, V3<L::F>) {
        let xi = stream.get_2d_at(l, PIXEL_PAIR);
        let u_lens = if self.lens.is_pinhole() {
            (l.f(0.0), l.f(0.0))
        } else {
            stream.get_2d_at(l, LENS_PAIR)
        };
        self.rays(l, pixel, xi, u_lens)
    }

    /// Ray through pixel `(i, j)` at offset `xi ∈ [0,1)²`, through the pinhole.
    pub fn generate_ray(&self, i: u32, j: u32, xi: Vec2) -> Ray {
        let pinhole = Camera {
            lens: ThinLens::PINHOLE,
            ..*self
        };
        pinhole.generate_lens_ray(i, j, xi, Vec2::ZERO)
    }

    /// Ray through pixel `(i, j)` at offset `xi` from lens point `u ∈ [0,1)²` (`rays`
    /// for one path).
    pub fn generate_lens_ray(&self, i: u32, j: u32, xi: Vec2, u: Vec2) -> Ray {
        let (o, d) = self.rays(One, (i as f32, j as f32), (xi.x, xi.y), (u.x, u.y));
        Ray::new(o.vec3(), d.vec3())
    }

    /// The lens point of `u ∈ [0,1)²` in the lens plane's (right, up) coordinates,
    /// mapped uniformly onto the lens disk as the course does (`r = radius·√u₁`,
    /// `φ = 2π·u₂`).
    #[inline(always)]
    fn lens_offset<L: Lanes>(&self, l: L, u: (L::F, L::F)) -> (L::F, L::F) {
        let r = l.f(self.lens.radius) * u.0.sqrt();
        let (sin, cos) = sin_cos_turns(u.1);
        (r * cos, r * sin)
    }

    /// Pixel `(x, y)` whose centre sees world point `p`, if it is in front of the camera and in the image.
    pub fn project(&self, p: Vec3) -> Option<(u32, u32)> {
        let d = p - self.eye;
        let depth = d.dot(self.forward);
        if depth <= 0.0 {
            return None;
        }
        let sx = d.dot(self.right) / depth / self.tan_half_x;
        let sy = d.dot(self.up) / depth / self.tan_half_y;
        let u = 0.5 * (sx + 1.0) * self.width as f32;
        let v = 0.5 * (1.0 - sy) * self.height as f32;
        (u >= 0.0 && v >= 0.0 && u < self.width as f32 && v < self.height as f32)
            .then_some((u as u32, v as u32))
    }
}

/// [`CameraConnection`]s of a lane type's points: the lanes in `seen` see theirs.
#[derive(Clone, Copy, Debug)]
pub struct LensConnections<F: Real> {
    pub seen: LaneBits,
    pub u: F,
    pub v: F,
    pub origin: V3<F>,
    pub to_eye: V3<F>,
    pub dist: F,
    pub importance: F,
}

/// The pixel that sees a scene point, for estimators that connect to the camera.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraConnection {
    pub x: u32,
    pub y: u32,
    /// Where the connection ends: the eye, or the point on the lens.
    pub origin: Vec3,
    /// Unit direction from the point toward `origin`.
    pub to_eye: Vec3,
    pub dist: f32,
    /// `We·cos θ / d² = 1/(A·cos³θ·d²)` (pbrt-v4 `PerspectiveCamera::SampleWi`),
    /// `A = 4·tan_half_x·tan_half_y` the image plane's area at distance 1; with a lens,
    /// `We = 1/(A·lensArea·cos⁴θ)` over the lens-area pdf `d²/(cos θ·lensArea)` gives the same.
    /// With `N` paths per pixel, a pixel is the sum of its `β·f·|cos|·importance` over `N`.
    pub importance: f32,
}

impl Camera {
    /// Projects `p` onto the image through the lens point of `u_lens` (unused by the
    /// pinhole): `None` behind the lens or outside the frame. The pixel is where the ray
    /// from the lens point through `p` crosses the focal plane, seen from the eye.
    pub fn connect(&self, p: Vec3, u_lens: Vec2) -> Option<CameraConnection> {
        let c = self.connect_l(One, 1, p.into(), || (u_lens.x, u_lens.y));
        let (x, y) = self.pixel_at(c.u, c.v);
        (c.seen != 0).then_some(CameraConnection {
            x,
            y,
            origin: c.origin.vec3(),
            to_eye: c.to_eye.vec3(),
            dist: c.dist,
            importance: c.importance,
        })
    }

    /// [`connect`](Self::connect) for the points `p` of `lanes`: the lanes that see
    /// theirs, and per lane where in the image `(u, v) ∈ [0,1)²` (`pixel_at` turns it
    /// into the pixel), the lens point, the direction to it and the importance.
    /// `u_lens` draws the lens point's numbers, only with a lens.
    #[inline(always)]
    pub fn connect_l<L: Lanes>(
        &self,
        l: L,
        lanes: LaneBits,
        p: V3<L::F>,
        u_lens: impl FnOnce() -> (L::F, L::F),
    ) -> LensConnections<L::F> {
        let (zero, one) = (l.f(0.0), l.f(1.0));
        let pinhole = self.lens.is_pinhole();
        let (right, up, eye) = (
            V3::splat(l, self.right),
            V3::splat(l, self.up),
            V3::splat(l, self.eye),
        );
        let origin = if pinhole {
            eye
        } else {
            let (lx, ly) = self.lens_offset(l, u_lens());
            (eye + right * lx) + up * ly
        };
        let d = p - origin;
        let dist = d.length();
        let w = d / dist;
        let cos = w.dot(V3::splat(l, self.forward));
        // The crossing with the plane at depth 1 (the pinhole) or at the focal distance,
        // scaled to depth 1 (the lens).
        let q = if pinhole {
            w / cos
        } else {
            (origin - eye) / l.f(self.lens.focal_distance) + w / cos
        };
        let half = l.f(0.5);
        let u = half * (q.dot(right) / l.f(self.tan_half_x) + one);
        let v = half * (one - q.dot(up) / l.f(self.tan_half_y));
        let area = l.f(4.0 * self.tan_half_x * self.tan_half_y);
        let importance = one / (area * cos * cos * cos * dist * dist);
        let in_frame = u.ge(zero) & u.lt(one) & v.ge(zero) & v.lt(one);
        let seen = dist.gt(zero) & dist.is_finite() & cos.gt(zero) & in_frame;
        LensConnections {
            seen: (seen & importance.is_finite()).bits() & lanes,
            u,
            v,
            origin,
            to_eye: -w,
            dist,
            importance,
        }
    }

    /// The pixel at image position `(u, v) ∈ [0,1)²`.
    pub fn pixel_at(&self, u: f32, v: f32) -> (u32, u32) {
        let x = ((u * self.width as f32) as u32).min(self.width - 1);
        let y = ((v * self.height as f32) as u32).min(self.height - 1);
        (x, y)
    }
}

/// The smallest field of view with aspect `a` containing the file's (spec §4).
pub fn output_fov(tx0: Option<f32>, ty0: Option<f32>, a: f32) -> (f32, f32) {
    match (tx0, ty0) {
        (Some(tx0), Some(ty0)) => {
            if tx0 / ty0 < a {
                (ty0 * a, ty0)
            } else {
                (tx0, tx0 / a)
            }
        }
        (Some(tx0), None) => (tx0, tx0 / a),
        (None, Some(ty0)) => (ty0 * a, ty0),
        (None, None) => {
            let tx0 = (49.13434f32.to_radians() * 0.5).tan();
            (tx0, tx0 / a)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cornell_fov_at_4_3() {
        let tx0 = (49.13434f32.to_radians() / 2.0).tan();
        let (tx, ty) = output_fov(Some(tx0), Some(tx0 / 1.333333), 480.0 / 360.0);
        assert!((tx - tx0).abs() < 1e-6);
        assert!((ty - 0.34284).abs() < 1e-4, "ty = {ty}");
    }

    #[test]
    fn centre_ray_is_forward() {
        let desc = CameraDesc::default();
        let b = Aabb::new(Vec3::splat(-1.0), Vec3::splat(1.0));
        let cam = Camera::new(&desc, &b, 4, 4);
        let r = cam.generate_ray(2, 2, Vec2::ZERO);
        assert!((r.d - desc.forward).length() < 1e-6);
        // Row 0 is the top: its rays point up.
        assert!(cam.generate_ray(0, 0, Vec2::splat(0.5)).d.dot(desc.up) > 0.0);
    }

    #[test]
    fn connect_inverts_generate_ray() {
        let desc = CameraDesc::default();
        let b = Aabb::new(Vec3::splat(-1.0), Vec3::splat(1.0));
        let cam = Camera::new(&desc, &b, 16, 12);
        for (i, j) in [(0, 0), (15, 11), (7, 3)] {
            let r = cam.generate_ray(i, j, Vec2::new(0.25, 0.75));
            let c = cam.connect(r.o + 3.0 * r.d, Vec2::ZERO).unwrap();
            assert_eq!((c.x, c.y), (i, j));
            assert!((c.dist - 3.0).abs() < 1e-4 && (c.to_eye + r.d).length() < 1e-5);
        }
        assert!(cam.connect(cam.eye - desc.forward, Vec2::ZERO).is_none());
    }

    #[test]
    fn connect_through_the_lens_inverts_generate_lens_ray() {
        let desc = CameraDesc::default();
        let b = Aabb::new(Vec3::splat(-1.0), Vec3::splat(1.0));
        let mut cam = Camera::new(&desc, &b, 16, 12);
        cam.lens = ThinLens {
            radius: 0.4,
            focal_distance: 2.5,
        };
        let mut s = crate::sampling::Rng::from_seed(11);
        for k in 0..200u32 {
            let (i, j) = (k % 16, (k / 16) % 12);
            let (xi, u) = (Vec2::new(0.25, 0.75), s.next_2d());
            let r = cam.generate_lens_ray(i, j, xi, u);
            for t in [1.0, 2.5, 6.0] {
                let c = cam.connect(r.o + t * r.d, u).unwrap();
                assert_eq!((c.x, c.y), (i, j), "t = {t}");
                assert!((c.origin - r.o).length() < 1e-6);
                assert!((c.dist - t).abs() < 1e-4 && (c.to_eye + r.d).length() < 1e-5);
            }
        }
    }

    #[test]
    fn lens_rays_meet_the_pinhole_ray_on_the_focal_plane() {
        let desc = CameraDesc::default();
        let b = Aabb::new(Vec3::splat(-1.0), Vec3::splat(1.0));
        let mut cam = Camera::new(&desc, &b, 64, 48);
        let fd = 3.0;
        cam.lens = ThinLens {
            radius: 0.5,
            focal_distance: fd,
        };
        let on_focal_plane = |r: Ray| {
            let t = (fd - (r.o - cam.eye).dot(cam.forward)) / r.d.dot(cam.forward);
            r.o + t * r.d
        };
        let mut s = crate::sampling::Rng::from_seed(7);
        for k in 0..2000u32 {
            let (i, j) = (k % 64, (k / 64) % 48);
            let (xi, u) = (s.next_2d(), s.next_2d());
            let lens = cam.generate_lens_ray(i, j, xi, u);
            let pin = cam.generate_ray(i, j, xi);
            let (a, b) = (on_focal_plane(lens), on_focal_plane(pin));
            assert!((a - b).length() < 1e-5 * fd, "{a} vs {b}");
            let o = lens.o - cam.eye;
            assert!(o.dot(cam.forward).abs() < 1e-6 && o.length() <= 0.5 + 1e-6);
        }
    }

    #[test]
    fn lens_points_cover_the_disk_uniformly() {
        // Uniform on the disk: the fraction inside radius r/2 is 1/4, and the mean is 0.
        let b = Aabb::new(Vec3::splat(-1.0), Vec3::splat(1.0));
        let mut cam = Camera::new(&CameraDesc::default(), &b, 8, 8);
        cam.lens.radius = 2.0;
        let mut s = crate::sampling::Rng::from_seed(3);
        let n = 40_000;
        let (mut inner, mut sum) = (0u32, Vec3::ZERO);
        for _ in 0..n {
            let o = cam.generate_lens_ray(4, 4, Vec2::splat(0.5), s.next_2d()).o - cam.eye;
            inner += (o.length() < 1.0) as u32;
            sum += o;
        }
        // Binomial(n, 1/4): sd = sqrt(n·3/16) ≈ 86.6. Each coordinate has variance r²/4 = 1,
        // so the mean point's coordinates have sd 1/sqrt(n) = 0.005 and its length < 5·0.005·√2.
        assert!(
            (inner as f64 - n as f64 / 4.0).abs() < 5.0 * 86.6,
            "{inner}"
        );
        assert!(
            (sum / n as f32).length() < 5.0 * 0.005 * 2f32.sqrt(),
            "{sum}"
        );
    }
}
