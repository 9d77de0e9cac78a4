//! The pinhole camera of spec §4: direction from the file, eye from the bounds,
//! field of view independent of the pixel count.

use crate::geometry::{Aabb, Ray};
use crate::scene::CameraDesc;
use glam::{Vec2, Vec3};

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
        let eye = c - 1.5 * d * f;
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
        }
    }

    /// Horizontal and vertical field of view in degrees.
    pub fn fov_degrees(&self) -> (f32, f32) {
        (
            2.0 * self.tan_half_x.atan().to_degrees(),
            2.0 * self.tan_half_y.atan().to_degrees(),
        )
    }

    /// Ray through pixel `(i, j)` (column from the left, row from the top) at offset `xi ∈ [0,1)²`.
    #[inline]
    pub fn generate_ray(&self, i: u32, j: u32, xi: Vec2) -> Ray {
        let u = (i as f32 + xi.x) / self.width as f32;
        let v = (j as f32 + xi.y) / self.height as f32;
        let d = (2.0 * u - 1.0) * self.tan_half_x * self.right
            + (1.0 - 2.0 * v) * self.tan_half_y * self.up
            + self.forward;
        Ray::new(self.eye, d.normalize())
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

/// The pixel that sees a scene point, for estimators that connect to the camera.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraConnection {
    pub x: u32,
    pub y: u32,
    /// Unit direction from the point toward the eye.
    pub to_eye: Vec3,
    pub dist: f32,
    /// `We·cos θ / d² = 1/(A·cos³θ·d²)` (pbrt-v4 `PerspectiveCamera::SampleWi` for a
    /// pinhole), `A = 4·tan_half_x·tan_half_y` the image plane's area at distance 1;
    /// with `N` paths per pixel, a pixel is the sum of its `β·f·|cos|·importance` over `N`.
    pub importance: f32,
}

impl Camera {
    /// Projects `p` onto the image: `None` behind the eye or outside the frame.
    pub fn connect(&self, p: Vec3) -> Option<CameraConnection> {
        let d = p - self.eye;
        let dist = d.length();
        if !(dist > 0.0 && dist.is_finite()) {
            return None;
        }
        let w = d / dist;
        let cos = w.dot(self.forward);
        if cos <= 0.0 {
            return None;
        }
        let q = w / cos;
        let u = 0.5 * (q.dot(self.right) / self.tan_half_x + 1.0);
        let v = 0.5 * (1.0 - q.dot(self.up) / self.tan_half_y);
        if !((0.0..1.0).contains(&u) && (0.0..1.0).contains(&v)) {
            return None;
        }
        let x = ((u * self.width as f32) as u32).min(self.width - 1);
        let y = ((v * self.height as f32) as u32).min(self.height - 1);
        let area = 4.0 * self.tan_half_x * self.tan_half_y;
        let importance = 1.0 / (area * cos * cos * cos * dist * dist);
        importance.is_finite().then_some(CameraConnection {
            x,
            y,
            to_eye: -w,
            dist,
            importance,
        })
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
            let c = cam.connect(r.o + 3.0 * r.d).unwrap();
            assert_eq!((c.x, c.y), (i, j));
            assert!((c.dist - 3.0).abs() < 1e-4 && (c.to_eye + r.d).length() < 1e-5);
        }
        assert!(cam.connect(cam.eye - desc.forward).is_none());
    }
}
