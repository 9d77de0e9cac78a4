//! Three-component vectors (points, directions, colours) of any lane type, with
//! glam's operations in glam's order, so `V3<f32>` computes what `glam::Vec3` does.

use super::real::Real;
use super::simd::LANES;
use super::Lanes;
use glam::Vec3;
use std::ops::{Add, Div, Mul, Neg, Sub};

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct V3<F> {
    pub x: F,
    pub y: F,
    pub z: F,
}

impl<F: Real> V3<F> {
    #[inline(always)]
    pub fn new(x: F, y: F, z: F) -> Self {
        V3 { x, y, z }
    }

    /// `v` in every lane.
    #[inline(always)]
    pub fn splat<L: Lanes<F = F>>(l: L, v: Vec3) -> Self {
        V3::new(l.f(v.x), l.f(v.y), l.f(v.z))
    }

    /// `v` in every lane of `self`'s kind.
    #[inline(always)]
    pub fn splat_as(self, v: Vec3) -> Self {
        V3::new(
            self.x.splat_as(v.x),
            self.x.splat_as(v.y),
            self.x.splat_as(v.z),
        )
    }

    /// `(x·x + y·y) + z·z`, glam's order.
    #[inline(always)]
    pub fn dot(self, o: Self) -> F {
        self.x * o.x + self.y * o.y + self.z * o.z
    }

    /// glam's `cross`, operation for operation.
    #[inline(always)]
    pub fn cross(self, o: Self) -> Self {
        V3::new(
            self.y * o.z - o.y * self.z,
            self.z * o.x - o.z * self.x,
            self.x * o.y - o.x * self.y,
        )
    }

    #[inline(always)]
    pub fn length_squared(self) -> F {
        self.dot(self)
    }

    #[inline(always)]
    pub fn length(self) -> F {
        self.dot(self).sqrt()
    }

    /// glam's `normalize`: `self · (1 / |self|)`.
    #[inline(always)]
    pub fn normalize(self) -> Self {
        let inv = self.x.splat_as(1.0) / self.length_squared().sqrt();
        self * inv
    }

    /// glam's `normalize_or_zero`: zero where `1/|self|` is not finite and positive.
    #[inline(always)]
    pub fn normalize_or_zero(self) -> Self {
        let rcp = self.x.splat_as(1.0) / self.length_squared().sqrt();
        let ok = rcp.is_finite() & rcp.gt(self.x.splat_as(0.0));
        let zero = self.x.splat_as(0.0);
        V3::select(ok, self * rcp, V3::new(zero, zero, zero))
    }

    #[inline(always)]
    pub fn abs(self) -> Self {
        V3::new(self.x.abs(), self.y.abs(), self.z.abs())
    }

    /// The largest component, as glam's `max_element` (`f32::max`: NaN-ignoring).
    #[inline(always)]
    pub fn max_element(self) -> F {
        max_nonnan(max_nonnan(self.x, self.y), self.z)
    }

    /// Lanes whose three components are all zero.
    #[inline(always)]
    pub fn is_zero(self) -> F::M {
        let zero = self.x.splat_as(0.0);
        self.x.eq(zero) & self.y.eq(zero) & self.z.eq(zero)
    }

    /// Lanes whose three components are all finite.
    #[inline(always)]
    pub fn is_finite(self) -> F::M {
        self.x.is_finite() & self.y.is_finite() & self.z.is_finite()
    }

    #[inline(always)]
    pub fn select(m: F::M, a: Self, b: Self) -> Self {
        V3::new(
            F::select(m, a.x, b.x),
            F::select(m, a.y, b.y),
            F::select(m, a.z, b.z),
        )
    }

    #[inline(always)]
    pub fn lane(self, i: usize) -> Vec3 {
        Vec3::new(self.x.lane(i), self.y.lane(i), self.z.lane(i))
    }

    /// Lanes from one array per component.
    #[inline(always)]
    pub fn from_arrays<L: Lanes<F = F>>(l: L, a: &[[f32; LANES]; 3]) -> Self {
        V3::new(l.f_from(a[0]), l.f_from(a[1]), l.f_from(a[2]))
    }

    /// One array per component.
    #[inline(always)]
    pub fn to_arrays(self) -> [[f32; LANES]; 3] {
        [self.x.to_array(), self.y.to_array(), self.z.to_array()]
    }

    /// Lanes from one vector per lane.
    #[inline(always)]
    pub fn from_lanes<L: Lanes<F = F>>(l: L, v: &[Vec3; LANES]) -> Self {
        V3::new(
            l.f_from(v.map(|p| p.x)),
            l.f_from(v.map(|p| p.y)),
            l.f_from(v.map(|p| p.z)),
        )
    }
}

/// `f32::max`: the other operand where one is NaN.
#[inline(always)]
pub fn max_nonnan<F: Real>(a: F, b: F) -> F {
    F::select(b.eq(b), a.max(b), a)
}

/// `f32::clamp` (NaN stays NaN).
#[inline(always)]
pub fn clamp<F: Real>(x: F, lo: F, hi: F) -> F {
    let x = F::select(x.lt(lo), lo, x);
    F::select(x.gt(hi), hi, x)
}

impl V3<f32> {
    #[inline(always)]
    pub fn vec3(self) -> Vec3 {
        Vec3::new(self.x, self.y, self.z)
    }
}

impl From<Vec3> for V3<f32> {
    #[inline(always)]
    fn from(v: Vec3) -> Self {
        V3::new(v.x, v.y, v.z)
    }
}

impl From<V3<f32>> for Vec3 {
    #[inline(always)]
    fn from(v: V3<f32>) -> Self {
        v.vec3()
    }
}

impl<F: Real> Add for V3<F> {
    type Output = Self;
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        V3::new(self.x + o.x, self.y + o.y, self.z + o.z)
    }
}
impl<F: Real> Sub for V3<F> {
    type Output = Self;
    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        V3::new(self.x - o.x, self.y - o.y, self.z - o.z)
    }
}
impl<F: Real> Mul<F> for V3<F> {
    type Output = Self;
    #[inline(always)]
    fn mul(self, k: F) -> Self {
        V3::new(self.x * k, self.y * k, self.z * k)
    }
}
impl<F: Real> Mul for V3<F> {
    type Output = Self;
    #[inline(always)]
    fn mul(self, o: Self) -> Self {
        V3::new(self.x * o.x, self.y * o.y, self.z * o.z)
    }
}
impl<F: Real> Div<F> for V3<F> {
    type Output = Self;
    #[inline(always)]
    fn div(self, k: F) -> Self {
        V3::new(self.x / k, self.y / k, self.z / k)
    }
}
impl<F: Real> Neg for V3<F> {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        V3::new(-self.x, -self.y, -self.z)
    }
}
