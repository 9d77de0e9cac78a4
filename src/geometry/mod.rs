//! Rays, bounds, primitive intersection and the robust spawning of secondary rays.

pub mod aabb;
pub mod frame;
pub mod ray;
pub mod sphere;
pub mod triangle;

pub use aabb::Aabb;
pub use frame::Frame;
pub use ray::{offset_ray_origin, Ray, NO_PRIM};

/// A primitive id: triangles first, then spheres.
pub type PrimId = u32;

/// The minimal answer of an acceleration structure: enough to rebuild the full
/// surface interaction identically whichever backend found it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PrimHit {
    pub t: f32,
    pub prim: PrimId,
    /// Barycentrics of corners 1 and 2 for triangles (Embree's u, v); unused for spheres.
    pub b1: f32,
    pub b2: f32,
}
