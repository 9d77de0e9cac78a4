//! Rays with a parametric interval, and spawning of rays from surfaces.

use crate::lanes::{Real, UInt, V3};
use glam::Vec3;

/// A ray `o + t·d` restricted to `t ∈ [t_min, t_max]`. `d` need not be unit length
/// (shadow rays use `d = p_light − p` with `t_max < 1`).
///
/// `skip` names the primitive the ray was spawned from (a scene primitive id), or
/// [`NO_PRIM`]. It is how rays leaving a surface avoid re-hitting it, instead of
/// rejecting every hit closer than a rounding bound (which also drops real hits
/// at grazing angles): a flat triangle cannot meet a ray that leaves it, so the
/// triangle `skip` is never hit; a sphere can, but only on its far side, so the
/// sphere `skip` is hit only at the far root of a ray heading inward.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    pub o: Vec3,
    pub d: Vec3,
    pub t_min: f32,
    pub t_max: f32,
    pub skip: u32,
}

/// `Ray::skip` of a ray that left no surface (camera rays, test rays).
pub const NO_PRIM: u32 = u32::MAX;

impl Ray {
    pub fn new(o: Vec3, d: Vec3) -> Self {
        Ray {
            o,
            d,
            t_min: 0.0,
            t_max: f32::INFINITY,
            skip: NO_PRIM,
        }
    }

    pub fn segment(o: Vec3, d: Vec3, t_max: f32) -> Self {
        Ray {
            o,
            d,
            t_min: 0.0,
            t_max,
            skip: NO_PRIM,
        }
    }

    #[inline]
    pub fn at(&self, t: f32) -> Vec3 {
        self.o + t * self.d
    }
}

/// Moves a surface point `p` off its surface, to the side of `w`, far enough that
/// the floating-point error of `p` (`p_error`, a conservative per-axis bound) cannot
/// put the new origin behind the surface (pbrt-v4 `OffsetRayOrigin`). The offset
/// scales with the magnitudes that produced `p`, so scenes at 1e-3 or 1e4 behave alike.
/// Rays leaving a surface should also skip its primitive: spawn them with
/// `SurfaceInteraction::spawn_ray` / `spawn_segment`, which do both.
pub fn offset_ray_origin(p: Vec3, p_error: Vec3, ng: Vec3, w: Vec3) -> Vec3 {
    offset_origin(p.into(), p_error.into(), ng.into(), w.into()).vec3()
}

/// [`offset_ray_origin`] per lane.
#[inline(always)]
pub fn offset_origin<F: Real>(p: V3<F>, p_error: V3<F>, ng: V3<F>, w: V3<F>) -> V3<F> {
    let zero = p.x.splat_as(0.0);
    let d = ng.abs().dot(p_error);
    let offset = ng * d;
    let offset = V3::select(w.dot(ng).lt(zero), -offset, offset);
    let po = p + offset;
    // Round away from p so the offset survives the addition's own rounding.
    V3::new(
        round_away(po.x, offset.x),
        round_away(po.y, offset.y),
        round_away(po.z, offset.z),
    )
}

/// `v` moved one float in the direction of `offset`'s sign (unchanged where it is 0).
#[inline(always)]
fn round_away<F: Real>(v: F, offset: F) -> F {
    let zero = v.splat_as(0.0);
    let up = F::select(offset.gt(zero), next_up(v), v);
    F::select(offset.lt(zero), next_down(v), up)
}

/// Smallest float greater than `v`.
pub fn next_float_up(v: f32) -> f32 {
    next_up(v)
}

/// Largest float smaller than `v`.
pub fn next_float_down(v: f32) -> f32 {
    next_down(v)
}

/// [`next_float_up`] per lane.
#[inline(always)]
pub fn next_up<F: Real>(v: F) -> F {
    let zero = v.splat_as(0.0);
    let v0 = F::select(v.eq(zero), zero, v);
    let bits = v0.to_bits();
    let up = bits.wrapping_add(bits.splat_as(1)).as_f32_bits();
    let down = bits.wrapping_add(bits.splat_as(u32::MAX)).as_f32_bits();
    let r = F::select(v0.ge(zero), up, down);
    F::select(v.eq(v.splat_as(f32::INFINITY)), v, r)
}

/// [`next_float_down`] per lane.
#[inline(always)]
pub fn next_down<F: Real>(v: F) -> F {
    let zero = v.splat_as(0.0);
    let v0 = F::select(v.eq(zero), v.splat_as(-0.0), v);
    let bits = v0.to_bits();
    let up = bits.wrapping_add(bits.splat_as(1)).as_f32_bits();
    let down = bits.wrapping_add(bits.splat_as(u32::MAX)).as_f32_bits();
    let r = F::select(v0.gt(zero), down, up);
    F::select(v.eq(v.splat_as(f32::NEG_INFINITY)), v, r)
}

/// `γ(n) = nε/(1−nε)`, the classic bound on the relative error of `n` float operations.
#[inline]
pub const fn gamma(n: i32) -> f32 {
    let e = f32::EPSILON * 0.5;
    (n as f32 * e) / (1.0 - n as f32 * e)
}
