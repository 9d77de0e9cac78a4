//! Rays, bounds, primitive intersection and the robust spawning of secondary rays.

pub mod aabb;
pub mod frame;
pub mod ray;
pub mod sphere;
pub mod triangle;

pub use aabb::Aabb;
pub use frame::Frame;
pub use ray::{offset_ray_origin, Ray, NO_PRIM};
