//! Orthonormal frames: BSDFs work in a local frame whose +z is the shading normal.

use crate::lanes::{Real, V3};
use glam::Vec3;

#[derive(Clone, Copy, Debug)]
pub struct Frame<F = f32> {
    pub s: V3<F>,
    pub t: V3<F>,
    pub n: V3<F>,
}

impl<F: Real> Frame<F> {
    /// Frame around unit `n` (Duff et al. 2017, branchless and continuous almost everywhere).
    #[inline(always)]
    pub fn around(n: V3<F>) -> Self {
        let one = n.z.splat_as(1.0);
        let sign = one.copysign(n.z);
        let a = n.z.splat_as(-1.0) / (sign + n.z);
        let b = n.x * n.y * a;
        let s = V3::new(one + sign * n.x * n.x * a, sign * b, -sign * n.x);
        let t = V3::new(b, sign + n.y * n.y * a, -n.y);
        Frame { s, t, n }
    }

    #[inline(always)]
    pub fn local(&self, v: V3<F>) -> V3<F> {
        V3::new(v.dot(self.s), v.dot(self.t), v.dot(self.n))
    }

    #[inline(always)]
    pub fn world(&self, v: V3<F>) -> V3<F> {
        self.s * v.x + self.t * v.y + self.n * v.z
    }
}

impl Frame {
    /// [`Frame::around`] for one path.
    pub fn from_normal(n: Vec3) -> Self {
        Frame::around(n.into())
    }

    pub fn to_local(&self, v: Vec3) -> Vec3 {
        self.local(v.into()).vec3()
    }

    pub fn to_world(&self, v: Vec3) -> Vec3 {
        self.world(v.into()).vec3()
    }
}
